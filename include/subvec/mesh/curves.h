// Uniform cubic B-spline curves: the feature curves of the limit surface and the stroke paths.
//
// Paper §3.2: a chain of crease or tear edges through crease or tear vertices subdivides with the
// masks 1/8-6/8-1/8 (vertex) and 1/2-1/2 (edge), whose limit is the uniform cubic B-spline of the
// chain; corner vertices do not move. A chain between two corners is therefore the *clamped*
// B-spline of its vertices: the spline of P0..Pn extended by the phantom points 2 P0 - P1 and
// 2 Pn - Pn-1, which starts exactly at P0 and ends exactly at Pn (with the phantom, the corner rule
// and the B-spline rule agree at every level). A chain with no corner that closes on itself is the
// periodic B-spline. Strokes (mesh/vector_image.h) use the clamped form, so a stroke whose points
// are a feature chain between corners follows the rendered feature curve exactly.
#pragma once

#include <span>
#include <vector>

#include "subvec/mesh/vector_image.h"

namespace subvec {

// Points of the curve, `per_span` (>= 1) segments per span. Open (clamped): #points - 1 spans,
// from points.front() to points.back() inclusive; closed (periodic): #points spans, the first
// sample repeated at the end. Needs at least 2 points (3 when closed); fewer give the points.
std::vector<Vec2> sample_bspline(std::span<const Vec2> points, bool closed, int per_span);

// The curve at parameter t in [0, 1] of span `span` (between the limits of points span and
// span + 1), same conventions.
Vec2 eval_bspline(std::span<const Vec2> points, bool closed, int span, double t);

}  // namespace subvec
