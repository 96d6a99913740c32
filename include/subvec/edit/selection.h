// Selection tools for editing (paper §6.1-6.2): the nearest control vertex or feature to a point,
// feature curves as drawn, and color regions grown from a vertex or a feature.
//
// Distances. Picking is Euclidean in image pixels: the nearest control vertex to the point, or the
// feature whose limit curve (the curve that is drawn, not its control polygon) passes nearest to
// it. A propagation radius r selects a region of *color values*, not of vertices: starting from
// the seed color values (those of the clicked side, see below), it grows across mesh triangles to
// every color value whose vertex lies within Euclidean distance r of the seed (of the vertex, or of
// the feature's control polygon), moving only through such values. Growing through triangles
// never crosses a tear, because the two sides of a tear use different color values at its
// vertices: the region is a Euclidean disk (or band) clipped to the side of the tears it started
// on, and it passes a tear only around its end, where the color is continuous.
//
// Regions. A region selection is a flood fill over the control mesh: from the clicked point's
// color value it grows through triangles to every color value whose color is within `tolerance`
// of the seed's, never across a tear, and optionally capped by a radius around the click. Tears
// rarely close a shape in a photograph; the tolerance stops the fill where the color changes, as a
// paint bucket does. It is a CIELAB distance (ΔE 1976, D65), so that shading in the dark, which
// RGB spreads thin, is one region (the default 25 fills the butterfly photograph's black wings
// from one click and stops at their outline, where RGB distance 60 left holes).
//
// Sides. A vertex on a tear has one color value per side. The seed is the value on the clicked
// side: for a vertex, the wedge of triangles around it that contains the direction to the click;
// for a feature, the side of its limit curve on which the click lies. So the two sides of a tear
// can be edited separately.
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "subvec/mesh/topology.h"
#include "subvec/mesh/vector_image.h"

namespace subvec {

// What a click selects: the nearest control vertex, the nearest feature, or the region around the
// click (color edits and the editor's Select tool; drags take a vertex or a feature).
// kVertices: a list of control vertices the user selected (the editor's direct handles).
enum class EditSelect { kVertex, kFeature, kRegion, kVertices, kAll };

// "vertex", "feature", "region", "vertices" or "all"; nullopt for any other name.
// kEditSelectNames lists them for error messages.
std::optional<EditSelect> edit_select_from_name(std::string_view name);
inline constexpr std::string_view kEditSelectNames =
    R"("vertex", "feature", "region", "vertices" or "all")";
// What a drag grabs: a vertex or a feature.
inline constexpr bool drag_grabs(EditSelect s) {
  return s == EditSelect::kVertex || s == EditSelect::kFeature;
}
inline constexpr std::string_view kDragSelectNames = R"("vertex" or "feature")";

// One smooth piece of a feature's limit curve (mesh/curves.h): the feature chain split at its
// corner vertices (junctions, a tear meeting a crease or the border), which the curve interpolates.
// `vertices` follows the chain's direction; closed: a loop with no corner (first not repeated).
struct CurvePiece {
  std::vector<int32_t> vertices;
  bool closed = false;
};

// The pieces of a feature of the mesh `topology` was built from, in chain order.
std::vector<CurvePiece> feature_pieces(const MeshTopology& topology, const Feature& feature);

// Control positions of a piece.
std::vector<Vec2> piece_points(const ControlMesh& mesh, const CurvePiece& piece);

// Index of the control vertex nearest to `p` (ties: the lowest index); -1 for an empty mesh.
int nearest_vertex(const ControlMesh& mesh, Vec2 p);

struct FeaturePick {
  int feature = -1;       // index into mesh.features, -1: the level has no feature
  double distance = 0;    // from the point to the feature's limit curve, pixels
  Vec2 nearest;           // the nearest point of the curve
  int side = 0;           // +1: the point is left of the chain direction in image coordinates
                          // (cross(tangent, point - nearest) > 0), -1 right, 0 on the curve
};

// The feature whose limit curve passes nearest to `p` (ties: the lowest index).
FeaturePick nearest_feature(const ControlMesh& mesh, const MeshTopology& topology, Vec2 p);
// The same among `chains` (chains of tear or crease edges of `mesh`; pick.feature indexes them).
FeaturePick nearest_feature(std::span<const Feature> chains, const ControlMesh& mesh,
                            const MeshTopology& topology, Vec2 p);

// The interior creases as chains, so that they are picked, dragged, moved and deleted like the
// tear features (issue 25): mesh.creases split at every vertex where they do not simply continue
// (a corner of the topology, or a crease vertex with other than two crease edges), each chain in
// the order of its first edge in mesh.creases, closed loops repeating their first vertex. Ids are
// -1, -2, ... (a tear feature's id is >= 0).
std::vector<Feature> crease_chains(const ControlMesh& mesh, const MeshTopology& topology);
// What a shape edit or a deletion picks from: the tear features, then the crease chains.
std::vector<Feature> editable_chains(const ControlMesh& mesh, const MeshTopology& topology);

// A selection of color values of one level, with the seed the region grew from.
struct ColorSelection {
  std::vector<int32_t> colors;  // ascending, unique
  int32_t seed_color = -1;      // the color value nearest to the click on its side
  int32_t seed_vertex = -1;
};

// Vertex selection: the color value of the nearest vertex on the side of the click, grown by
// `radius` (pixels, >= 0; 0: the seed alone).
ColorSelection select_vertex_colors(const ControlMesh& mesh, const MeshTopology& topology, Vec2 at,
                                    double radius);

// Feature selection: the color values on the clicked side of the nearest feature (all its
// vertices), grown by `radius` around its control polygon. The seed is the clicked side's value at
// the feature vertex nearest to the click. Throws Error(kInvalidArgument) when the level has no
// feature.
ColorSelection select_feature_colors(const ControlMesh& mesh, const MeshTopology& topology,
                                     Vec2 at, double radius);

// Region selection (a flood fill, see Regions above): the seed is the color value of the clicked
// triangle's corner nearest to `at` (a point on no triangle takes the nearest triangle). The fill
// takes color values within `tolerance` (ΔE, >= 0) of the seed's color whose vertex lies within
// `radius` of `at` (infinity: no cap).
inline constexpr double kDefaultRegionTolerance = 25;
// A color selection's radius when none is given: no cap for a region, 0 (the seed alone) else.
inline constexpr double default_color_radius(EditSelect s) {
  return s == EditSelect::kRegion ? std::numeric_limits<double>::infinity() : 0.0;
}
ColorSelection select_region_colors(const ControlMesh& mesh, Vec2 at,
                                    double radius = std::numeric_limits<double>::infinity(),
                                    double tolerance = kDefaultRegionTolerance);

// Every color value of the mesh (an object's, recolored whole), the seed being the nearest vertex
// to `at` and its color value on the side of `at`.
ColorSelection select_all_colors(const ControlMesh& mesh, const MeshTopology& topology, Vec2 at);

// Every color value of the given control vertices (all sides of a vertex on a tear): color editing
// per control point. The seed is the first vertex and its first value. Throws
// Error(kInvalidArgument) for an empty list or an index out of range.
ColorSelection select_vertices_colors(const ControlMesh& mesh, std::span<const int32_t> vertices);

// The selection a color edit makes: one of the four above. `tolerance` is the region's only,
// `vertices` the list's.
ColorSelection select_colors(const ControlMesh& mesh, const MeshTopology& topology,
                             EditSelect select, Vec2 at, double radius, double tolerance,
                             std::span<const int32_t> vertices = {});

}  // namespace subvec
