// Vectorization stages on synthetic images whose answer is known, and the whole pipeline on the
// shared photographs (../shared/images, skipped with a message when absent).
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <functional>
#include <set>
#include <string>
#include <vector>
#include <utility>

#include "subvec/core/error.h"
#include "subvec/core/metrics.h"
#include "subvec/io/image_io.h"
#include "subvec/mesh/topology.h"
#include "subvec/mesh/validate.h"
#include "subvec/render/renderer.h"
#include "subvec/subdiv/subdivision.h"
#include "subvec/vectorize/vectorize.h"
#include "support/shared_photos.h"

namespace subvec {
namespace {

// A disk of radius r at (cx, cy) over a horizontal gradient, anti-aliased by 8x8 supersampling.
Image8 disk_image(int w, int h, double cx, double cy, double r) {
  Image8 img(w, h, 3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      double inside = 0;
      for (int sy = 0; sy < 8; ++sy)
        for (int sx = 0; sx < 8; ++sx)
          inside += std::hypot(x + (sx + 0.5) / 8 - cx, y + (sy + 0.5) / 8 - cy) < r ? 1.0 / 64 : 0;
      const double bg[3] = {40 + 120.0 * x / w, 60.0, 200 - 100.0 * x / w};
      const double fg[3] = {230, 200 - 60.0 * y / h, 40};
      uint8_t* p = img.row(y) + 3 * x;
      for (int k = 0; k < 3; ++k) p[k] = static_cast<uint8_t>(std::lround(inside * fg[k] + (1 - inside) * bg[k]));
    }
  }
  return img;
}

TEST(Features, FindsTheDiskBoundaryAtSubpixelAccuracy) {
  const double cx = 40.3, cy = 37.6, r = 21.4;
  const Image8 img = disk_image(80, 72, cx, cy, r);
  const auto features = detect_features(img);
  ASSERT_EQ(features.size(), 1u);
  EXPECT_TRUE(features[0].closed());
  EXPECT_NEAR(features[0].length, 2 * M_PI * r, 0.05 * 2 * M_PI * r);
  double worst = 0;
  for (const Vec2& p : features[0].points) worst = std::max(worst, std::abs(std::hypot(p.x - cx, p.y - cy) - r));
  EXPECT_LT(worst, 0.35);
}

TEST(Features, FlatAndNoisyImagesHaveNoFeatures) {
  Image8 flat(64, 48, 3);
  std::fill(flat.pixels.begin(), flat.pixels.end(), uint8_t{128});
  EXPECT_TRUE(detect_features(flat).empty());
  Image8 noise(64, 48, 3);
  uint32_t state = 12345;
  for (uint8_t& p : noise.pixels) {
    state = state * 1664525u + 1013904223u;
    p = static_cast<uint8_t>(120 + (state >> 29));  // +-4 gray levels of noise
  }
  EXPECT_TRUE(detect_features(noise).empty());
}

TEST(InitialMesh, IsValidAndFollowsTheFeatures) {
  const Image8 img = disk_image(64, 64, 31.7, 32.2, 17.3);
  const auto features = detect_features(img);
  const ControlMesh mesh = build_initial_mesh(img, features);
  const MeshTopology topo = validate_level(mesh, 64, 64);
  ASSERT_EQ(mesh.features.size(), 1u);
  EXPECT_TRUE(mesh.features[0].closed());
  // Roughly one vertex per pixel, plus the border and the feature, minus what the feature displaced.
  EXPECT_GT(mesh.num_vertices(), 64 * 64 * 9 / 10);
  EXPECT_LT(mesh.num_vertices(), 64 * 64 + 4 * 64 + 200);
  // Each tear vertex has two colors: the disk's on one side, the background's on the other.
  int split = 0;
  for (VertexTag tag : topo.vertex_tags) split += tag == VertexTag::kTear;
  EXPECT_EQ(mesh.num_colors(), mesh.num_vertices() + split);
  int num_colors = 0;
  EXPECT_EQ(face_varying_indices(mesh, topo, num_colors), mesh.triangle_colors);
  EXPECT_EQ(num_colors, mesh.num_colors());
}

// The dense mesh reads its color values off the triangulation; they must be the ones the
// topology implies, also where features meet and cross (many do on the astronaut).
TEST(InitialMesh, ColorValuesAreTheTopologysOnAPhotograph) {
  const auto path = std::filesystem::path(SUBVEC_SOURCE_DIR) / ".." / "shared" / "images" / "astronaut.png";
  if (const auto why = test::skip_shared_photos(path)) GTEST_SKIP() << *why;
  const Image8 img = read_image(path);
  const ControlMesh mesh = build_initial_mesh(img, detect_features(img));
  const MeshTopology topo = validate_level(mesh, img.width, img.height);
  ASSERT_GT(mesh.features.size(), 100u);
  int num_colors = 0;
  EXPECT_EQ(face_varying_indices(mesh, topo, num_colors), mesh.triangle_colors);
  EXPECT_EQ(num_colors, mesh.num_colors());
}

// Distance from p to the polyline.
double polyline_distance(const Vec2& p, const std::vector<Vec2>& line) {
  double best = 1e30;
  for (size_t i = 0; i + 1 < line.size(); ++i) {
    const Vec2 a = line[i], b = line[i + 1];
    const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
    const double t = len2 > 0 ? std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / len2, 0.0, 1.0) : 0;
    best = std::min(best, std::hypot(p.x - a.x - t * dx, p.y - a.y - t * dy));
  }
  return best;
}

