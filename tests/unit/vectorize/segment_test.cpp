// GrabCut segmentation as a feature source (vectorize/segment.h): the mask, its boundary as
// features, the clearance cut of Canny features, and the whole pipeline with a segment rectangle
// on a synthetic picture and on a shared photograph (skipped when ../shared is absent).
#include "subvec/vectorize/segment.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <opencv2/core.hpp>

#include "subvec/core/error.h"
#include "subvec/io/image_io.h"
#include "subvec/mesh/validate.h"
#include "subvec/vectorize/vectorize.h"
#include "support/shared_photos.h"

namespace subvec {
namespace {

// A disk of radius r at (cx, cy), orange on a blue-green gradient, anti-aliased (8x8 samples).
Image8 disk_image(int w, int h, double cx, double cy, double r) {
  Image8 img(w, h, 3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      double inside = 0;
      for (int sy = 0; sy < 8; ++sy)
        for (int sx = 0; sx < 8; ++sx)
          inside += std::hypot(x + (sx + 0.5) / 8 - cx, y + (sy + 0.5) / 8 - cy) < r ? 1.0 / 64 : 0;
      const double bg[3] = {30 + 40.0 * x / w, 110 + 50.0 * y / h, 170};
      const double fg[3] = {235, 140, 40};
      uint8_t* p = img.row(y) + 3 * x;
      for (int k = 0; k < 3; ++k)
        p[k] = static_cast<uint8_t>(std::lround(inside * fg[k] + (1 - inside) * bg[k]));
    }
  }
  return img;
}

double point_segment_distance(Vec2 p, Vec2 a, Vec2 b) {
  const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
  const double t =
      len2 > 0 ? std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / len2, 0.0, 1.0) : 0.0;
  return std::hypot(p.x - a.x - t * dx, p.y - a.y - t * dy);
}

// The crack boundary of a mask: unit segments between inside and outside pixels (4-neighbours),
// and the image border beside inside pixels.
std::vector<std::array<Vec2, 2>> crack_edges(const RegionMask& m) {
  std::vector<std::array<Vec2, 2>> out;
  auto in = [&](int x, int y) {
    return x >= 0 && y >= 0 && x < m.width && y < m.height && m.at(x, y);
  };
  for (int y = 0; y <= m.height; ++y)
    for (int x = 0; x < m.width; ++x)
      if (in(x, y - 1) != in(x, y))
        out.push_back({Vec2{double(x), double(y)}, Vec2{x + 1.0, double(y)}});
  for (int y = 0; y < m.height; ++y)
    for (int x = 0; x <= m.width; ++x)
      if (in(x - 1, y) != in(x, y))
        out.push_back({Vec2{double(x), double(y)}, Vec2{double(x), y + 1.0}});
  return out;
}

// Nearest-distance queries against a set of segments, bucketed on the pixel grid.
class Segments {
 public:
  explicit Segments(std::vector<std::array<Vec2, 2>> s) : s_(std::move(s)) {
    for (size_t k = 0; k < s_.size(); ++k) {
      const Vec2 mid{(s_[k][0].x + s_[k][1].x) / 2, (s_[k][0].y + s_[k][1].y) / 2};
      cells_[key(mid)].push_back(k);
    }
  }
  // Distance to the nearest segment whose midpoint is within `radius` cells, or 1e9.
  double distance(Vec2 p, int radius = 3) const {
    double best = 1e9;
    const auto [cx, cy] = cell(p);
    for (int dy = -radius; dy <= radius; ++dy) {
      for (int dx = -radius; dx <= radius; ++dx) {
        const auto it = cells_.find(int64_t(cy + dy) * 100000 + (cx + dx));
        if (it == cells_.end()) continue;
        for (size_t k : it->second)
          best = std::min(best, point_segment_distance(p, s_[k][0], s_[k][1]));
      }
    }
    return best;
  }

 private:
  static std::pair<int, int> cell(Vec2 p) { return {int(std::floor(p.x)), int(std::floor(p.y))}; }
  static int64_t key(Vec2 p) {
    const auto [x, y] = cell(p);
    return int64_t(y) * 100000 + x;
  }
  std::vector<std::array<Vec2, 2>> s_;
  std::map<int64_t, std::vector<size_t>> cells_;
};

