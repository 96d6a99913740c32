// Shape editing (paper §6.1): as-rigid-as-possible deformation of one level's control mesh under
// the constraints a mouse gives: drag a vertex, drag part of a feature, move a whole feature.
//
// The image frame is part of every constraint set: the four image corners stay where they are and
// the other border vertices slide along their side of the rectangle (the coordinate across the
// side is fixed). A handle on the border is projected onto its side in the same way; a handle on
// an image corner does not move. Only positions change, never the topology, so feature chains,
// creases and tears are kept and every feature curve stays a C^2 cubic B-spline by construction
// (paper §3.2).
//
// No edit folds the mesh (issue 25). The ARAP solve (edit/arap.h) is the result whenever it
// flips nothing. When its scale-adjustment step s2 flips (near thin triangles squeezed against
// the border or a feature) but the similarity step s1 does not, the result is
// s1 + lambda (s2 - s1) with the largest lambda in [0, 1) that flips nothing (bisection to
// 1/1024). When s1 itself flips, the fold-free path takes over: starting from the rest shape, it
// pushes the handles towards their targets along the ARAP step (or along the preconditioned step
// of the symmetric Dirichlet energy, whichever goes farther), each push stopping before any
// triangle falls to 1/1000 of its rest area (the signed area along a straight path is a quadratic,
// so the bound is exact), and between pushes descends the symmetric Dirichlet energy with the
// handles held (Laplacian-preconditioned, after Kovalsky et al.'s accelerated quadratic proxy):
// the energy is infinite at a degenerate triangle, so the descent moves the free vertices away
// from squeezed triangles and makes room. Then it descends the energy with the handles at their
// targets until it settles. The handles meet their targets exactly, unless the pushes stop
// gaining ground: then the result is the last fold-free position on the way and reached() says
// how far it went. That happens where no fold-free position exists or is within reach: a feature
// chain that would cross itself or another chain held in place, or the image frame, which stops
// handles a margin (kFrameMargin) inside it and can squeeze a triangle of handles flat (framed()).
// The result is deterministic: the same ops give the same bits.
#pragma once

#include <cstdint>
#include <list>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "subvec/edit/arap.h"
#include "subvec/mesh/vector_image.h"

namespace subvec {

// Control vertices the user moves and their target positions (parallel arrays, no repeats), and
// optionally the extent of the deformation.
struct Handles {
  std::vector<int32_t> vertices;
  std::vector<Vec2> targets;
  // > 0: only the part of the mesh within this Euclidean distance (pixels, rest positions) of a
  // handle deforms; farther vertices are pinned. 0: the whole mesh, held by the image frame.
  double region = 0;
  // When set, the region is the disk of radius `region` around this point instead of around every
  // handle. A feature drag sets it to the grab point: the far vertices of a long feature are
  // handles that barely move (the Gaussian falloff), and the region around them would let the
  // mesh near them deform beyond 3 sigma of the drag.
  std::optional<Vec2> center;
};

// One vertex moved by `displacement`.
Handles drag_vertex(const ControlMesh& mesh, int vertex, Vec2 displacement);

// Part of a feature dragged from `center` by `displacement` (paper §6.1): every vertex of the
// feature moves by g * displacement with g = exp(-d^2 / (2 sigma^2)), d the Euclidean distance from
// its rest position to `center`. All the feature's vertices are handles (far ones barely move, so
// the rest of the feature holds its place); a region given later is centred on `center`
// (Handles::center). sigma > 0, pixels.
Handles drag_feature(const ControlMesh& mesh, const Feature& feature, Vec2 center,
                     Vec2 displacement, double sigma);

// A whole feature rotated by `degrees` about the centroid of its control vertices, then translated
// by `translate`. Positive angles turn from +x towards +y: clockwise on screen (y points down).
Handles move_feature(const ControlMesh& mesh, const Feature& feature, Vec2 translate,
                     double degrees);

// A selection of control vertices translated by `translate` (the editor's direct handles: a box
// selection dragged or nudged with the arrow keys). Throws Error(kInvalidArgument) for an empty
// selection, an index out of range or one given twice.
Handles move_vertices(const ControlMesh& mesh, std::span<const int32_t> vertices, Vec2 translate);

// The extent of a drag the user leaves to the editor (issue 29): an influence local to what was
// grabbed, so that a small shape moves without the rest of the picture. For a feature, sigma is a
// quarter of its control polygon's length, within [8, 60] pixels, or, for a closed feature whose
// bounding box has a diagonal D of 60 pixels or less, 2 D, so that the small closed shape moves
// nearly as a whole; the region is 3 sigma, at least 30 pixels. For a vertex (feature < 0), the
// region is 4 times its longest edge, at least 30 pixels (sigma is unused). Throws
// Error(kInvalidArgument) for an index out of range.
struct DragExtent {
  double sigma = 20;
  double region = 0;
};
DragExtent suggested_drag_extent(const ControlMesh& mesh, int feature, int vertex);
// For a chain of the mesh (a feature, or a crease chain: edit/selection.h), as for a feature.
DragExtent suggested_drag_extent(const ControlMesh& mesh, const Feature& chain);
// For a selection of vertices: the largest of their regions (sigma is unused).
DragExtent suggested_drag_extent(const ControlMesh& mesh, std::span<const int32_t> vertices);

// Carries points through a shape edit: each point keeps its barycentric coordinates in the control
// triangle of `triangles` that holds it at `rest` and takes them to the same triangle at `moved`
// (both #V; the triangles cover the image, so every point inside it has one; a point outside, or
// on no triangle through rounding, takes the nearest triangle's clamped coordinates). The map is
// piecewise affine and continuous, the identity where nothing moved, and exact for a rigid motion
// of the whole mesh. It is how strokes follow a drag (apply_edit_ops).
void transport_points(const std::vector<Vec2>& rest, const std::vector<Vec2>& moved,
                      const std::vector<Tri>& triangles, std::span<Vec2> points);

class ShapeEditor {
 public:
  // The rest shape is `mesh`'s positions now; `width` x `height` is the image. Throws
  // Error(kInvalidArgument) for a mesh with a degenerate triangle.
  // With width and height MeshTopology::kNoFrame (an object's mesh, edit/objects.h) there is no
  // frame: targets go anywhere, and the object's boundary holds as the frame does (its vertices
  // stay unless they are handles).
  ShapeEditor(const ControlMesh& mesh, int width, int height);