TEST(InitialMesh, CoarseGridKeepsPixelCentresNearFeaturesOnly) {
  const Image8 img = disk_image(96, 96, 47.7, 48.2, 25.3);
  const auto features = detect_features(img);
  InitialMeshOptions fine, coarse;
  fine.grid_step = 1;
  coarse.grid_step = 2;
  coarse.fine_band = 3;
  const ControlMesh a = build_initial_mesh(img, features, fine);
  const ControlMesh b = build_initial_mesh(img, features, coarse);
  validate_level(b, 96, 96);
  ASSERT_EQ(b.features.size(), 1u);
  EXPECT_EQ(b.features[0].vertices.size(), a.features[0].vertices.size());
  // Interior vertices: pixel centres (x.5, y.5) within the band of the circle, block centres
  // (whole coordinates) at least 2.2 px away from it, and far fewer of them than with step 1.
  int centres = 0, corners = 0;
  for (const Vec2& p : b.positions) {
    if (p.x <= 0 || p.y <= 0 || p.x >= 96 || p.y >= 96) continue;
    const double d = std::abs(std::hypot(p.x - 47.7, p.y - 48.2) - 25.3);
    if (p.x == std::floor(p.x) && p.y == std::floor(p.y)) {
      ++corners;
      EXPECT_GT(d, 2.2) << p.x << ", " << p.y;
    } else if (p.x - std::floor(p.x) == 0.5 && p.y - std::floor(p.y) == 0.5) {
      ++centres;
      EXPECT_LT(d, 4.6) << p.x << ", " << p.y;
    }
  }
  EXPECT_GT(corners, 1000);
  EXPECT_GT(centres, 500);
  EXPECT_LT(b.num_vertices(), a.num_vertices() * 6 / 10);
  // A block centre's color is its 2 x 2 block's mean.
  int checked = 0;
  for (int f = 0; f < b.num_triangles(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const Vec2 p = b.positions[b.triangles[f][k]];
      if (p.x != 21 || p.y != 21) continue;  // the block of pixels 20..21 x 20..21
      const Color c = b.colors[b.triangle_colors[f][k]];
      for (int ch = 0; ch < 3; ++ch) {
        double mean = 0;
        for (int y = 20; y <= 21; ++y)
          for (int x = 20; x <= 21; ++x) mean += img.row(y)[3 * x + ch] / 4.0;
        EXPECT_NEAR((&c.r)[ch], mean, 1e-3);
      }
      ++checked;
    }
  }
  EXPECT_GT(checked, 0);
  // Steps 4 and 8 with the default band: a quadtree whose blocks shrink toward the circle. Every
  // interior vertex off the circle is a pixel centre or the centre of an aligned block of 2, 4 or
  // 8 pixels that stays clear of the circle (no pixel centre in it within the band, the centre
  // itself at least min_grid_distance from the detected polyline), and each coarser step has fewer vertices.
  int previous = b.num_vertices();
  for (const int step : {4, 8}) {
    SCOPED_TRACE(step);
    InitialMeshOptions coarser;
    coarser.grid_step = step;
    const ControlMesh c = build_initial_mesh(img, features, coarser);
    validate_level(c, 96, 96);
    ASSERT_EQ(features.size(), 1u);
    ASSERT_EQ(c.features.size(), 1u);
    EXPECT_EQ(c.features[0].vertices.size(), a.features[0].vertices.size());
    EXPECT_LT(c.num_vertices(), previous * 8 / 10);
    previous = c.num_vertices();
    std::set<int32_t> on_feature(c.features[0].vertices.begin(), c.features[0].vertices.end());
    std::array<int, 4> sizes{};  // block centres of 2, 4, 8 px; pixel centres
    for (int32_t v = 0; v < c.num_vertices(); ++v) {
      const Vec2 p = c.positions[v];
      if (on_feature.count(v) || p.x <= 0 || p.y <= 0 || p.x >= 96 || p.y >= 96) continue;
      const auto distance = [&](double x, double y) { return polyline_distance({x, y}, features[0].points); };
      if (p.x - std::floor(p.x) == 0.5 && p.y - std::floor(p.y) == 0.5) {
        EXPECT_GE(distance(p.x, p.y), coarser.min_grid_distance - 1e-9);
        ++sizes[3];
        continue;
      }
      // The largest aligned block this centre can be of.
      int s = 0;
      for (int t = step; t >= 2 && !s; t /= 2)
        if (std::fmod(p.x - t / 2, t) == 0 && std::fmod(p.y - t / 2, t) == 0) s = t;
      ASSERT_GT(s, 0) << p.x << ", " << p.y;
      ++sizes[s == 2 ? 0 : s == 4 ? 1 : 2];
      EXPECT_GE(distance(p.x, p.y), coarser.min_grid_distance) << p.x << ", " << p.y;
      for (double y = p.y - s / 2 + 0.5; y < p.y + s / 2; ++y)
        for (double x = p.x - s / 2 + 0.5; x < p.x + s / 2; ++x)
          ASSERT_GE(distance(x, y), coarser.fine_band) << p.x << ", " << p.y << " (block of " << s << ")";
    }
    EXPECT_GT(sizes[0], 0);
    EXPECT_GT(sizes[1], 0);
    if (step == 8) {
      EXPECT_GT(sizes[2], 0);
    }
  }
  // A feature along the pixel edges x = 30 passes no pixel centre closer than 0.5 px, but through
  // the centre of every 4 x 4 block of columns 28..31: those blocks are split, and no grid point
  // lands on the feature.
  DetectedFeature edge;
  for (int y = 6; y <= 90; ++y) edge.points.push_back({30.0, y + 0.5});
  edge.length = 84;
  InitialMeshOptions on_edges;
  on_edges.grid_step = 4;
  const ControlMesh e = build_initial_mesh(img, {edge}, on_edges);
  validate_level(e, 96, 96);
  ASSERT_EQ(e.features.size(), 1u);
  std::set<int32_t> edge_vertices(e.features[0].vertices.begin(), e.features[0].vertices.end());
  EXPECT_EQ(edge_vertices.size(), edge.points.size());
  for (int32_t v = 0; v < e.num_vertices(); ++v) {
    if (edge_vertices.count(v)) continue;
    EXPECT_GE(polyline_distance(e.positions[v], edge.points), on_edges.min_grid_distance)
        << e.positions[v].x << ", " << e.positions[v].y;
  }
  for (const int bad_step : {3, 6, 16, -1}) {
    InitialMeshOptions bad;
    bad.grid_step = bad_step;
    EXPECT_THROW(build_initial_mesh(img, features, bad), Error) << bad_step;
  }
}