// Samples of the limit curve of a closed tear feature without corners: the closed uniform cubic
// B-spline of its control polygon (Loop's crease rules, 1/8-6/8-1/8 and midpoints).
std::vector<Vec2> closed_bspline(const std::vector<Vec2>& control, int per_span) {
  const size_t n = control.size();
  std::vector<Vec2> out;
  for (size_t k = 0; k < n; ++k) {
    const Vec2 p0 = control[(k + n - 1) % n], p1 = control[k], p2 = control[(k + 1) % n],
               p3 = control[(k + 2) % n];
    for (int s = 0; s < per_span; ++s) {
      const double t = double(s) / per_span, t2 = t * t, t3 = t2 * t;
      const double b0 = (1 - t) * (1 - t) * (1 - t) / 6, b1 = (3 * t3 - 6 * t2 + 4) / 6,
                   b2 = (-3 * t3 + 3 * t2 + 3 * t + 1) / 6, b3 = t3 / 6;
      out.push_back({b0 * p0.x + b1 * p1.x + b2 * p2.x + b3 * p3.x,
                     b0 * p0.y + b1 * p1.y + b2 * p2.y + b3 * p3.y});
    }
  }
  return out;
}

ErrorCode error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.code();
  }
  ADD_FAILURE() << "expected subvec::Error";
  return ErrorCode::kIo;
}

TEST(Segment, FindsTheDiskAndTracesItsBoundaryAsOneClosedFeature) {
  const double cx = 47.3, cy = 41.8, r = 22.6;
  const Image8 img = disk_image(96, 88, cx, cy, r);
  const RegionMask mask = segment_foreground(img, {18, 12, 60, 60});
  // GrabCut decides whole pixels and takes most of the mixed ones along the edge.
  EXPECT_NEAR(double(mask.area()), M_PI * r * r, 0.08 * M_PI * r * r);
  const auto features = region_boundary_features(mask);
  ASSERT_EQ(features.size(), 1u);
  const DetectedFeature& f = features[0];
  EXPECT_TRUE(f.closed());
  EXPECT_EQ(f.start_node, -1);
  EXPECT_NEAR(f.length, 2 * M_PI * r, 0.05 * 2 * M_PI * r);
  const Segments cracks(crack_edges(mask));
  double to_circle = 0, to_crack = 0, longest = 0, shortest = 1e9;
  for (size_t i = 0; i + 1 < f.points.size(); ++i) {
    const Vec2 p = f.points[i], q = f.points[i + 1];
    to_circle = std::max(to_circle, std::abs(std::hypot(p.x - cx, p.y - cy) - r));
    to_crack = std::max(to_crack, cracks.distance(p));
    longest = std::max(longest, std::hypot(q.x - p.x, q.y - p.y));
    shortest = std::min(shortest, std::hypot(q.x - p.x, q.y - p.y));
  }
  EXPECT_LT(to_circle, 1.0);
  EXPECT_LT(to_crack, 0.4);
  EXPECT_LT(longest, 1.1);
  EXPECT_GT(shortest, 0.9);
}

TEST(Segment, IsDeterministicAndLeavesTheCallersRngAlone) {
  const Image8 img = disk_image(64, 64, 30.5, 33.2, 17.0);
  cv::theRNG() = cv::RNG(777);
  const RegionMask a = segment_foreground(img, {8, 10, 46, 46});
  EXPECT_EQ(cv::theRNG().state, cv::RNG(777).state);
  cv::theRNG() = cv::RNG(123);  // another caller state: same segmentation
  const RegionMask b = segment_foreground(img, {8, 10, 46, 46});
  EXPECT_EQ(a.inside, b.inside);
}

TEST(Segment, RejectsBadRectangles) {
  const Image8 img = disk_image(40, 30, 20, 15, 8);
  for (const PixelRect& r :
       {PixelRect{5, 5, 0, 10}, PixelRect{5, 5, 10, -1}, PixelRect{-1, 0, 10, 10},
        PixelRect{0, 25, 10, 10}, PixelRect{35, 5, 6, 5}, PixelRect{0, 0, 40, 30},
        PixelRect{10, 10, 2, 2}}) {
    EXPECT_EQ(error_of([&] { segment_foreground(img, r); }), ErrorCode::kInvalidArgument)
        << r.x << "," << r.y << "," << r.width << "," << r.height;
  }
}

TEST(Segment, RegionOnTheBorderGivesOpenFeaturesEndingOnIt) {
  // A half disk cut by the left border, and a blob over the bottom-right corner.
  RegionMask m;
  m.width = 50, m.height = 40;
  m.inside.assign(size_t(m.width) * m.height, 0);
  for (int y = 0; y < m.height; ++y) {
    for (int x = 0; x < m.width; ++x) {
      const bool half_disk = std::hypot(x + 0.5 - 0, y + 0.5 - 15) < 10;
      const bool corner = std::hypot(x + 0.5 - 50, y + 0.5 - 40) < 16;
      m.inside[size_t(y) * m.width + x] = half_disk || corner;
    }
  }
  // Two regions: region_boundary_features takes the larger, the corner blob.
  const auto features = region_boundary_features(m);
  ASSERT_EQ(features.size(), 1u);
  const DetectedFeature& f = features[0];
  EXPECT_FALSE(f.closed());
  const Vec2 a = f.points.front(), b = f.points.back();
  const bool a_on = a.x == 50 || a.y == 40, b_on = b.x == 50 || b.y == 40;
  EXPECT_TRUE(a_on && b_on) << a.x << "," << a.y << " " << b.x << "," << b.y;
  for (size_t i = 1; i + 1 < f.points.size(); ++i) {
    EXPECT_LT(f.points[i].x, 50);
    EXPECT_LT(f.points[i].y, 40);
  }
}

