// New and deleted features (issue 25; the paper's own limitation, §7.3): editing the topology of
// one level's control mesh so that a sharp edge appears where the user draws one, or goes away.
//
// Adding. A drawn polyline is fitted by a C^2 cubic B-spline (fit_curve): the clamped spline of
// its control points for an open curve, the periodic one for a closed curve. Those control points
// become the new feature's chain: each is inserted into the mesh (a triangle or an edge split),
// the chain's edges are recovered by flipping the smooth edges that cross them, and the triangles
// that changed are made Delaunay again by flips that keep every sharp edge. Because a chain of
// tear (or crease) edges subdivides to the B-spline of its vertices (mesh/curves.h), the rendered
// curve is the fit exactly. A tear then separates the colors of its two sides; each side's colors
// near the chain are refitted, by least squares through the subdivision stencils, to the surface
// as it was before the cut, so the picture changes only in that a sharp edge now exists where
// there was none: far from it nothing changes at all (the colors of the vertices more than two
// rings from a changed triangle are kept, and the surface there depends on nothing else).
//
// Deleting. A feature's edges become smooth, the color values of its two sides merge, and the
// colors near it are refitted: to the surface as it was, except within a band along the feature,
// where a membrane (Laplacian) term alone sets them, so the color crosses where the tear was by a
// ramp instead of a step. The band widens with the jump across the feature so that the ramp stays
// gentle; the mesh keeps its vertices, and so its budget.
//
// Creases drawn with kind kCrease, and those of a file, are edited like tears: picked, dragged and
// moved as chains (crease_chains(), edit/selection.h) and deleted with delete_crease().
//
// Both edits keep the mesh valid (mesh/validate.h) and are deterministic. Topology changes break
// the pyramid's link between this level and its neighbours (ControlMesh::parent_vertices,
// collapses): add_feature and delete_feature clear the edited level's, and the caller the next
// level's (apply_edit_ops does).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "subvec/mesh/vector_image.h"

namespace subvec {

enum class FeatureKind { kTear, kCrease };

// The C^2 fit of a drawn polyline: control points whose uniform cubic B-spline (clamped when open,
// periodic when closed; mesh/curves.h) follows it, parameterized by arc length. The polyline is
// closed when its ends are within kCloseDistance pixels and it is longer than 4 times that. The
// control points are spaced about `spacing` pixels apart, closer where the curve bends, until the
// curve is within `tolerance` pixels of every point of the polyline (or the spacing falls to
// kMinSpacing). Throws Error(kInvalidArgument) for fewer than 2 distinct points, a non-finite
// coordinate or a polyline shorter than kMinLength.
struct CurveFit {
  std::vector<Vec2> points;  // control points; a closed curve does not repeat its first
  bool closed = false;
  double deviation = 0;  // largest distance from the polyline to the curve, pixels
};
inline constexpr double kCloseDistance = 2.0;
inline constexpr double kMinSpacing = 1.5;
inline constexpr double kMinLength = 2.0;
inline constexpr double kJoinDistance = 2.0;  // add_feature: an open end this close joins a feature
// With `may_close` false the curve is open whatever its ends.
CurveFit fit_curve(std::span<const Vec2> polyline, double spacing, double tolerance = 0.5, bool may_close = true);

struct FeatureEditResult {
  int feature = -1;          // add: index of the new feature in mesh.features; delete: the index it had
  int32_t id = 0;            // the feature's id
  int vertices_added = 0;    // add: control vertices inserted
  int flips = 0;             // add: edge flips (recovery and Delaunay)
  int colors_refit = 0;      // color values refitted
  CurveFit curve;            // add: the fit whose control points the (first) chain is
  int pieces = 1;            // add: new features (the drawn curve split at its junctions)
  int junctions = 0;         // add: points where it meets existing features or creases
};

// Adds a feature along `polyline` (image pixels) to `mesh` (a valid level of a width x height
// image). A point within 1 pixel of the image border is put on it; the rest are kept kFrameMargin
// inside. Where the polyline crosses an existing feature or crease, or an open end comes within
// kJoinDistance of one, the two meet at a junction: a corner vertex inserted on the existing chain
// (whose curve then passes through it), and the polyline is split there into pieces, each fitted
// on its own with its ends on the junctions and added as its own feature. Throws
// Error(kInvalidArgument) naming the problem, with `mesh` unchanged, when the polyline is unusable
// (fit_curve), when a fitted piece would still cross a feature or crease ("crosses feature 3
// (id 12) near (40.5, 20)"), or when its control polygon crosses itself.
FeatureEditResult add_feature(ControlMesh& mesh, int width, int height, std::span<const Vec2> polyline,
                              FeatureKind kind = FeatureKind::kTear);

// Deletes mesh.features[feature] (see above). Throws Error(kInvalidArgument) for an index out of
// range.
FeatureEditResult delete_feature(ControlMesh& mesh, int width, int height, int feature);
// Deletes a chain of creases (one of crease_chains(), edit/selection.h): its edges become smooth and
// the colors near it are refitted as above (there is no jump, so the band is the narrowest).
// Throws Error(kInvalidArgument) when an edge of the chain is not a crease.
FeatureEditResult delete_crease(ControlMesh& mesh, int width, int height, const Feature& chain);

}  // namespace subvec