// The limit feature curves of a mesh as refined polylines (depth 4), one list of segments each.
std::vector<std::array<Vec2, 2>> limit_tear_segments(const ControlMesh& mesh, int w, int h) {
  const MeshTopology topo = MeshTopology::build(mesh, w, h);
  const Subdivision sub(mesh, topo, 4);
  RefinedMesh r;
  sub.evaluate(mesh.positions, mesh.colors, r);
  std::vector<std::array<Vec2, 2>> out;
  for (const EdgeVerts& e : r.tear_edges) {
    out.push_back({Vec2{r.positions[2 * e[0]], r.positions[2 * e[0] + 1]},
                   Vec2{r.positions[2 * e[1]], r.positions[2 * e[1] + 1]}});
  }
  return out;
}

// Checks the invariants every vectorization must keep and returns the rendered MAE.
double check_vectorization(const Image8& img, const VectorizeOptions& options, const char* name) {
  VectorizeReport report;
  VectorizeOptions one_level = options;  // level 0 is checked here; the levels in tests/unit/pyramid
  one_level.levels.levels = 1;
  const VectorImage v = vectorize(img, one_level, &report);
  EXPECT_NO_THROW(validate(v)) << name;
  const ControlMesh& mesh = v.levels[0];
  // No flipped or degenerate triangle.
  for (const Tri& t : mesh.triangles) {
    const Vec2 a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
    EXPECT_GT((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x), 1e-4) << name;
  }
  // Every detected point of every kept feature lies within 1 px of the limit feature curves.
  const auto segments = limit_tear_segments(mesh, img.width, img.height);
  std::vector<Vec2> curve;
  double worst = 0;
  for (const auto& target : report.feature_targets) {
    for (const Vec2& p : target) {
      double best = 1e30;
      for (const auto& s : segments) best = std::min(best, polyline_distance(p, {s[0], s[1]}));
      worst = std::max(worst, best);
    }
  }
  // The simplifier bounds the parametric distance to the exact limit curve by 1 px; the depth-4
  // chords measured here sag inside the curve by up to ~len^2 * curvature / 8, a few thousandths
  // of a pixel for these curves.
  EXPECT_LE(worst, 1.005) << name;
  RenderOptions ro;
  const Image8 rendered = render(v, ro);
  return compare(img, rendered).mae_mean;
}

