// Evaluation paths agree bit for bit: threads split the color channels, never the arithmetic.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "subvec/subdiv/subdivision.h"
#include "support/test_meshes.h"

namespace subvec {
namespace {

TEST(Evaluate, ColorsAreIdenticalWhateverTheThreadCount) {
  const testing::TestMesh t = testing::torn_disk();
  const MeshTopology topo = t.topology();
  const Subdivision sub(t.mesh, topo, 3);
  const int colors = sub.num_colors();
  std::vector<float> one(size_t(colors) * 3), two(size_t(colors) * 3), three(size_t(colors) * 3);
  sub.evaluate_colors(t.mesh.colors, one, 1);
  sub.evaluate_colors(t.mesh.colors, two, 2);
  sub.evaluate_colors(t.mesh.colors, three, 3);
  EXPECT_EQ(one, two);
  EXPECT_EQ(one, three);
  // And the values are the stencils' (to float precision).
  const SparseMatrix& s = sub.color_stencils();
  for (int i = 0; i < colors; ++i) {
    double r = 0;
    for (SparseMatrix::InnerIterator it(s, i); it; ++it) r += it.value() * t.mesh.colors[it.col()].r;
    EXPECT_NEAR(one[3 * size_t(i)], r, 1e-3);
  }
}

TEST(Evaluate, OneOffPositionsMatchTheStencils) {
  const testing::TestMesh t = testing::torn_disk();
  const MeshTopology topo = t.topology();
  for (int depth : {0, 1, 3}) {
    const Subdivision sub(t.mesh, topo, depth);
    std::vector<float> once(size_t(sub.num_vertices()) * 2), stencils(once.size());
    sub.evaluate_positions_once(t.mesh.positions, once);
    sub.evaluate_positions(t.mesh.positions, stencils);
    for (size_t i = 0; i < once.size(); ++i) EXPECT_NEAR(once[i], stencils[i], 1e-4) << "depth " << depth;
  }
}

// A triangle as its corners' limit values (x, y, r, g, b), rounded to 1/1024 and sorted, so that
// two refinements can be compared whatever their vertex numbering.
using Corners = std::array<std::array<long, 5>, 3>;
std::vector<Corners> triangle_values(const RefinedMesh& r, const std::vector<Tri>& triangles,
                                     const std::vector<Tri>& colors) {
  std::vector<Corners> out;
  for (size_t t = 0; t < triangles.size(); ++t) {
    Corners c;
    for (int k = 0; k < 3; ++k) {
      const size_t v = static_cast<size_t>(triangles[t][k]), m = static_cast<size_t>(colors[t][k]);
      const float values[5] = {r.positions[2 * v], r.positions[2 * v + 1], r.colors[3 * m],
                               r.colors[3 * m + 1], r.colors[3 * m + 2]};
      for (int i = 0; i < 5; ++i) c[k][i] = std::lround(values[i] * 1024);
    }
    std::sort(c.begin(), c.end());
    out.push_back(c);
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The coarse triangles of a depth-d refinement are the triangles of the depth d - 1 refinement:
// the same limit points and color values, tears included, for the whole mesh and for a few faces.
TEST(Evaluate, CoarseTrianglesAreTheLimitMeshOneLevelCoarser) {
  for (const testing::TestMesh& t : testing::all_test_meshes()) {
    const MeshTopology topo = t.topology();
    const std::vector<int32_t> some = {0, 1, 2, static_cast<int32_t>(t.mesh.num_triangles() - 1)};
    for (const std::vector<int32_t>& faces : {std::vector<int32_t>{}, some}) {
      for (int depth = 1; depth <= 3; ++depth) {
        const Subdivision fine(t.mesh, topo, depth, faces), coarse(t.mesh, topo, depth - 1, faces);
        RefinedMesh f, c;
        fine.evaluate_once(t.mesh.positions, t.mesh.colors, f);
        coarse.evaluate_once(t.mesh.positions, t.mesh.colors, c);
        ASSERT_EQ(f.coarse_triangles.size(), c.triangles.size()) << t.name << " depth " << depth;
        EXPECT_EQ(triangle_values(f, f.coarse_triangles, f.coarse_triangle_colors),
                  triangle_values(c, c.triangles, c.triangle_colors))
            << t.name << " depth " << depth << (faces.empty() ? "" : ", some faces");
      }
    }
    const Subdivision flat(t.mesh, topo, 0);
    EXPECT_TRUE(flat.topology().coarse_triangles.empty());
  }
}

}  // namespace
}  // namespace subvec