TEST(Segment, ClearFeaturesNearCutsCannyFeaturesBack) {
  // The boundary: a closed square loop 20..40; a horizontal feature crossing it at y = 30 with a
  // junction at each end, and a closed feature far away that stays whole.
  DetectedFeature box;
  for (int k = 0; k <= 80; ++k) {
    const double s = k * 0.25 * 4;  // 0..80 along the perimeter, 1 px steps
    Vec2 p = s < 20   ? Vec2{20 + s, 20}
             : s < 40 ? Vec2{40, s}
             : s < 60 ? Vec2{80 - s, 40}
                      : Vec2{20, 100 - s};
    box.points.push_back(p);
  }
  box.points.back() = box.points.front();
  ASSERT_TRUE(box.closed());
  DetectedFeature line;
  for (int x = 0; x <= 60; ++x) line.points.push_back({x + 0.3, 30.2});
  line.start_node = 4, line.end_node = 7;
  DetectedFeature ring;
  for (int k = 0; k <= 40; ++k)
    ring.points.push_back({90 + 6 * std::cos(k * M_PI / 20), 30 + 6 * std::sin(k * M_PI / 20)});
  ring.points.back() = ring.points.front();
  std::vector<DetectedFeature> features{line, ring};
  clear_features_near(features, {box}, 1.5, 5.0);
  // Left piece 0..~18.5 (keeps node 4), inside piece ~21.5..~38.5 (no node), right piece (node 7).
  ASSERT_EQ(features.size(), 4u);
  EXPECT_EQ(features[0].start_node, 4);
  EXPECT_EQ(features[0].end_node, -1);
  EXPECT_EQ(features[1].start_node, -1);
  EXPECT_EQ(features[1].end_node, -1);
  EXPECT_EQ(features[2].start_node, -1);
  EXPECT_EQ(features[2].end_node, 7);
  EXPECT_TRUE(features[3].closed());
  EXPECT_EQ(features[3].points.size(), ring.points.size());
  for (size_t k = 0; k < 3; ++k) {
    for (const Vec2& p : features[k].points) {
      double d = 1e9;
      for (size_t i = 0; i + 1 < box.points.size(); ++i)
        d = std::min(d, point_segment_distance(p, box.points[i], box.points[i + 1]));
      EXPECT_GE(d, 1.5);
    }
  }
  // Pieces shorter than min_length go.
  std::vector<DetectedFeature> short_ones{line};
  clear_features_near(short_ones, {box}, 1.5, 16.0);  // the inside piece, 14 px, goes
  EXPECT_EQ(short_ones.size(), 2u);
}