TEST(Vectorize, DiskIsReproducedWithATearOnItsBoundary) {
  const Image8 img = disk_image(96, 80, 47.2, 38.9, 24.6);
  VectorizeOptions options;
  options.vertices = 120;
  const double mae = check_vectorization(img, options, "disk");
  EXPECT_LT(mae, 2.0);
}

TEST(Vectorize, IsDeterministic) {
  const Image8 img = disk_image(64, 64, 30.2, 33.1, 18.4);
  VectorizeOptions options;
  options.vertices = 80;
  const VectorImage a = vectorize(img, options), b = vectorize(img, options);
  ASSERT_EQ(a.levels[0].num_vertices(), b.levels[0].num_vertices());
  EXPECT_EQ(a.levels[0].positions, b.levels[0].positions);
  EXPECT_EQ(a.levels[0].colors, b.levels[0].colors);
  EXPECT_EQ(a.levels[0].triangles, b.levels[0].triangles);
}

TEST(Vectorize, IdenticalForAnyThreadCount) {
  // Regions are simplified in parallel first, and the fit assembles its rows in parallel; neither
  // result may depend on the schedule.
  const Image8 img = disk_image(160, 128, 70.3, 61.8, 37.5);
  const ControlMesh dense = build_initial_mesh(img, detect_features(img));
  std::vector<ControlMesh> out;
  for (int threads : {1, 2, 3}) {
    ControlMesh mesh = dense;
    SimplifyOptions options;
    options.target_vertices = 150;
    options.threads = threads;
    simplify(mesh, img.width, img.height, options);
    EXPECT_NO_THROW(validate_level(mesh, img.width, img.height));
    EXPECT_EQ(mesh.num_vertices(), 150);
    ColorFitOptions fit;
    fit.threads = threads;
    fit.l1_iterations = 1;  // the reweighted solve too
    fit_colors(mesh, img.width, img.height, img, fit);
    out.push_back(std::move(mesh));
  }
  for (size_t i = 1; i < out.size(); ++i) {
    EXPECT_EQ(out[i].positions, out[0].positions);
    EXPECT_EQ(out[i].colors, out[0].colors);
    EXPECT_EQ(out[i].triangles, out[0].triangles);
    EXPECT_EQ(out[i].triangle_colors, out[0].triangle_colors);
  }
}

TEST(Vectorize, PixelFitBeatsVertexFitAndErrorFallsWithRatio) {
  const Image8 img = disk_image(96, 96, 44.0, 50.5, 27.5);
  VectorizeOptions pixel_fit;
  pixel_fit.vertices = 90;
  VectorizeOptions vertex_fit = pixel_fit;
  vertex_fit.fit.target = ColorFitTarget::kRefinedVertices;
  const double pixel_mae = compare(img, render(vectorize(img, pixel_fit), {})).mae_mean;
  const double vertex_mae = compare(img, render(vectorize(img, vertex_fit), {})).mae_mean;
  EXPECT_LT(pixel_mae, vertex_mae);
  VectorizeOptions finer = pixel_fit;
  finer.vertices = 400;
  EXPECT_LT(compare(img, render(vectorize(img, finer), {})).mae_mean, pixel_mae);
}

