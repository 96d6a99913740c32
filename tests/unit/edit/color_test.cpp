// Selection and color editing (edit/selection.h, edit/color.h): BLEND and TRANSFORM keep what
// they promise, and the two sides of a tear are selected and edited separately.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
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

// A region (a fill) from a click inside the torn disk is the inside, from outside the outside,
// whatever the tolerance: the closed tear stops it.
TEST(ColorSelection, RegionStopsAtATear) {
  const TestMesh disk = testing::torn_disk();
  const ControlMesh& m = disk.mesh;
  const std::set<int> inside = side_colors(m, true), outside = side_colors(m, false);
  const Vec2 centre = m.positions[0];
  for (const double tolerance : {1e3, 1e9}) {
    const ColorSelection in = select_region_colors(m, {centre.x + 0.5, centre.y + 0.3},
                                                   std::numeric_limits<double>::infinity(), tolerance);
    EXPECT_EQ(std::set<int>(in.colors.begin(), in.colors.end()), inside);
    const ColorSelection out = select_region_colors(m, {1, 1}, std::numeric_limits<double>::infinity(), tolerance);
    EXPECT_EQ(std::set<int>(out.colors.begin(), out.colors.end()), outside);
  }
}

// Without tears, the tolerance is what stops a region: a grid whose left columns are black and the
// rest grey 50 (CIELAB distance 20.8 from black, RGB distance 87). Tolerance 20 keeps to the black
// (the values the fill can reach through black ones), 22 takes the grey too. The radius caps it
// around the click.
TEST(ColorSelection, RegionFollowsTheToleranceInCielabAndTheRadius) {
  TestMesh grid = testing::grid_mesh(8, 6, 4, true);
  ControlMesh& m = grid.mesh;
  std::vector<int32_t> column(m.num_colors());
  for (int f = 0; f < m.num_triangles(); ++f)
    for (int k = 0; k < 3; ++k) column[m.triangle_colors[f][k]] = int(std::lround(m.positions[m.triangles[f][k]].x / 4));
  std::set<int> black;
  for (int c = 0; c < m.num_colors(); ++c) {
    m.colors[c] = column[c] <= 3 ? Color{0, 0, 0} : Color{50, 50, 50};
    if (column[c] <= 3) black.insert(c);
  }
  const Vec2 at{5, 11};
  const double none = std::numeric_limits<double>::infinity();
  const ColorSelection tight = select_region_colors(m, at, none, 20);
  EXPECT_EQ(std::set<int>(tight.colors.begin(), tight.colors.end()), black);
  EXPECT_EQ(select_region_colors(m, at, none, 22).colors.size(), size_t(m.num_colors()));
  // Capped at 6 px: only values within 6 px of the click, and all of the black ones there.
  const ColorSelection capped = select_region_colors(m, at, 6, 1e3);
  ASSERT_FALSE(capped.colors.empty());
  for (int c : capped.colors) {
    int v = -1;
    for (int f = 0; f < m.num_triangles() && v < 0; ++f)
      for (int k = 0; k < 3; ++k)
        if (m.triangle_colors[f][k] == c) v = m.triangles[f][k];
    EXPECT_LE(std::hypot(m.positions[v].x - at.x, m.positions[v].y - at.y), 6.0);
  }
  EXPECT_LT(capped.colors.size(), black.size());
  // Through the dispatcher, as the edit ops and the editor call it.
  const MeshTopology topology = grid.topology();
  EXPECT_EQ(select_colors(m, topology, EditSelect::kRegion, at, none, 20).colors, tight.colors);
  EXPECT_THROW(select_region_colors(m, at, none, -1), Error);
  EXPECT_EQ(edit_select_from_name("region"), EditSelect::kRegion);
  EXPECT_EQ(edit_select_from_name("Region"), std::nullopt);
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
