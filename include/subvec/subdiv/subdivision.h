// Piecewise smooth Loop subdivision (paper §3.1-3.2) through OpenSubdiv.
//
// The control mesh becomes an OpenSubdiv Loop topology: crease and tear edges are infinitely
// sharp, corner vertices infinitely sharp, and colors a face-varying channel whose seams are the
// tears, interpolated with FVAR_LINEAR_NONE so that each side of a tear refines independently as a
// cubic B-spline boundary (the tear masks of Fig. 2d/2g). As in the paper we refine `depth` levels
// uniformly and push the refined vertices to their limit positions.
//
// A Subdivision refines topology once; evaluate() then re-applies the refinement to new positions
// or colors (an edit) without touching topology, and the *_stencils() matrices express the same
// map as one sparse operator (limit value = S * control values) for fitting.
#pragma once

#include <memory>
#include <span>
#include <vector>

#include <Eigen/SparseCore>

#include "subvec/mesh/topology.h"
#include "subvec/mesh/vector_image.h"

namespace subvec {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int32_t>;

// A dense triangle mesh on the limit surface.
struct RefinedMesh {
  int depth = 0;
  std::vector<float> positions;          // #N by 2, limit (x, y) of each refined vertex
  std::vector<float> colors;             // #M by 3, limit (r, g, b) of each refined color value
  std::vector<Tri> triangles;            // #T refined triangles (vertex indices), same orientation
  std::vector<Tri> triangle_colors;      // #T color index of each corner
  std::vector<int32_t> triangle_parent;  // #T control face each one refines
  std::vector<EdgeVerts> tear_edges;     // refined edges on a tear (the feature curves)
  std::vector<EdgeVerts> crease_edges;   // refined edges on an interior crease
  std::vector<EdgeVerts> border_edges;   // refined edges on the image border
  // The limit mesh one level coarser, over the same vertices and color values (empty at depth 0):
  // a refined vertex that refines a vertex of level depth - 1 has that vertex's limit, so these
  // are exactly the depth - 1 triangles. For a cheaper preview (subvec serve's drags).
  std::vector<Tri> coarse_triangles;
  std::vector<Tri> coarse_triangle_colors;

  int num_vertices() const { return static_cast<int>(positions.size() / 2); }
  int num_colors() const { return static_cast<int>(colors.size() / 3); }
  int num_triangles() const { return static_cast<int>(triangles.size()); }
};

class Subdivision {
 public:
  // Refines `depth` levels (0..10). With an empty `faces`, the whole mesh; otherwise only the listed
  // control faces (each once, any order) and the one-ring of faces their limit surface depends on;
  // the output then holds the children of the listed faces only. With `push_to_limit` false the
  // outputs (evaluate, stencils) are the refined control values at `depth` instead of their limits:
  // the plain masks of Fig. 2, for tests and analysis.
  Subdivision(const ControlMesh& mesh, const MeshTopology& topology, int depth,
              std::span<const int32_t> faces = {}, bool push_to_limit = true);
  ~Subdivision();
  Subdivision(Subdivision&&) noexcept;
  Subdivision& operator=(Subdivision&&) noexcept;

  int depth() const;
  bool push_to_limit() const;
  // Topology of the refined mesh (positions and colors left empty).
  const RefinedMesh& topology() const;
  // Sizes of the evaluated arrays: refined vertices (#N) and refined color values (#M).
  int num_vertices() const;
  int num_colors() const;

  // Limit (without the limit push: refined) positions and colors of the refined vertices for the
  // given control values (the full control arrays of the mesh this was built from). Fills
  // out.positions / out.colors and copies the topology into `out` when its triangle count
  // differs. `threads` <= 0: all cores. Views of up to 2^19 refined values evaluate through the
  // limit stencils (built on first use, then one sparse product split over the threads); larger
  // ones refine level by level. The path depends on the size alone, never on call history.
  void evaluate(std::span<const Vec2> positions, std::span<const Color> colors, RefinedMesh& out,
                int threads = 0) const;
  void evaluate_positions(std::span<const Vec2> positions, std::span<float> out, int threads = 0) const;
  void evaluate_colors(std::span<const Color> colors, std::span<float> out, int threads = 0) const;
  // The values of evaluate() and evaluate_positions() (to float precision) for a single
  // evaluation: they refine level by level and never build the stencils, which cost several
  // evaluations (a one-off render, the fit's limit positions).
  void evaluate_once(std::span<const Vec2> positions, std::span<const Color> colors, RefinedMesh& out,
                     int threads = 0) const;
  void evaluate_positions_once(std::span<const Vec2> positions, std::span<float> out) const;

  // Limit stencils: row i expresses refined vertex i (color value i) as a combination of control
  // vertices (color values). #N by #V and #M by #C; every row sums to 1 (to 3e-8 for color values
  // on a tear after the limit push: OpenSubdiv's face-varying crease limit mask has float
  // weights). Without the limit push, the refinement stencils.
  const SparseMatrix& position_stencils() const;
  const SparseMatrix& color_stencils() const;

 private:
  void evaluate_with(std::span<const Vec2> positions, std::span<const Color> colors, RefinedMesh& out,
                     int threads, bool once) const;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Exact limit evaluation anywhere, through OpenSubdiv's Loop patches (Gregory triangles at
// irregular vertices). A point of control face f with parameters (u, v), u, v >= 0, u + v <= 1,
// lies at barycentric weights (1-u-v, u, v) of the face's corners in the refined limit sense.
class LimitEvaluator {
 public:
  LimitEvaluator(const ControlMesh& mesh, const MeshTopology& topology);
  ~LimitEvaluator();
  LimitEvaluator(LimitEvaluator&&) noexcept;
  LimitEvaluator& operator=(LimitEvaluator&&) noexcept;

  struct Sample {
    Vec2 position, position_du, position_dv;
    std::array<double, 3> color{}, color_du{}, color_dv{};
  };
  Sample evaluate(int face, double u, double v) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace subvec