// The reweighted (least absolute deviations) fit shrugs off sparse outliers that pull a plain
// least-squares fit: against the clean picture it is closer, and against the noisy one its mean
// absolute error, the measure it targets, is lower too.
TEST(ColorFit, ReweightingResistsOutliers) {
  const Image8 clean = disk_image(96, 96, 44.0, 50.5, 27.5);
  Image8 noisy = clean;
  uint32_t state = 12345;
  for (size_t i = 0; i < noisy.pixels.size(); i += 3) {
    state = state * 1664525u + 1013904223u;
    if (state >> 28 != 0) continue;  // 1 pixel in 16 becomes white or black
    const uint8_t v = (state >> 27) & 1 ? 255 : 0;
    noisy.pixels[i] = noisy.pixels[i + 1] = noisy.pixels[i + 2] = v;
  }
  ControlMesh mesh = build_initial_mesh(clean, detect_features(clean));
  SimplifyOptions simplify_options;
  simplify_options.target_vertices = 120;
  simplify(mesh, clean.width, clean.height, simplify_options);
  auto fit = [&](int iterations) {
    VectorImage image;
    image.width = clean.width, image.height = clean.height;
    image.levels.push_back(mesh);
    ColorFitOptions options;
    options.l1_iterations = iterations;
    fit_colors(image.levels[0], clean.width, clean.height, noisy, options);
    return render(image, {});
  };
  const Image8 plain = fit(0), reweighted = fit(4);
  EXPECT_LT(compare(clean, reweighted).mae_mean, 0.7 * compare(clean, plain).mae_mean);
  EXPECT_LT(compare(noisy, reweighted).mae_mean, compare(noisy, plain).mae_mean);
  ColorFitOptions bad;
  bad.l1_iterations = -1;
  EXPECT_THROW(fit_colors(mesh, clean.width, clean.height, noisy, bad), Error);
}

// A w x h crop of the bundled photograph (examples/04-rocket.png) from (x, y).
Image8 rocket_crop(int x, int y, int w, int h) {
  const Image8 photo = read_image(std::filesystem::path(SUBVEC_SOURCE_DIR) / "examples" / "04-rocket.png");
  Image8 crop(w, h, 3);
  for (int row = 0; row < h; ++row) std::copy_n(photo.row(row + y) + 3 * x, 3 * w, crop.row(row));
  return crop;
}

// The fit refines one level coarser than the renderer draws (kFitEdgePixels, docs/vectorize.md "Fit
// depth"): its refined edges average at most 5 px, and the rendered image is within 1 % of the one
// fitted at the renderer's depth, on a crop of the bundled photograph.
TEST(ColorFit, OneLevelCoarserThanTheRendererCostsUnderOnePercent) {
  const Image8 crop = rocket_crop(100, 60, 200, 160);
  VectorizeOptions options;
  options.ratio = 0.01;
  VectorImage image = vectorize(crop, options);
  const int depth = default_fit_depth(image.levels[0]);
  ASSERT_GE(depth, 1);
  double total = 0;
  int count = 0;
  for (const Tri& t : image.levels[0].triangles) {
    for (int k = 0; k < 3; ++k) {
      const Vec2 a = image.levels[0].positions[t[k]], b = image.levels[0].positions[t[(k + 1) % 3]];
      total += std::hypot(b.x - a.x, b.y - a.y), ++count;
    }
  }
  const double refined_edge = total / count / std::pow(2.0, depth);
  EXPECT_LE(refined_edge, kFitEdgePixels);
  EXPECT_GT(refined_edge, kFitEdgePixels / 2);  // one level less would be over the limit
  auto rendered_error = [&](int fit_depth) {
    VectorImage fitted = image;
    ColorFitOptions fit;
    fit.depth = fit_depth;
    fit_colors(fitted.levels[0], crop.width, crop.height, crop, fit);
    return compare(crop, render(fitted, {})).mae_mean;
  };
  const double coarse = rendered_error(depth), fine = rendered_error(depth + 1);
  EXPECT_LT(coarse, 1.01 * fine) << "fit depth " << depth << ": " << coarse << ", one deeper: " << fine;
}

