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
// refined tear edge a band `width` wide (image pixels) on each side, in that side's color half a
// width in (linear over the refined triangle), drawn as an ordinary anti-aliased shape, restores
// them. All first sides' bands come first and reach half a width across the tear; the second
// sides' bands, drawn over them from the tear out, then mix the two sides by coverage in the
// pixels on the tear, as the raster renderer does, with nothing of the unsmoothed mesh under
// them. (Measured on the eight vectorized photographs in poppler: median MAE 1.29 with bands in
// the edge's color meeting on the tear, 1.14 with these.)
struct TearBand {
  std::array<Vec2, 4> corners;  // the edge's ends, then their offsets into the side
  std::array<double, 3> color{0, 0, 0};
  EdgeVerts edge{-1, -1};  // the refined tear edge, as listed in mesh.tear_edges
  int side = 0;
};
std::vector<TearBand> tear_bands(const RefinedMesh& mesh, double width);

// The bands as drawn: runs of consecutive bands on one side of a tear whose colors are within
// `color_tolerance` levels of the run's first become one polygon (the tear's points, then the
// offsets back, where two bands meet the mean of their corners) in the run's mean color.
struct TearHint {
  std::vector<Vec2> polygon;
  std::array<double, 3> color{0, 0, 0};
};
std::vector<TearHint> tear_hints(const RefinedMesh& mesh, double width, double color_tolerance);

// Numbers for text formats: fixed notation, at most `decimals` decimals, no trailing zeros.
std::string fixed(double v, int decimals);

}  // namespace subvec::detail