// Checks that `v` has the segment boundary as one closed tear whose limit curve stays within 1 px
// of the detected (smoothed) GrabCut boundary and within 1.5 px of the mask's pixel edges (the
// smoothing keeps the detected boundary within 0.4 px of them), and that it follows all of it.
void expect_closed_segment_tear(const VectorImage& v, const VectorizeReport& report,
                                const char* name) {
  ASSERT_EQ(report.segment_feature_ids.size(), 1u) << name;
  const ControlMesh& mesh = v.levels[0];
  const auto it = std::find_if(mesh.features.begin(), mesh.features.end(), [&](const Feature& f) {
    return f.id == report.segment_feature_ids[0];
  });
  ASSERT_NE(it, mesh.features.end()) << name;
  ASSERT_TRUE(it->closed()) << name;
  // No other feature touches it, so it has no corner and its limit is a closed B-spline.
  for (const Feature& f : mesh.features) {
    if (f.id == it->id) continue;
    for (int32_t a : f.vertices)
      EXPECT_EQ(std::count(it->vertices.begin(), it->vertices.end(), a), 0) << name;
  }
  std::vector<Vec2> control;
  for (size_t i = 0; i + 1 < it->vertices.size(); ++i)
    control.push_back(mesh.positions[it->vertices[i]]);
  const std::vector<Vec2> curve = closed_bspline(control, 16);

  // The detected boundary is what the mesh feature started from (report.feature_targets).
  const size_t index = static_cast<size_t>(it - mesh.features.begin());
  ASSERT_LT(index, report.feature_targets.size());
  std::vector<std::array<Vec2, 2>> detected_segments;
  const std::vector<Vec2>& target = report.feature_targets[index];
  for (size_t i = 0; i + 1 < target.size(); ++i)
    detected_segments.push_back({target[i], target[i + 1]});
  const Segments detected(detected_segments);
  const std::vector<std::array<Vec2, 2>> cracks = crack_edges(report.segment_mask);
  const Segments pixel_edges(cracks);
  double to_detected = 0, to_pixels = 0;
  for (const Vec2& p : curve) {
    to_detected = std::max(to_detected, detected.distance(p));
    to_pixels = std::max(to_pixels, pixel_edges.distance(p));
  }
  EXPECT_LE(to_detected, 1.0 + 1e-6) << name << ": limit curve to the detected GrabCut boundary";
  EXPECT_LE(to_pixels, 1.5) << name << ": limit curve to the GrabCut mask's pixel edges";
  std::vector<std::array<Vec2, 2>> curve_segments;
  for (size_t i = 0; i < curve.size(); ++i)
    curve_segments.push_back({curve[i], curve[(i + 1) % curve.size()]});
  const Segments limit(curve_segments);
  double uncovered = 0;
  for (const auto& c : cracks)
    uncovered = std::max(uncovered, limit.distance({(c[0].x + c[1].x) / 2, (c[0].y + c[1].y) / 2}));
  EXPECT_LE(uncovered, 2.0) << name << ": GrabCut mask's pixel edges to the limit curve";
  std::printf(
      "[ %s ] segment: %zu control vertices; limit curve within %.3f px of the detected boundary, "
      "%.3f px of the mask's pixel edges; those within %.3f px of the curve\n",
      name, control.size(), to_detected, to_pixels, uncovered);
}

TEST(Segment, VectorizeMakesTheBoundaryAClosedTear) {
  const Image8 img = disk_image(96, 80, 45.6, 41.2, 24.3);
  VectorizeOptions options;
  options.vertices = 150;
  options.segment = PixelRect{14, 10, 64, 64};
  VectorizeReport report;
  const VectorImage v = vectorize(img, options, &report);
  EXPECT_NO_THROW(validate(v));
  expect_closed_segment_tear(v, report, "disk");
  // Canny found the same circle; within the clearance of the boundary it is gone.
  EXPECT_EQ(v.levels[0].features.size(), 1u);
  ASSERT_GE(report.stages.size(), 5u);
  EXPECT_EQ(report.stages[0].stage, "segment");
  // Same input, same output.
  VectorizeReport again;
  const VectorImage w = vectorize(img, options, &again);
  EXPECT_EQ(v.levels[0].positions, w.levels[0].positions);
  EXPECT_EQ(v.levels[0].colors, w.levels[0].colors);
  EXPECT_EQ(v.levels[0].triangles, w.levels[0].triangles);
}

TEST(Segment, VectorizeEndsTheBoundaryOnTheImageBorder) {
  // The disk overhangs the left border; the rectangle starts at column 0.
  const Image8 img = disk_image(80, 64, 6.5, 30.7, 20.2);
  VectorizeOptions options;
  options.vertices = 100;
  options.segment = PixelRect{0, 4, 34, 54};
  VectorizeReport report;
  const VectorImage v = vectorize(img, options, &report);
  EXPECT_NO_THROW(validate(v));
  ASSERT_EQ(report.segment_feature_ids.size(), 1u);
  for (const Feature& f : v.levels[0].features) {
    if (f.id != report.segment_feature_ids[0]) continue;
    EXPECT_FALSE(f.closed());
    EXPECT_EQ(v.levels[0].positions[f.vertices.front()].x, 0.0);
    EXPECT_EQ(v.levels[0].positions[f.vertices.back()].x, 0.0);
  }
}

TEST(Segment, SharedPhotograph) {
  const std::filesystem::path path =
      std::filesystem::path(SUBVEC_SOURCE_DIR) / ".." / "shared" / "images" / "apple.png";
  if (const auto why = test::skip_shared_photos(path)) GTEST_SKIP() << *why;
  const Image8 img = read_image(path);
  VectorizeOptions options;
  options.ratio = 0.01;
  options.segment = PixelRect{30, 40, 440, 460};
  VectorizeReport report;
  const VectorImage v = vectorize(img, options, &report);
  EXPECT_NO_THROW(validate(v));
  EXPECT_GT(report.segment_mask.area(), 100000);  // the apple: about 61 % of the image
  expect_closed_segment_tear(v, report, "apple");
}

}  // namespace
}  // namespace subvec