// Relocation moves smooth control vertices only, keeps the mesh valid, lowers the squared pixel
// error, and does not depend on the thread count: on a 160 x 120 crop of the bundled photograph.
TEST(ColorFit, RelocationLowersTheErrorAndMovesOnlySmoothVertices) {
  const Image8 crop = rocket_crop(110, 70, 160, 120);
  VectorizeOptions options;
  options.ratio = 0.02;
  options.refine.rounds = 0;  // relocation on the simplified mesh, as it was measured
  const VectorImage plain = vectorize(crop, options);
  const ControlMesh& before = plain.levels[0];
  auto relocated = [&](int threads, ColorFitStats& stats) {
    ControlMesh mesh = before;
    ColorFitOptions fit;
    fit.relocate_iterations = 4;
    fit.threads = threads;
    stats = fit_colors(mesh, crop.width, crop.height, crop, fit);
    return mesh;
  };
  ColorFitStats unmoved, moved, moved1;
  ControlMesh refit = before;
  unmoved = fit_colors(refit, crop.width, crop.height, crop, {});
  const ControlMesh after = relocated(0, moved);
  EXPECT_GT(moved.relocations, 0);
  EXPECT_LT(moved.rms, 0.99 * unmoved.rms);
  EXPECT_NO_THROW(validate_level(after, crop.width, crop.height));
  const MeshTopology topo = MeshTopology::build(before, crop.width, crop.height);
  int shifted = 0;
  for (int v = 0; v < before.num_vertices(); ++v) {
    const bool same = after.positions[v].x == before.positions[v].x && after.positions[v].y == before.positions[v].y;
    if (topo.vertex_tags[v] != VertexTag::kSmooth) {
      EXPECT_TRUE(same) << "vertex " << v << " is not smooth";
    }
    shifted += !same;
  }
  EXPECT_GT(shifted, before.num_vertices() / 10);
  const ControlMesh one_thread = relocated(1, moved1);
  EXPECT_EQ(one_thread.positions, after.positions);
  EXPECT_EQ(one_thread.colors, after.colors);
  for (auto set : {+[](ColorFitOptions& o) { o.relocate_iterations = -1; }, +[](ColorFitOptions& o) { o.relocate_max_step = 0; },
                   +[](ColorFitOptions& o) { o.relocate_cg_iterations = 0; }}) {
    ColorFitOptions bad;
    set(bad);
    ControlMesh mesh = before;
    EXPECT_THROW(fit_colors(mesh, crop.width, crop.height, crop, bad), Error);
  }
}

TEST(Vectorize, RejectsBadOptions) {
  const Image8 img = disk_image(32, 32, 16, 16, 8);
  VectorizeOptions options;
  options.ratio = 0;
  EXPECT_THROW(vectorize(img, options), Error);
  options.ratio = 1.5;
  EXPECT_THROW(vectorize(img, options), Error);
  options.ratio = -0.1;
  EXPECT_THROW(vectorize(img, options), Error);
  EXPECT_THROW(vectorize(Image8(1, 1, 3), {}), Error);
}

// validate() holds every range of the job's options, with one message naming the field (the front
// ends replace the name by their flag or keyword, and test that).
TEST(Vectorize, ValidateNamesTheOptionOutOfRange) {
  EXPECT_NO_THROW(validate(VectorizeOptions{}));
  auto message = [](const std::function<void(VectorizeOptions&)>& set) {
    VectorizeOptions options;
    set(options);
    try {
      validate(options);
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message([](VectorizeOptions& o) { o.ratio = 2; }), "ratio must be in (0, 1], got 2");
  EXPECT_EQ(message([](VectorizeOptions& o) { o.ratio = std::nan(""); }), "ratio must be in (0, 1], got nan");
  EXPECT_EQ(message([](VectorizeOptions& o) { o.vertices = 3; }),
            "vertices must be 0 (use ratio) or in [4, 67108864], got 3");
  EXPECT_EQ(message([](VectorizeOptions& o) { o.features.high_quantile = 1; }),
            "features.high_quantile must be in [0.01, 0.999], got 1");
  EXPECT_EQ(message([](VectorizeOptions& o) { o.refine.rounds = -1; }), "refine.rounds must be in [0, 50], got -1");
  EXPECT_EQ(message([](VectorizeOptions& o) { o.fit.relocate_iterations = 51; }),
            "fit.relocate_iterations must be in [0, 50], got 51");
  EXPECT_EQ(message([](VectorizeOptions& o) { o.levels.levels = 0; }), "levels.levels must be in [1, 16], got 0");
  EXPECT_EQ(message([](VectorizeOptions& o) { o.levels.reduction = 1; }),
            "levels.reduction must be in [0.01, 0.95], got 1");
  EXPECT_EQ(message([](VectorizeOptions& o) { o.threads = -1; }), "threads must be in [0, 1024], got -1");
}

// The cancel flag stops the job at its next check (here inside refine, cancel_test.cpp) with a
// typed error; the progress callback hears of every stage before it, in vectorize_stages() order,
// and of none after.
TEST(Vectorize, CancelStopsAtTheNextStage) {
  const Image8 img = disk_image(64, 64, 31.7, 32.2, 17.3);
  std::atomic<bool> cancel{false};
  std::vector<std::string> seen;
  VectorizeOptions options;
  options.cancel = &cancel;
  options.progress = [&](const std::string& stage, double) {
    seen.push_back(stage);
    if (stage == "refine") cancel = true;
  };
  try {
    vectorize(img, options);
    ADD_FAILURE() << "not cancelled";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kCancelled);
  }
  EXPECT_EQ(seen, (std::vector<std::string>{"features", "mesh", "simplify", "refine"}));
  // Uncancelled, every stage reports, levels included, then "done".
  cancel = false;
  seen.clear();
  options.progress = [&](const std::string& stage, double) { seen.push_back(stage); };
  const VectorImage v = vectorize(img, options);
  EXPECT_EQ(seen, (std::vector<std::string>{"features", "mesh", "simplify", "refine", "fit", "levels", "done"}));
  EXPECT_EQ(static_cast<int>(v.levels.size()), LevelOptions{}.levels);
}