  const std::vector<Vec2>& rest() const { return rest_; }
  // The lambda of the last deform: 1 when the scale adjustment was applied in full.
  double scale_fraction() const { return scale_fraction_; }
  // The fraction of the way the handles went in the last deform: 1 when they met their targets,
  // less when the fold-free path stopped (see above).
  double reached() const { return reached_; }
  // Whether the frame held a handle in the last deform: a target outside the image (less the
  // margin) was moved to its nearest point inside.
  bool framed() const { return framed_; }

  // Deformed positions (#V) with the handles at their targets (projected as described above).
  // The factorization depends only on the set of handle vertices and the region, and is cached
  // (the last few sets), so repeated calls with the same vertices and new targets, a drag, only
  // back-substitute. Never flips or degenerates a triangle (see above; reached() < 1 when the
  // handles stopped short). Throws Error(kInvalidArgument) for an out-of-range or repeated
  // handle vertex, or a non-finite target or region.
  std::vector<Vec2> deform(const Handles& handles);
  void deform(const Handles& handles, std::vector<Vec2>& out);

 private:
  struct Cached {
    std::vector<int32_t> handles;  // sorted
    double region = 0;
    std::optional<Vec2> center;
    std::shared_ptr<const ArapDeformer> deformer;
  };
  const ArapDeformer& deformer_for(std::vector<int32_t> handles, double region, std::optional<Vec2> center);

  std::vector<Vec2> rest_;
  std::vector<Tri> triangles_;
  int width_, height_;
  static constexpr double kFrameMargin = 1.0;  // pixels: how close the frame lets a handle come (0.25 squeezed more drags flat)
  std::vector<uint8_t> sides_;  // per vertex: bit 0 left, 1 right, 2 top, 3 bottom
  std::vector<uint8_t> pinned_;  // an object's mesh (no frame): its boundary vertices, held
  std::list<Cached> cache_;     // most recently used first
  int first_flip(const std::vector<Vec2>& positions) const;
  void fold_free(const ArapDeformer& deformer, std::vector<Vec2>& out);
  double distortion(const std::vector<Vec2>& x, std::vector<Vec2>* gradient) const;
  double relax_step(const ArapDeformer& deformer, std::vector<Vec2>& x);
  static constexpr double kAreaFloor = 1e-3;  // of each triangle's rest area
  static constexpr double kStepShare = 0.9;   // of the way to the first triangle at its floor
  static constexpr int kFoldFreeRounds = 200, kRelaxSteps = 4, kSettleSteps = 100;
  struct Inverse {
    double m00, m01, m10, m11, area;  // the rest edge matrix's inverse, and the rest area
  };
  std::vector<double> floor2_;  // per triangle, twice its smallest allowed area
  std::vector<Inverse> inverse_;
  std::vector<Vec2> gradient_, direction_, trial_;  // scratch
  double reached_ = 1;
  bool framed_ = false;

  std::vector<Vec2> targets_, similarity_;  // scratch
  double scale_fraction_ = 1;
};

}  // namespace subvec
