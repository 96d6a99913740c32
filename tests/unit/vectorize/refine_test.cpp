// Data-dependent refinement (vectorize/refine.h): flips that follow the image, moves that lower
// the error, and what must not change (tears, corners, the border line, validity, determinism).
#include <gtest/gtest.h>

#include <cmath>

#include "subvec/core/error.h"
#include "subvec/mesh/topology.h"
#include "subvec/mesh/validate.h"
#include "subvec/vectorize/features.h"
#include "subvec/vectorize/initial_mesh.h"
#include "subvec/vectorize/refine.h"
#include "subvec/vectorize/simplify.h"
#include "support/synthetic.h"

namespace subvec {
namespace {

using test::textured_disk;

// The simplified mesh the refinement starts from in vectorize().
ControlMesh simplified(const Image8& img, int vertices) {
  ControlMesh mesh = build_initial_mesh(img, detect_features(img));
  SimplifyOptions options;
  options.target_vertices = vertices;
  simplify(mesh, img.width, img.height, options);
  return mesh;
}

// Two triangles over a 16 x 16 image whose colors are exactly the linear interpolation across the
// main diagonal (bright along x = y, dark at the other two corners), given the other diagonal.
TEST(Refine, FlipsToTheDiagonalThatFollowsTheImage) {
  constexpr int kSize = 16;
  Image8 img(kSize, kSize, 3);
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x)
      for (int k = 0; k < 3; ++k) img.row(y)[3 * x + k] = static_cast<uint8_t>(std::lround(240.0 * (1 - std::abs(x - y) / 16.0)));
  ControlMesh mesh;
  mesh.positions = {{0, 0}, {kSize, 0}, {kSize, kSize}, {0, kSize}};
  mesh.colors = {{240, 240, 240}, {0, 0, 0}, {240, 240, 240}, {0, 0, 0}};
  mesh.triangles = {{0, 1, 3}, {1, 2, 3}};  // the anti-diagonal 1-3
  mesh.triangle_colors = mesh.triangles;
  const RefineStats stats = refine_mesh(mesh, img);
  ASSERT_NO_THROW(validate_level(mesh, kSize, kSize));
  const MeshTopology topo = MeshTopology::build(mesh, kSize, kSize);
  EXPECT_GE(topo.find_edge(0, 2), 0);
  EXPECT_LT(topo.find_edge(1, 3), 0);
  EXPECT_GE(stats.flips, 1);
  // Corners stay; the error left is the image's 8-bit rounding.
  EXPECT_EQ(mesh.positions[2].x, kSize);
  EXPECT_GT(stats.error_before, 100 * stats.error_after);
  EXPECT_LT(stats.error_after / (3.0 * kSize * kSize), 0.5);
}

TEST(Refine, LowersTheErrorAndKeepsTearsCornersAndBorder) {
  const Image8 img = textured_disk(96, 72);
  ControlMesh mesh = simplified(img, 160);
  ASSERT_FALSE(mesh.features.empty());
  const ControlMesh before = mesh;
  const MeshTopology topo = MeshTopology::build(before, img.width, img.height);
  const RefineStats stats = refine_mesh(mesh, img);
  ASSERT_NO_THROW(validate_level(mesh, img.width, img.height));
  EXPECT_GT(stats.flips, 0);
  EXPECT_GT(stats.moves, 0);
  EXPECT_LT(stats.error_after, 0.9 * stats.error_before);
  // Same vertices, same features; tears and corners in place, border vertices on their side.
  ASSERT_EQ(mesh.num_vertices(), before.num_vertices());
  ASSERT_EQ(mesh.num_triangles(), before.num_triangles());
  EXPECT_EQ(mesh.features.size(), before.features.size());
  for (size_t f = 0; f < mesh.features.size(); ++f) EXPECT_EQ(mesh.features[f].vertices, before.features[f].vertices);
  int moved = 0;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Vec2 p = before.positions[v], q = mesh.positions[v];
    moved += !(p == q);
    switch (topo.vertex_tags[v]) {
      case VertexTag::kSmooth:
        break;
      case VertexTag::kCrease:  // the border: on the same side
        if (p.x == 0 || p.x == img.width) EXPECT_EQ(q.x, p.x) << v;
        else EXPECT_EQ(q.y, p.y) << v;
        break;
      default:
        EXPECT_EQ(q, p) << v;
    }
  }
  EXPECT_GT(moved, mesh.num_vertices() / 4);
  // The refined mesh's own error is what the stats report (recomputed from scratch, one round
  // further, it only falls).
  ControlMesh again = mesh;
  RefineOptions one;
  one.rounds = 1;
  const RefineStats next = refine_mesh(again, img, one);
  EXPECT_NEAR(next.error_before, stats.error_after, 1e-6 * stats.error_after);
  EXPECT_LE(next.error_after, next.error_before);
}

TEST(Refine, SameResultForAnyThreadCount) {
  const Image8 img = textured_disk(80, 64);
  const ControlMesh start = simplified(img, 120);
  ControlMesh one = start, two = start, three = start;
  RefineOptions options;
  options.threads = 1;
  refine_mesh(one, img, options);
  options.threads = 2;
  refine_mesh(two, img, options);
  options.threads = 3;
  refine_mesh(three, img, options);
  EXPECT_EQ(one.positions, two.positions);
  EXPECT_EQ(one.colors, two.colors);
  EXPECT_EQ(one.triangles, two.triangles);
  EXPECT_EQ(one.triangle_colors, two.triangle_colors);
  EXPECT_EQ(one.positions, three.positions);
  EXPECT_EQ(one.triangles, three.triangles);
}

TEST(Refine, ZeroRoundsLeavesTheMeshAlone) {
  const Image8 img = textured_disk(64, 48);
  ControlMesh mesh = simplified(img, 80);
  const ControlMesh before = mesh;
  RefineOptions options;
  options.rounds = 0;
  const RefineStats stats = refine_mesh(mesh, img, options);
  EXPECT_EQ(stats.flips + stats.moves, 0);
  EXPECT_EQ(mesh.positions, before.positions);
  EXPECT_EQ(mesh.triangles, before.triangles);
  EXPECT_EQ(mesh.colors, before.colors);
}

TEST(Refine, RejectsOptionsOutOfRange) {
  const Image8 img = textured_disk(32, 24);
  ControlMesh mesh = simplified(img, 40);
  for (auto change : std::initializer_list<void (*)(RefineOptions&)>{
           [](RefineOptions& o) { o.rounds = -1; }, [](RefineOptions& o) { o.min_gain = 1; },
           [](RefineOptions& o) { o.min_area = -1; }, [](RefineOptions& o) { o.max_step = 0; },
           [](RefineOptions& o) { o.over_relaxation = 2.5; }, [](RefineOptions& o) { o.flip_passes = -1; },
           [](RefineOptions& o) { o.min_quality = 1.5; }, [](RefineOptions& o) { o.min_move_quality = -1; }}) {
    RefineOptions options;
    change(options);
    EXPECT_THROW(refine_mesh(mesh, img, options), Error);
  }
}

}  // namespace
}  // namespace subvec
