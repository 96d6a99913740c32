// As-rigid-as-possible shape manipulation of a 2D triangle mesh (paper §6.1, after Igarashi,
// Moscovich and Hughes, "As-Rigid-As-Possible Shape Manipulation", SIGGRAPH 2005).
//
// Design note. Igarashi et al. split the non-linear ARAP problem into two linear least-squares
// solves, both with hard constraints on chosen coordinates:
//   1. similarity step: every triangle keeps the shape of its rest triangle up to a similarity.
//      For each triangle and each of its three vertices k with base edge (i, j), the rest position
//      is p_k = p_i + x (p_j - p_i) + y R90 (p_j - p_i); the energy E1 sums
//      |v_k - v_i - x (v_j - v_i) - y R90 (v_j - v_i)|^2. It is quadratic in all 2#V coordinates
//      (x and y coupled).
//   2. scale adjustment: each rest triangle is fitted to the step-1 result by a similarity
//      (a 4x4 least-squares problem per triangle, precomputed), scaled back to its rest size, and
//      the mesh is solved to match the edge vectors of these fitted triangles:
//      E2 = sum over triangles and edges |(v_b - v_a) - e_ab|^2 (x and y separate, same matrix).
// Weights. Control meshes from vectorization have many thin triangles along features and near the
// border, and the plain energies let such a triangle flip for a sub-pixel error. Each step-1 term
// is therefore weighted by |e_k|^2 / (4 A), e_k the base edge opposite vertex k and A the rest
// area: the squared residual divided by the squared height of k, times the area, so the energy
// approximates the integral of the squared distortion over the mesh and a thin triangle resists
// having its apex pushed through its base. Step 2 weights a triangle's edges by the mean of its
// three step-1 weights. Weights change neither the exact reproduction of rigid motions nor the
// constraints.
//
// Constrained coordinates are eliminated (fixed values moved to the right-hand side), so the
// constraints are met exactly. The three matrices (step 1; step 2 for x; step 2 for y) depend only
// on the rest mesh and on *which* coordinates are fixed: they are factored once per constraint set
// (sparse LDLT with AMD ordering) and a drag only back-substitutes (libigl's
// arap_precomputation / arap_solve split).
//
// Coordinates are fixed per axis so that a vertex can slide along a line (an image border vertex
// keeps its y on the top and bottom sides and its x on the left and right sides).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "subvec/mesh/vector_image.h"

namespace subvec {

// Which coordinates of a vertex are constrained (bit field).
enum class FixedAxes : uint8_t { kNone = 0, kX = 1, kY = 2, kXY = 3 };

class ArapDeformer {
 public:
  // `rest`: #V rest positions; `triangles`: #F triangles of positive signed area over them;
  // `fixed`: #V, which coordinates each vertex has constrained. Factors the three systems.
  // Throws Error(kInvalidArgument) on mismatched sizes, an index out of range, a degenerate rest
  // triangle, or constraints that leave the similarity step singular: it needs at least two
  // vertices with both coordinates fixed in every connected part of the mesh (a similarity has
  // four degrees of freedom), and the scale step at least one fixed x and one fixed y.
  ArapDeformer(std::span<const Vec2> rest, std::span<const Tri> triangles,
               std::span<const FixedAxes> fixed);
  ~ArapDeformer();
  ArapDeformer(ArapDeformer&&) noexcept;
  ArapDeformer& operator=(ArapDeformer&&) noexcept;

  int num_vertices() const;
  const std::vector<FixedAxes>& fixed() const;

  // Deforms the mesh: `targets` (#V) gives the value of every fixed coordinate (the others are
  // ignored); `out` (#V) receives the deformed positions, whose fixed coordinates are copied from
  // `targets` bit for bit. Back-substitution only. With `similarity` (#V), the step-1 result too.
  // Throws Error(kInvalidArgument) on a size mismatch or a non-finite target.
  void solve(std::span<const Vec2> targets, std::span<Vec2> out,
             std::span<Vec2> similarity = {}) const;
  // Step 1 alone (the similarity solve), for tests and analysis.
  void solve_similarity(std::span<const Vec2> targets, std::span<Vec2> out) const;

  // One iteration of local-global ARAP (Sorkine and Alexa 2007; Liu et al. 2008 in the plane)
  // from `current` (#V): each triangle's rest shape is rotated to fit its `current` shape best,
  // then `out` (#V) receives the positions whose edges best match those rotated rest edges, with
  // step 2's weighted edge Laplacian (factored already) and the fixed coordinates from `targets`.
  // Returns the rigidity energy of `current` in that weighting, sum over triangles of
  // w_f * sum over edges |(v_b - v_a) - R_f (p_b - p_a)|^2: one iteration never increases it
  // along the straight path from `current` to `out` (the global step minimises a convex
  // quadratic). Used by ShapeEditor's fold-free path (edit/shape.h).
  double rigid_step(std::span<const Vec2> targets, std::span<const Vec2> current,
                    std::span<Vec2> out) const;

  // Solves L d = -g for the free coordinates of `direction` (#V), whose fixed coordinates are
  // given (0: a descent step; the handles' remaining way: a step that also moves them), L step
  // 2's weighted edge Laplacian (factored already), both axes: the quadratic proxy that
  // preconditions a descent on another energy whose gradient is `gradient` (#V).
  void precondition(std::span<const Vec2> gradient, std::span<Vec2> direction) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The usual ARAP rigidity energy of a deformation: sum over triangles of
// min over rotations R of sum over the triangle's edges |(v_b - v_a) - R (p_b - p_a)|^2, in square
// pixels; 0 exactly for a rigid motion. `rest` and `deformed` are #V, `triangles` #F.
double rigidity_energy(std::span<const Vec2> rest, std::span<const Vec2> deformed,
                       std::span<const Tri> triangles);

}  // namespace subvec
