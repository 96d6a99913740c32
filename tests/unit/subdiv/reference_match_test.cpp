// The OpenSubdiv path (subdiv/subdivision.h) against the naive reference of the paper's masks
// (tests/support/reference_loop.h) on every test mesh: same refined topology, same stencils (hence
// the same positions and colors for any control values), with and without the limit push.
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "subvec/subdiv/subdivision.h"
#include "support/reference_loop.h"
#include "support/test_meshes.h"

namespace subvec {
namespace {

using testing::StencilMesh;
using testing::TestMesh;

// Triangle key independent of the starting corner: rotated so that the smallest index comes first
// (keeps the orientation).
Tri canonical(Tri t) {
  std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
  return t;
}

// "index:weight ..." of the nonzero entries of a stencil row, for failure messages.
std::string describe(const Eigen::MatrixXd& stencils, int row) {
  std::string s;
  for (int j = 0; j < stencils.cols(); ++j)
    if (stencils(row, j) != 0)
      s += " " + std::to_string(j) + ":" + std::to_string(stencils(row, j));
  return s;
}

void expect_same_refinement(const TestMesh& t, int depth, bool limit) {
  SCOPED_TRACE(t.name + " depth " + std::to_string(depth) + (limit ? " limit" : " refined"));
  const MeshTopology topo = t.topology();
  const StencilMesh ref = testing::reference_stencils(t.mesh, topo, depth, limit);
  const StencilMesh osd = testing::opensubdiv_stencils(t.mesh, topo, depth, limit);
  ASSERT_EQ(osd.num_vertices(), ref.num_vertices());
  ASSERT_EQ(osd.num_colors(), ref.num_colors());
  ASSERT_EQ(osd.triangles.size(), ref.triangles.size());

  // Vertices correspond by position (refined vertices are well apart on these meshes).
  const std::vector<int> vmap = testing::match_points(osd.positions, ref.positions, 1e-9);
  std::set<int> hit;
  for (int i = 0; i < osd.num_vertices(); ++i) {
    ASSERT_GE(vmap[i], 0) << "refined vertex " << i << " at (" << osd.positions(i, 0) << ", "
                          << osd.positions(i, 1) << ") has no reference vertex";
    hit.insert(vmap[i]);
    const double diff =
        (osd.position_stencils.row(i) - ref.position_stencils.row(vmap[i])).cwiseAbs().maxCoeff();
    EXPECT_LT(diff, 1e-12) << "position stencil of refined vertex " << i
                           << "\n  opensubdiv:" << describe(osd.position_stencils, i)
                           << "\n  reference: " << describe(ref.position_stencils, vmap[i]);
  }
  EXPECT_EQ(static_cast<int>(hit.size()), osd.num_vertices());

  // Triangles correspond through the vertex map (same orientation, same parent); color values
  // through the triangles' corners.
  std::map<Tri, int> ref_triangle;
  for (size_t i = 0; i < ref.triangles.size(); ++i)
    ref_triangle[canonical(ref.triangles[i])] = static_cast<int>(i);
  std::vector<int> cmap(osd.num_colors(), -1);
  for (size_t i = 0; i < osd.triangles.size(); ++i) {
    Tri mapped;
    for (int k = 0; k < 3; ++k) mapped[k] = vmap[osd.triangles[i][k]];
    auto it = ref_triangle.find(canonical(mapped));
    ASSERT_NE(it, ref_triangle.end()) << "refined triangle " << i << " is not in the reference";
    const int r = it->second;
    EXPECT_EQ(osd.triangle_parent[i], ref.triangle_parent[r]);
    for (int k = 0; k < 3; ++k) {
      int rk = 0;
      while (ref.triangles[r][rk] != mapped[k]) ++rk;
      int& c = cmap[osd.triangle_colors[i][k]];
      if (c < 0) c = ref.triangle_colors[r][rk];
      EXPECT_EQ(c, ref.triangle_colors[r][rk]) << "color value " << osd.triangle_colors[i][k];
    }
  }
  for (int i = 0; i < osd.num_colors(); ++i) {
    ASSERT_GE(cmap[i], 0);
    const double diff =
        (osd.color_stencils.row(i) - ref.color_stencils.row(cmap[i])).cwiseAbs().maxCoeff();
    EXPECT_LT(diff, limit ? 1e-7 : 1e-12)
        << "color stencil of refined color value " << i
        << "\n  opensubdiv:" << describe(osd.color_stencils, i)
        << "\n  reference: " << describe(ref.color_stencils, cmap[i]);
  }

  // Tagged edges: the same sets.
  auto edge_set = [](const std::vector<EdgeVerts>& edges, const std::vector<int>* map) {
    std::set<std::pair<int, int>> set;
    for (EdgeVerts e : edges) {
      if (map) e = {(*map)[e[0]], (*map)[e[1]]};
      set.insert(std::minmax(e[0], e[1]));
    }
    return set;
  };
  EXPECT_EQ(edge_set(osd.tear_edges, &vmap), edge_set(ref.tear_edges, nullptr));
  EXPECT_EQ(edge_set(osd.crease_edges, &vmap), edge_set(ref.crease_edges, nullptr));
  EXPECT_EQ(edge_set(osd.border_edges, &vmap), edge_set(ref.border_edges, nullptr));

  // The float values of Subdivision::evaluate() are the same refinement.
  const Subdivision subdivision(t.mesh, topo, depth, {}, limit);
  RefinedMesh out;
  subdivision.evaluate(t.mesh.positions, t.mesh.colors, out, 1);
  ASSERT_EQ(out.num_vertices(), osd.num_vertices());
  ASSERT_EQ(out.num_colors(), osd.num_colors());
  double position_error = 0, color_error = 0;
  for (int i = 0; i < out.num_vertices(); ++i)
    for (int c = 0; c < 2; ++c)
      position_error =
          std::max(position_error, std::abs(out.positions[2 * i + c] - ref.positions(vmap[i], c)));
  for (int i = 0; i < out.num_colors(); ++i)
    for (int c = 0; c < 3; ++c)
      color_error = std::max(color_error, std::abs(out.colors[3 * i + c] - ref.colors(cmap[i], c)));
  EXPECT_LT(position_error, 1e-5);  // float output, positions below 25
  EXPECT_LT(color_error, 1e-4);     // float output, colors below 256
}

TEST(ReferenceMatch, EveryTestMeshAtDepths0To3) {
  for (const TestMesh& t : testing::all_test_meshes()) {
    expect_same_refinement(t, 0, true);
    for (int depth = 1; depth <= 3; ++depth) {
      expect_same_refinement(t, depth, false);
      expect_same_refinement(t, depth, true);
    }
  }
}

}  // namespace
}  // namespace subvec
