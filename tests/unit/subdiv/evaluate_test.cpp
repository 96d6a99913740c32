// Evaluation paths agree bit for bit: threads split the color channels, never the arithmetic.
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace subvec
