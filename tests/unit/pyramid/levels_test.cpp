// Levels of abstraction (vectorize/levels.h, paper §5): saliency order, nested feature sets, vertex
// counts that halve, overrides, closed seams, and the shared photographs.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "pyramid_test_util.h"
#include "subvec/core/error.h"
#include "subvec/io/image_io.h"
#include "subvec/mesh/topology.h"
#include "subvec/mesh/validate.h"
#include "support/shared_photos.h"

namespace subvec {
namespace {

std::set<int32_t> ids(const ControlMesh& m) {
  std::set<int32_t> out;
  for (const Feature& f : m.features) out.insert(f.id);
  return out;
}

void expect_levels_ok(const VectorImage& image, double tolerance, const std::string& name, bool fewer = true) {
  validate(image);
  for (size_t l = 1; l < image.levels.size(); ++l) {
    const double ratio = double(image.levels[l].num_vertices()) / image.levels[l - 1].num_vertices();
    EXPECT_NEAR(ratio, 0.5, tolerance) << name << " level " << l << ": " << image.levels[l].num_vertices()
                                       << " of " << image.levels[l - 1].num_vertices();
    const auto coarse = ids(image.levels[l]), fine = ids(image.levels[l - 1]);
    EXPECT_TRUE(std::includes(fine.begin(), fine.end(), coarse.begin(), coarse.end())) << name << " level " << l;
    if (fewer) {
      EXPECT_LT(coarse.size(), fine.size()) << name << " level " << l;
    }
  }
}

TEST(Levels, SaliencyGroupsFeaturesUniformly) {
  ControlMesh m;
  for (int i = 0; i < 7; ++i) m.features.push_back({10 + i, {}, 0});
  const std::vector<double> s = {5, 70, 30, 10, 60, 20, 40};
  // Descending: 70 (11), 60 (14), 40 (16) | 30 (12), 20 (15) | 10 (13), 5 (10); groups of 7*l/3.
  const std::vector<int> level = assign_feature_levels(m, s, 3, {});
  EXPECT_EQ(level, (std::vector<int>{0, 2, 1, 0, 2, 1, 2}));
  const std::vector<int> over = assign_feature_levels(m, s, 3, {{10, 2}, {11, 0}});
  EXPECT_EQ(over[0], 2);
  EXPECT_EQ(over[1], 0);
  EXPECT_THROW(assign_feature_levels(m, s, 3, {{99, 1}}), Error);
  EXPECT_THROW(assign_feature_levels(m, s, 3, {{10, 3}}), Error);
  EXPECT_EQ(assign_feature_levels(m, s, 1, {}), std::vector<int>(7, 0));
}

TEST(Levels, SaliencyIsLengthPlusWeightedContrast) {
  // A vertical step of 60 levels in one channel: C = 60 / 2 = 30 levels per pixel across it.
  Image8 img(40, 40, 3);
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 40; ++x) img.row(y)[3 * x] = x < 20 ? 100 : 160;
  const std::vector<Vec2> line = {{20, 5}, {20, 35}};
  EXPECT_NEAR(curve_saliency(line, img, 2), 30 + 2 * 30, 1e-9);
  EXPECT_NEAR(curve_saliency(line, img, 0), 30, 1e-9);
}

TEST(Levels, CountsHalveAndFeatureSetsNest) {
  const Image8 img = test::shapes_image();
  LevelReport report;
  const VectorImage image = test::shapes_levels(img, {}, &report);
  ASSERT_EQ(image.levels.size(), 3u);
  expect_levels_ok(image, 0.025, "shapes");
  // Every feature of level 0 got a saliency and is in exactly the levels its group says.
  ASSERT_EQ(report.feature_level.size(), image.levels[0].features.size());
  for (size_t f = 0; f < image.levels[0].features.size(); ++f) {
    EXPECT_GT(image.levels[0].features[f].saliency, 0);
    for (int l = 0; l < 3; ++l)
      EXPECT_EQ(ids(image.levels[l]).count(image.levels[0].features[f].id), l <= report.feature_level[f] ? 1u : 0u);
  }
  // The most salient feature reaches the coarsest level, the least salient only level 0.
  const auto& fs = image.levels[0].features;
  const auto most = std::max_element(fs.begin(), fs.end(), [](auto& a, auto& b) { return a.saliency < b.saliency; });
  const auto least = std::min_element(fs.begin(), fs.end(), [](auto& a, auto& b) { return a.saliency < b.saliency; });
  EXPECT_EQ(ids(image.levels[2]).count(most->id), 1u);
  EXPECT_EQ(ids(image.levels[1]).count(least->id), 0u);
  // Deterministic.
  const VectorImage again = test::shapes_levels(img);
  for (size_t l = 0; l < 3; ++l) {
    EXPECT_EQ(again.levels[l].positions, image.levels[l].positions);
    EXPECT_EQ(again.levels[l].colors, image.levels[l].colors);
    EXPECT_EQ(again.levels[l].collapses, image.levels[l].collapses);
  }
}

TEST(Levels, OverrideKeepsAFeatureToTheCoarsestLevel) {
  const Image8 img = test::shapes_image();
  const VectorImage plain = test::shapes_levels(img);
  const auto& fs = plain.levels[0].features;
  const auto least = std::min_element(fs.begin(), fs.end(), [](auto& a, auto& b) { return a.saliency < b.saliency; });
  LevelOptions options;
  options.feature_levels = {{least->id, 2}};
  const VectorImage image = test::shapes_levels(img, options);
  expect_levels_ok(image, 0.025, "override", false);  // the override may leave a level all of them
  for (int l = 0; l < 3; ++l) EXPECT_EQ(ids(image.levels[l]).count(least->id), 1u) << l;
  options.feature_levels = {{least->id, 3}};
  EXPECT_THROW(test::shapes_levels(img, options), Error);
}

// After a feature is dropped its former tear vertices have one color: the field is continuous there.
TEST(Levels, MergedTearIsContinuous) {
  const Image8 img = test::shapes_image();
  const VectorImage image = test::shapes_levels(img);
  const ControlMesh& fine = image.levels[0];
  const ControlMesh& coarse = image.levels[1];
  const auto kept = ids(coarse);
  std::set<int32_t> dropped_vertices, kept_vertices;
  for (const Feature& f : fine.features)
    for (int32_t v : f.vertices) (kept.count(f.id) ? kept_vertices : dropped_vertices).insert(v);
  ASSERT_FALSE(dropped_vertices.empty());
  std::vector<std::set<int32_t>> colors_of(coarse.num_vertices());
  for (int f = 0; f < coarse.num_triangles(); ++f)
    for (int k = 0; k < 3; ++k) colors_of[coarse.triangles[f][k]].insert(coarse.triangle_colors[f][k]);
  int checked = 0;
  for (int32_t v = 0; v < coarse.num_vertices(); ++v) {
    const int32_t p = coarse.parent_vertices[v];
    if (!dropped_vertices.count(p) || kept_vertices.count(p)) continue;
    EXPECT_EQ(colors_of[v].size(), 1u) << "vertex " << v << " (level 0 vertex " << p << ")";
    ++checked;
  }
  EXPECT_GT(checked, 0);
  // And no edge of level 1 is a tear unless it belongs to a kept feature.
  const MeshTopology topo = validate_level(coarse, image.width, image.height, 1);
  int tears = 0;
  for (EdgeTag t : topo.edge_tags) tears += t == EdgeTag::kTear;
  int kept_edges = 0;
  for (const Feature& f : coarse.features) kept_edges += static_cast<int>(f.vertices.size()) - 1;
  EXPECT_EQ(tears, kept_edges);
}

TEST(Levels, BadOptions) {
  const Image8 img = test::shapes_image(64, 48);
  VectorizeOptions v;
  v.vertices = 200;
  VectorImage image = vectorize(img, v);
  LevelOptions options;
  options.levels = 0;
  EXPECT_THROW(build_levels(image, img, options), Error);
  options = {};
  options.reduction = 1;
  EXPECT_THROW(build_levels(image, img, options), Error);
  const Image8 other(32, 32, 3);
  EXPECT_THROW(build_levels(image, other, {}), Error);
  // One level: nothing to build, level 0 unchanged.
  options = {};
  options.levels = 1;
  const ControlMesh before = image.levels[0];
  build_levels(image, img, options);
  ASSERT_EQ(image.levels.size(), 1u);
  EXPECT_EQ(image.levels[0].positions, before.positions);
}

// Every shared photograph: counts halve within 5 %, features nest, every level is valid and the
// error rises with the level.
TEST(Levels, SharedPhotographs) {
  const auto dir = test::shared_images();
  if (const auto why = test::skip_shared_photos(dir)) GTEST_SKIP() << *why;
  int count = 0;
  for (const char* name : {"astronaut", "chelsea", "rocket", "fruits", "butterfly", "home", "squirrel", "apple"}) {
    const auto path = dir / (std::string(name) + ".png");
    if (!std::filesystem::exists(path)) continue;
    const Image8 img = read_image(path);
    const VectorImage image = vectorize(img, {});  // the default levels included
    expect_levels_ok(image, 0.025, name);
    ++count;
  }
  EXPECT_GT(count, 0);
}

}  // namespace
}  // namespace subvec