// The coarse grids that large images start from (2 and 4 px) give the same error as the pixel
// grid (MAE 3.18, 3.18 and 3.12): checked on the 2x upscale of a shared photograph's 256 x 256
// crop, with the invariants of every vectorization. (Automatic from 2^18 and 2^21 pixels; forced
// here to keep the test short.)
TEST(Vectorize, CoarseGridMatchesThePixelGridOnAnUpscaledPhotograph) {
  const std::filesystem::path path =
      std::filesystem::path(SUBVEC_SOURCE_DIR) / ".." / "shared" / "images" / "astronaut.png";
  if (const auto why = test::skip_shared_photos(path)) GTEST_SKIP() << *why;
  const Image8 photo = read_image(path);
  constexpr int kSize = 512, kScale = 2;
  Image8 img(kSize, kSize, 3);
  for (int y = 0; y < kSize; ++y) {
    for (int x = 0; x < kSize; ++x) {
      // Bilinear upscale of the crop at (128, 64).
      const double sx = std::clamp((x + 0.5) / kScale - 0.5, 0.0, 255.0);
      const double sy = std::clamp((y + 0.5) / kScale - 0.5, 0.0, 255.0);
      const int x0 = std::min(int(sx), 254), y0 = std::min(int(sy), 254);
      const double fx = sx - x0, fy = sy - y0;
      for (int k = 0; k < 3; ++k) {
        auto at = [&](int px, int py) { return double(photo.row(64 + py)[3 * (128 + px) + k]); };
        img.row(y)[3 * x + k] = static_cast<uint8_t>(std::lround(
            (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
            fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1))));
      }
    }
  }
  VectorizeOptions options;
  options.ratio = 0.01;
  options.initial_mesh.grid_step = 1;
  const double fine = check_vectorization(img, options, "upscale, step 1");
  options.initial_mesh.grid_step = 2;
  const double coarse = check_vectorization(img, options, "upscale, step 2");
  EXPECT_LT(coarse, fine * 1.03) << "step 1: " << fine << ", step 2: " << coarse;
  for (const int step : {4, 8}) {
    options.initial_mesh.grid_step = step;
    const double coarser = check_vectorization(img, options, ("upscale, step " + std::to_string(step)).c_str());
    EXPECT_LT(coarser, fine * 1.03) << "step 1: " << fine << ", step " << step << ": " << coarser;
  }
}

// A bilinear upscale by an integer factor (pixel centres mapped onto pixel centres).
Image8 upscale(const Image8& photo, int scale) {
  Image8 out(photo.width * scale, photo.height * scale, 3);
  for (int y = 0; y < out.height; ++y) {
    const double sy = std::clamp((y + 0.5) / scale - 0.5, 0.0, photo.height - 1.0);
    const int y0 = std::min(int(sy), photo.height - 2);
    const double fy = sy - y0;
    for (int x = 0; x < out.width; ++x) {
      const double sx = std::clamp((x + 0.5) / scale - 0.5, 0.0, photo.width - 1.0);
      const int x0 = std::min(int(sx), photo.width - 2);
      const double fx = sx - x0;
      for (int k = 0; k < 3; ++k) {
        auto at = [&](int px, int py) { return double(photo.row(py)[3 * px + k]); };
        out.row(y)[3 * x + k] = static_cast<uint8_t>(std::lround(
            (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
            fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1))));
      }
    }
  }
  return out;
}

