// Selection and color editing (edit/selection.h, edit/color.h): BLEND and TRANSFORM keep what
// they promise, and the two sides of a tear are selected and edited separately.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <vector>

#include "subvec/core/error.h"
#include "subvec/edit/color.h"
#include "subvec/edit/selection.h"
#include "subvec/mesh/validate.h"
#include "support/synthetic.h"
#include "support/test_meshes.h"

namespace subvec {
namespace {

using testing::TestMesh;

// Color values used by the inside (faces 0..7) or the outside of the torn disk.
std::set<int> side_colors(const ControlMesh& m, bool inside) {
  std::set<int> colors;
  for (int f = 0; f < m.num_triangles(); ++f)
    if ((f < 8) == inside) colors.insert(m.triangle_colors[f].begin(), m.triangle_colors[f].end());
  return colors;
}

TEST(ColorSelection, VertexSelectionStaysOnTheClickedSideOfATear) {
  const TestMesh disk = testing::torn_disk();
  const MeshTopology topology = disk.topology();
  const ControlMesh& m = disk.mesh;
  const std::set<int> inside = side_colors(m, true), outside = side_colors(m, false);
  const Vec2 v = m.positions[disk.focus];  // a vertex on the tear
  const Vec2 centre = m.positions[0];
  // A click just inside the tear vertex picks its inside value; just outside, its outside value.
  const Vec2 in{v.x + 0.35 * (centre.x - v.x), v.y + 0.35 * (centre.y - v.y)};
  const Vec2 out{v.x - 0.2 * (centre.x - v.x), v.y - 0.2 * (centre.y - v.y)};
  const ColorSelection a = select_vertex_colors(m, topology, in, 0);
  const ColorSelection b = select_vertex_colors(m, topology, out, 0);
  EXPECT_EQ(a.seed_vertex, disk.focus);
  EXPECT_EQ(b.seed_vertex, disk.focus);
  EXPECT_TRUE(inside.count(a.seed_color) && !outside.count(a.seed_color));
  EXPECT_TRUE(outside.count(b.seed_color) && !inside.count(b.seed_color));
  // Growing any distance from inside never crosses the closed tear.
  const ColorSelection all_in = select_vertex_colors(m, topology, in, 1000);
  EXPECT_EQ(std::set<int>(all_in.colors.begin(), all_in.colors.end()), inside);
  const ColorSelection all_out = select_vertex_colors(m, topology, out, 1000);
  EXPECT_EQ(std::set<int>(all_out.colors.begin(), all_out.colors.end()), outside);
  // A small radius selects a few values near the seed.
  const ColorSelection some = select_vertex_colors(m, topology, out, 4);
  EXPECT_GT(some.colors.size(), 1u);
  EXPECT_LT(some.colors.size(), outside.size());
}

TEST(ColorSelection, FeatureSelectionTakesTheClickedSide) {
  const TestMesh disk = testing::torn_disk();
  const MeshTopology topology = disk.topology();
  const ControlMesh& m = disk.mesh;
  const std::set<int> inside = side_colors(m, true), outside = side_colors(m, false);
  const Vec2 v = m.positions[disk.focus], centre = m.positions[0];
  const Vec2 in{v.x + 0.35 * (centre.x - v.x), v.y + 0.35 * (centre.y - v.y)};
  const Vec2 out{v.x - 0.2 * (centre.x - v.x), v.y - 0.2 * (centre.y - v.y)};
  const FeaturePick pick = nearest_feature(m, topology, in);
  EXPECT_EQ(pick.feature, 0);
  EXPECT_LT(pick.distance, 1.5);
  const ColorSelection a = select_feature_colors(m, topology, in, 0);
  const ColorSelection b = select_feature_colors(m, topology, out, 0);
  // 8 tear vertices, one value per side each.
  EXPECT_EQ(a.colors.size(), 8u);
  EXPECT_EQ(b.colors.size(), 8u);
  for (int c : a.colors) EXPECT_TRUE(inside.count(c) && !outside.count(c));
  for (int c : b.colors) EXPECT_TRUE(outside.count(c) && !inside.count(c));
  EXPECT_EQ(a.seed_vertex, disk.focus);
}

TEST(ColorSelection, NothingToSelectWithoutFeatures) {
  const TestMesh grid = testing::grid_mesh(4, 4, 3, false);
  EXPECT_THROW(select_feature_colors(grid.mesh, grid.topology(), {5, 5}, 2), Error);
  EXPECT_EQ(nearest_feature(grid.mesh, grid.topology(), {5, 5}).feature, -1);
}

TEST(ColorEdit, BlendWithAmountZeroIsTheIdentity) {
  const VectorImage image = test::make_synthetic_image({.width = 96, .height = 96, .vertices = 400});
  ControlMesh m = image.levels[0];
  std::vector<int32_t> all(m.num_colors());
  for (int c = 0; c < m.num_colors(); ++c) all[c] = c;
  blend_colors(m, all, {1, 2, 3}, 0.0);
  EXPECT_EQ(m.colors, image.levels[0].colors);
  blend_colors(m, all, {1, 2, 3}, 1.0);
  for (const Color& c : m.colors) EXPECT_EQ(c, (Color{1, 2, 3}));
  EXPECT_THROW(blend_colors(m, all, {1, 2, 3}, 1.5), Error);
}

TEST(ColorEdit, BlendMixesLinearly) {
  const TestMesh disk = testing::torn_disk();
  ControlMesh m = disk.mesh;
  const std::vector<int32_t> some = {0, 3, 5};
  blend_colors(m, some, {200, 100, 0}, 0.25);
  for (int c = 0; c < m.num_colors(); ++c) {
    const Color o = disk.mesh.colors[c];
    const bool selected = c == 0 || c == 3 || c == 5;
    const Color want = selected ? Color{0.75f * o.r + 50, 0.75f * o.g + 25, 0.75f * o.b} : o;
    EXPECT_NEAR(m.colors[c].r, want.r, 1e-4);
    EXPECT_NEAR(m.colors[c].g, want.g, 1e-4);
    EXPECT_NEAR(m.colors[c].b, want.b, 1e-4);
  }
}

TEST(ColorEdit, TransformKeepsPerChannelRatiosInsideTheSelection) {
  const VectorImage image = test::make_synthetic_image({.width = 128, .height = 128, .vertices = 600});
  const ControlMesh& before = image.levels[0];
  const MeshTopology topology = validate_level(before, image.width, image.height);
  const ColorSelection s = select_vertex_colors(before, topology, {64, 64}, 30);
  ASSERT_GT(s.colors.size(), 10u);
  ControlMesh m = before;
  const Color seed = before.colors[s.seed_color];
  const Color target{30, 200, 120};
  transform_colors(m, s.colors, seed, target);
  EXPECT_NEAR(m.colors[s.seed_color].r, target.r, 1e-3);
  EXPECT_NEAR(m.colors[s.seed_color].g, target.g, 1e-3);
  EXPECT_NEAR(m.colors[s.seed_color].b, target.b, 1e-3);
  const std::set<int> selected(s.colors.begin(), s.colors.end());
  for (int c = 0; c < m.num_colors(); ++c) {
    if (!selected.count(c)) {
      EXPECT_EQ(m.colors[c], before.colors[c]) << "color " << c << " is not selected";
      continue;
    }
    // Ratio to the seed, per channel, is what it was.
    const float o[3] = {before.colors[c].r, before.colors[c].g, before.colors[c].b};
    const float n[3] = {m.colors[c].r, m.colors[c].g, m.colors[c].b};
    const float so[3] = {seed.r, seed.g, seed.b}, sn[3] = {target.r, target.g, target.b};
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(n[k] / sn[k], o[k] / so[k], 1e-5 * (1 + o[k] / so[k]));
  }
  // A seed with a zero channel cannot be transformed.
  EXPECT_THROW(transform_colors(m, s.colors, {0, 10, 10}, target), Error);
}

TEST(ColorEdit, TheTwoSidesOfATearAreEditedSeparately) {
  const TestMesh disk = testing::torn_disk();
  const MeshTopology topology = disk.topology();
  ControlMesh m = disk.mesh;
  const Vec2 v = m.positions[disk.focus], centre = m.positions[0];
  const Vec2 in{v.x + 0.35 * (centre.x - v.x), v.y + 0.35 * (centre.y - v.y)};
  const ColorSelection s = select_vertex_colors(m, topology, in, 1000);
  blend_colors(m, s.colors, {0, 255, 0}, 1);
  for (int c : side_colors(m, false)) EXPECT_EQ(m.colors[c], disk.mesh.colors[c]);
  for (int c : side_colors(m, true)) EXPECT_EQ(m.colors[c], (Color{0, 255, 0}));
  EXPECT_NO_THROW(validate_level(m, disk.width, disk.height));
}

}  // namespace
}  // namespace subvec
