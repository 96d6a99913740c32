// As-rigid-as-possible deformation (edit/arap.h): rigid motions are reproduced exactly,
// constraints are met bit for bit, and bad constraint sets are refused.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "subvec/core/error.h"
#include "subvec/edit/arap.h"
#include "support/test_meshes.h"

namespace subvec {
namespace {

Vec2 rigid(Vec2 p, double degrees, Vec2 t) {
  const double a = degrees * M_PI / 180, c = std::cos(a), s = std::sin(a);
  return {c * p.x - s * p.y + t.x, s * p.x + c * p.y + t.y};
}

TEST(Arap, RigidMotionOfTheWholeMeshIsReproducedExactly) {
  const testing::TestMesh m = testing::grid_mesh(9, 7, 3.0, true);
  const std::vector<Vec2>& rest = m.mesh.positions;
  const int n = m.mesh.num_vertices();
  std::vector<FixedAxes> fixed(n, FixedAxes::kNone);
  // Two full vertices and one extra coordinate far apart.
  fixed[0] = fixed[n - 1] = FixedAxes::kXY;
  fixed[n / 2] = FixedAxes::kY;
  const ArapDeformer arap(rest, m.mesh.triangles, fixed);
  for (const double degrees : {0.0, 30.0, -115.0, 180.0}) {
    std::vector<Vec2> targets(n), out(n), step1(n);
    for (int v = 0; v < n; ++v) targets[v] = rigid(rest[v], degrees, {5.5, -3.25});
    arap.solve(targets, out);
    arap.solve_similarity(targets, step1);
    for (int v = 0; v < n; ++v) {
      EXPECT_NEAR(out[v].x, targets[v].x, 1e-9) << "vertex " << v << ", " << degrees << " degrees";
      EXPECT_NEAR(out[v].y, targets[v].y, 1e-9) << "vertex " << v << ", " << degrees << " degrees";
      EXPECT_NEAR(step1[v].x, targets[v].x, 1e-9);
      EXPECT_NEAR(step1[v].y, targets[v].y, 1e-9);
    }
    EXPECT_NEAR(rigidity_energy(rest, out, m.mesh.triangles), 0, 1e-12);
  }
}

TEST(Arap, ConstraintsAreMetBitForBit) {
  const testing::TestMesh m = testing::grid_mesh(6, 5, 4.0, true);
  const int n = m.mesh.num_vertices();
  std::vector<FixedAxes> fixed(n, FixedAxes::kNone);
  fixed[0] = fixed[7] = fixed[n - 1] = FixedAxes::kXY;
  fixed[12] = FixedAxes::kX;
  const ArapDeformer arap(m.mesh.positions, m.mesh.triangles, fixed);
  std::vector<Vec2> targets = m.mesh.positions, out(n);
  targets[7] = {targets[7].x + 1.0 / 3, targets[7].y - 0.7};
  targets[12].x += 0.1;
  arap.solve(targets, out);
  for (const int v : {0, 7, n - 1}) {
    EXPECT_EQ(out[v].x, targets[v].x);
    EXPECT_EQ(out[v].y, targets[v].y);
  }
  EXPECT_EQ(out[12].x, targets[12].x);
  EXPECT_NE(out[12].y, targets[12].y + 1);  // free: anything finite
  for (const Vec2& p : out) EXPECT_TRUE(std::isfinite(p.x) && std::isfinite(p.y));
}

TEST(Arap, TheSameTargetsGiveTheSameResult) {
  const testing::TestMesh m = testing::grid_mesh(6, 5, 4.0, true);
  const int n = m.mesh.num_vertices();
  std::vector<FixedAxes> fixed(n, FixedAxes::kNone);
  fixed[0] = fixed[n - 1] = fixed[15] = FixedAxes::kXY;
  const ArapDeformer arap(m.mesh.positions, m.mesh.triangles, fixed);
  std::vector<Vec2> a = m.mesh.positions, b = a, out_a(n), out_b(n), again(n), again_b(n);
  a[15].x += 2;
  b[15].y -= 3;
  arap.solve(a, out_a);
  arap.solve(b, out_b);
  arap.solve(a, again);
  arap.solve(b, again_b);
  EXPECT_EQ(out_a, again);
  EXPECT_EQ(out_b, again_b);
  // The two targets differ, and so do the results (each holds its own handle).
  EXPECT_NE(out_a, out_b);
  EXPECT_EQ(out_a[15], a[15]);
  EXPECT_EQ(out_b[15], b[15]);
}

TEST(Arap, ConstraintsThatDoNotPinTheMeshAreRefused) {
  const testing::TestMesh m = testing::grid_mesh(4, 4, 3.0, false);
  const int n = m.mesh.num_vertices();
  std::vector<FixedAxes> fixed(n, FixedAxes::kNone);
  fixed[5] = FixedAxes::kXY;  // one vertex leaves a rotation and a scaling free
  EXPECT_THROW(ArapDeformer(m.mesh.positions, m.mesh.triangles, fixed), Error);
  fixed[6] = FixedAxes::kX;  // still free to scale about vertex 5 along y... and rotate: rank 3
  EXPECT_THROW(ArapDeformer(m.mesh.positions, m.mesh.triangles, fixed), Error);
  fixed[6] = FixedAxes::kXY;
  EXPECT_NO_THROW(ArapDeformer(m.mesh.positions, m.mesh.triangles, fixed));
  std::vector<FixedAxes> wrong_size(n - 1, FixedAxes::kXY);
  EXPECT_THROW(ArapDeformer(m.mesh.positions, m.mesh.triangles, wrong_size), Error);
}

TEST(Arap, RigidityEnergyIsZeroForRigidMotionsOnly) {
  const testing::TestMesh m = testing::grid_mesh(5, 5, 2.0, true);
  std::vector<Vec2> moved, sheared;
  for (const Vec2& p : m.mesh.positions) {
    moved.push_back(rigid(p, 47, {3, 4}));
    sheared.push_back({p.x + 0.2 * p.y, p.y});
  }
  EXPECT_NEAR(rigidity_energy(m.mesh.positions, moved, m.mesh.triangles), 0, 1e-12);
  EXPECT_GT(rigidity_energy(m.mesh.positions, sheared, m.mesh.triangles), 0.1);
}

}  // namespace
}  // namespace subvec
