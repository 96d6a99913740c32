// Pieces shared by the PDF and SVG writers.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "subvec/mesh/vector_image.h"
#include "subvec/subdiv/subdivision.h"

namespace subvec::detail {

// The outline of a stroke (docs/format.md, "Strokes and metadata"), as one closed polygon in image
// coordinates: the cubic B-spline through the control points (end points repeated so that it
// starts and ends at them), offset on both sides by half its width, which falls linearly to zero
// over the first and last `taper` fraction of its length. Empty for fewer than two points.
std::vector<Vec2> stroke_outline(const Stroke& stroke);

// Triangle strips in the sense of PDF's free-form triangle meshes: a strip starts with a triangle
// (a, b, c) and each further vertex d makes (b, c, d) (flag 1) or (a, c, d) (flag 2) with the
// previous triangle's vertices a, b, c. Vertices are refined corners: a position and a color
// index, so strips never cross a tear. `order` lists, per strip vertex, the refined triangle and
// corner it comes from, and `flags` its flag (0 for the three vertices that start a strip).
struct Strips {
  std::vector<std::array<int32_t, 2>> corners;  // (triangle, corner 0..2)
  std::vector<uint8_t> flags;
};
Strips make_strips(const RefinedMesh& mesh);

// Tear hints. Viewers that fill a mesh of triangles without anti-aliasing (poppler's shadings,
// SVG with crisp edges) leave the tears, the only sharp edges of the picture, jagged. Along each
// refined tear edge a band `width` wide (image pixels) on each side, in that side's color at the
// edge (the mean of the edge's two corners), drawn as an ordinary anti-aliased shape, restores
// them: the two bands meet exactly on the tear, so their anti-aliased edges there mix the two
// sides as the raster renderer does, while elsewhere a band is within a fraction of a level of
// what it covers. All first sides' bands come first, then all second sides'.
struct TearBand {
  std::array<Vec2, 4> corners;  // the edge's ends, then their offsets into the side
  std::array<double, 3> color{0, 0, 0};
};
std::vector<TearBand> tear_bands(const RefinedMesh& mesh, double width);

// Numbers for text formats: fixed notation, at most `decimals` decimals, no trailing zeros.
std::string fixed(double v, int decimals);

}  // namespace subvec::detail
