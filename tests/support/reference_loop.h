// A slow, obvious reference for the piecewise smooth Loop subdivision of paper §3.2, written from
// the masks of Fig. 2 alone, to check the OpenSubdiv path (src/subdiv/subdivision.cpp).
//
// Design note. One level of refinement is one function, refine(), that applies the masks face by
// face and vertex by vertex with no precomputed structure beyond an edge map; push_to_limit()
// applies the limit masks. Values are matrices with one row per vertex (per color value) and any
// number of columns, so the same code refines positions (2 columns), colors (3 columns) or the
// identity matrix, which yields the stencils (row i = weights of refined value i over the control
// values). Colors are face-varying exactly as in ControlMesh: every triangle corner names a color
// value, and the masks at a vertex act on the "fan" of corners that share one value, so the two
// sides of a tear refine independently.
//
// Masks (weights of the centre, then of the neighbours):
//   vertex point  smooth        alpha(n) = (3/8 + 1/4 cos(2 pi / n))^2 + 3/8,  (1 - alpha) / n each
//                 crease, tear  6/8, 1/8 and 1/8 on the two sharp neighbours (per side for tears)
//                 corner        1 (fixed)
//   edge point    smooth        3/8 and 3/8 on the ends, 1/8 and 1/8 on the two opposite vertices
//                 crease, tear  1/2, 1/2 (per side for tears); the image border is a crease
//   limit         smooth        1 - n chi, chi each, chi = 1 / (3 / (8 beta) + n), beta = (1 -
//   alpha) / n
//                 crease, tear  4/6, 1/6 and 1/6
//                 corner        1
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "subvec/mesh/topology.h"
#include "subvec/mesh/vector_image.h"
#include "subvec/subdiv/subdivision.h"

namespace subvec::testing {

// Loop's smooth vertex weight alpha(n) (Fig. 2a) and the smooth limit weight chi(n) of each of the
// n neighbours (the centre gets 1 - n chi).
double loop_alpha(int valence);
double loop_limit_chi(int valence);

// One level of the reference refinement.
struct ReferenceMesh {
  Eigen::MatrixXd vertex_values;  // #V by k, e.g. positions (k = 2) or the identity (stencils)
  Eigen::MatrixXd color_values;   // #C by l
  std::vector<Tri> triangles;
  std::vector<Tri> triangle_colors;
  std::vector<std::array<EdgeTag, 3>> edge_tags;  // tag of edge (v_k, v_k+1) of each triangle
  std::vector<VertexTag> vertex_tags;             // #V
  std::vector<int32_t> triangle_parent;           // control face each triangle lies in
  // (u, v) of each corner in the parent control face: barycentric weights (1-u-v, u, v) of the
  // control face's corners, as in LimitEvaluator. Dyadic, so exact in double.
  std::vector<std::array<std::array<double, 2>, 3>> triangle_uv;

  int num_vertices() const { return static_cast<int>(vertex_values.rows()); }
  int num_colors() const { return static_cast<int>(color_values.rows()); }
  int num_triangles() const { return static_cast<int>(triangles.size()); }
};

// The control mesh as level 0, with the given values (#V by k and #C by l). Throws
// std::invalid_argument when the sizes disagree with the mesh.
ReferenceMesh reference_control_mesh(const ControlMesh& mesh, const MeshTopology& topology,
                                     Eigen::MatrixXd vertex_values, Eigen::MatrixXd color_values);
// Same, with the mesh's positions (#V by 2) and colors (#C by 3) as values.
ReferenceMesh reference_control_mesh(const ControlMesh& mesh, const MeshTopology& topology);

// One step M^r -> M^(r+1) with the masks of Fig. 2. Throws std::logic_error when a color value
// spans a smooth edge inconsistently or a crease/tear vertex does not have two sharp edges.
ReferenceMesh refine(const ReferenceMesh& mesh);
// The limit masks applied to every vertex and color value (topology unchanged).
ReferenceMesh push_to_limit(const ReferenceMesh& mesh);

// `depth` steps of refine(), then push_to_limit() when asked; values are positions and colors.
ReferenceMesh reference_loop(const ControlMesh& mesh, const MeshTopology& topology, int depth,
                             bool limit);

// The refinement of a control mesh as explicit linear maps, from either implementation, so that
// tests can be written once and run on both. Dense: the test meshes are tiny.
struct StencilMesh {
  Eigen::MatrixXd position_stencils;  // #N by #V
  Eigen::MatrixXd color_stencils;     // #M by #C
  Eigen::MatrixXd positions;          // #N by 2, position_stencils * control positions
  Eigen::MatrixXd colors;             // #M by 3, color_stencils * control colors
  std::vector<Tri> triangles;         // refined vertex indices, #T
  std::vector<Tri> triangle_colors;   // refined color indices, #T
  std::vector<int32_t> triangle_parent;
  std::vector<EdgeVerts> tear_edges, crease_edges, border_edges;  // as in RefinedMesh

  int num_vertices() const { return static_cast<int>(positions.rows()); }
  int num_colors() const { return static_cast<int>(colors.rows()); }
};
StencilMesh reference_stencils(const ControlMesh& mesh, const MeshTopology& topology, int depth,
                               bool limit);
StencilMesh opensubdiv_stencils(const ControlMesh& mesh, const MeshTopology& topology, int depth,
                                bool limit);

// Positions and colors of a control mesh as matrices (#V by 2, #C by 3).
Eigen::MatrixXd position_values(const ControlMesh& mesh);
Eigen::MatrixXd color_values(const ControlMesh& mesh);

// For each row of `points` (#A by 2), the index of the row of `targets` (#B by 2) within
// `tolerance` of it (the nearest one), or -1 when there is none.
std::vector<int> match_points(const Eigen::MatrixXd& points, const Eigen::MatrixXd& targets,
                              double tolerance);

}  // namespace subvec::testing