// Vectorizes at a vertex budget and checks that it holds (within 2 %; the collapses stop at it) and
// what the report says of it.
VectorizeReport check_budget(const Image8& photo, int vertices, const std::string& what) {
  VectorizeOptions options;
  options.vertices = vertices;
  options.levels.levels = 1;
  VectorizeReport report;
  const VectorImage v = vectorize(photo, options, &report);
  EXPECT_NO_THROW(validate(v)) << what;
  EXPECT_EQ(v.levels[0].num_vertices(), report.vertices) << what;
  EXPECT_LE(report.vertices, vertices) << what;
  EXPECT_GE(report.vertices, 0.98 * vertices) << what;
  EXPECT_EQ(report.target_vertices, vertices) << what;
  EXPECT_GE(report.feature_tolerance, options.max_feature_error) << what;
  EXPECT_LE(report.feature_tolerance, 3 * options.max_feature_error) << what;
  EXPECT_EQ(report.feature_targets.size(), v.levels[0].features.size()) << what;
  return report;
}

// Butterfly's 160 features need about 1,240 vertices at 1 px: below that the budget loosens the
// chains to 3 px, then drops the least salient features, rather than return more vertices than
// asked (before: 1,250 for --vertices 300, 1,237 for 1,000). Its 4x upscale has 1,127 features.
TEST(Vectorize, TheVertexBudgetHoldsOnAFeatureRichPhotograph) {
  const std::filesystem::path path = test::shared_photos() / "butterfly.png";
  if (const auto why = test::skip_shared_photos(path)) GTEST_SKIP() << *why;
  const Image8 photo = read_image(path);
  const VectorizeReport few = check_budget(photo, 300, "300");
  EXPECT_GT(few.features_dropped, 0);
  EXPECT_GT(few.features, 0);  // the most salient stay
  const VectorizeReport some = check_budget(photo, 1000, "1000");
  EXPECT_EQ(some.features_dropped, 0);  // loosening was enough
  EXPECT_GT(some.feature_tolerance, 1);
  const VectorizeReport enough = check_budget(photo, 2000, "2000");
  EXPECT_EQ(enough.features_dropped, 0);
  EXPECT_EQ(enough.feature_tolerance, 1);
  const VectorizeReport large = check_budget(upscale(photo, 4), 2000, "4x upscale, 2000");
  EXPECT_GT(large.features_dropped, 0);
}

// The smallest budget validate() lets through, the image's four corners, holds too: the tear goes,
// and the simplifier takes what half-edge collapses cannot (they stop at 10 on rocket).
TEST(Vectorize, TheSmallestBudgetIsTheFrame) {
  const Image8 photo =
      read_image(std::filesystem::path(SUBVEC_SOURCE_DIR) / "examples" / "04-rocket.png");
  const VectorizeReport r = check_budget(photo, 4, "4");
  EXPECT_EQ(r.vertices, 4);
  EXPECT_EQ(r.features, 0);
  EXPECT_GT(r.features_dropped, 0);
}

// The shared photographs: valid meshes, no flips, feature curves within 1 px of the detected
// features, and at ratio 0.01 at most 0.92 x the error of the plain baseline of issue 3 (an
// adaptive Delaunay mesh with linearly interpolated least-squares colors; docs/quality.md).
TEST(Vectorize, SharedPhotographs) {
  const std::filesystem::path dir = std::filesystem::path(SUBVEC_SOURCE_DIR) / ".." / "shared" / "images";
  if (const auto why = test::skip_shared_photos(dir)) GTEST_SKIP() << *why;
  const std::pair<const char*, double> baseline[] = {{"astronaut", 10.1}, {"chelsea", 7.3}, {"rocket", 4.9},
                                                     {"fruits", 7.8},     {"butterfly", 20.3}, {"home", 9.1},
                                                     {"squirrel", 9.7},   {"apple", 5.2}};
  int count = 0;
  for (const auto& [name, baseline_mae] : baseline) {
    const auto path = dir / (std::string(name) + ".png");
    if (!std::filesystem::exists(path)) continue;
    const Image8 img = read_image(path);
    VectorizeOptions options;
    options.ratio = 0.01;
    const double mae = check_vectorization(img, options, name);
    EXPECT_LE(mae, 0.92 * baseline_mae) << name;
    ++count;
  }
  EXPECT_GT(count, 0);
}

}  // namespace
}  // namespace subvec
