// The subdivision vector image (paper §3): a 2D triangle control mesh over the image domain
// [0,W]x[0,H] (pixel units, origin top-left, y down; pixel (i,j) is centred at (i+0.5, j+0.5)).
//
// Design note. Positions and colors are two attribute channels over one topology, as in
// OpenSubdiv. Positions are per vertex. Colors are face-varying: every triangle corner refers to a
// color value, so the two sides of a tear can carry different colors at the same vertex while a
// smooth vertex has one color shared by all its corners. Edge tags are not stored per edge: the
// image border is always a crease, interior creases are listed explicitly, and tears are exactly
// the edges of the features (chains of vertices). Everything else (edge list, vertex types) is
// derived once by MeshTopology (mesh/topology.h), so there is no redundant state to keep in sync.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace subvec {

struct Vec2 {
  double x = 0, y = 0;
  friend bool operator==(const Vec2&, const Vec2&) = default;
};

// sRGB color on the 0-255 scale, interpolated as stored (no linearization).
struct Color {
  float r = 0, g = 0, b = 0;
  friend bool operator==(const Color&, const Color&) = default;
};

using Tri = std::array<int32_t, 3>;
using EdgeVerts = std::array<int32_t, 2>;

// A tear feature: an ordered chain of control vertices whose consecutive pairs are mesh edges.
// A closed feature repeats its first vertex at the end. Ids are stable across levels.
struct Feature {
  int32_t id = 0;
  std::vector<int32_t> vertices;
  double saliency = 0;  // paper eq. 2; filled by vectorization, 0 when unknown

  bool closed() const { return vertices.size() > 2 && vertices.front() == vertices.back(); }
};

// A stylization stroke (paper §6.3): a cubic B-spline path through control points in image
// coordinates, drawn over the color field, tapering linearly at both ends.
struct Stroke {
  int32_t level = 0;
  std::vector<Vec2> points;
  float width = 1;      // pixels at scale 1
  Color color;
  float taper = 0.25f;  // fraction of the length over which each end tapers
};

// One level of detail: the control mesh of one piecewise smooth subdivision surface.
struct ControlMesh {
  std::vector<Vec2> positions;        // #V
  std::vector<Color> colors;          // #C face-varying color values
  std::vector<Tri> triangles;         // #F vertex indices, positive signed area (see docs/format.md)
  std::vector<Tri> triangle_colors;   // #F color index of each corner
  std::vector<EdgeVerts> creases;     // interior crease edges; the image border is always a crease
  std::vector<Feature> features;      // tear chains

  // Levels 1 and up of a multiresolution image (paper §5, §6.4): how this level was made from the
  // level before it, which is what the vector image pyramid replays (include/subvec/pyramid/).
  // That level lost the features this one lacks (their seams closed), then these half-edge
  // collapses in order, then its colors were refitted. Both are empty on level 0 and when unknown.
  std::vector<int32_t> parent_vertices;  // #V or empty: each vertex's index in the level before
  std::vector<EdgeVerts> collapses;      // (removed, kept) vertex pairs in the level before's numbering

  int num_vertices() const { return static_cast<int>(positions.size()); }
  int num_colors() const { return static_cast<int>(colors.size()); }
  int num_triangles() const { return static_cast<int>(triangles.size()); }

  // Matrix views for interop: #V by 2 positions, #C by 3 colors, #F by 3 indices.
  using PositionMatrix = Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor>;
  using ColorMatrix = Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor>;
  using IndexMatrix = Eigen::Matrix<int32_t, Eigen::Dynamic, 3, Eigen::RowMajor>;
  Eigen::Map<const PositionMatrix> position_matrix() const {
    return {&positions.data()->x, num_vertices(), 2};
  }
  Eigen::Map<PositionMatrix> position_matrix() { return {&positions.data()->x, num_vertices(), 2}; }
  Eigen::Map<const ColorMatrix> color_matrix() const {
    return {&colors.data()->r, num_colors(), 3};
  }
  Eigen::Map<ColorMatrix> color_matrix() { return {&colors.data()->r, num_colors(), 3}; }
  Eigen::Map<const IndexMatrix> triangle_matrix() const {
    return {triangles.data()->data(), num_triangles(), 3};
  }
  Eigen::Map<const IndexMatrix> triangle_color_matrix() const {
    return {triangle_colors.data()->data(), num_triangles(), 3};
  }
};

// An object (a layer over one level): its own control mesh, drawn over the level's mesh in the
// order of VectorImage::objects. Its mesh is a triangulated region whose boundary is the closed
// curve it was cut along (a boundary edge is a crease, like the image border of a level), and its
// positions may leave the image (an object moved partly off it is clipped when drawn). Moving,
// rotating or scaling it moves its control points: the limit surface of an affine image of the
// control points is the affine image of the limit surface. edit/objects.h makes and edits them.
struct Object {
  int32_t level = 0;  // the level it is drawn over
  std::string name;
  bool visible = true;
  ControlMesh mesh;   // parent_vertices and collapses stay empty
  // Strokes on the object (edit/stylize.h with an object): drawn over its layer, under the objects
  // above it, and moved with it. Each has the object's level.
  std::vector<Stroke> strokes;
};

struct VectorImage {
  int32_t width = 0, height = 0;
  std::vector<ControlMesh> levels;  // level 0 is the finest
  std::vector<Object> objects;      // bottom to top
  std::vector<Stroke> strokes;
  std::vector<std::pair<std::string, std::string>> metadata;
};

}  // namespace subvec
