// The private core helpers (src/core/geometry_p.h, src/core/messages_p.h): the one
// point-to-segment distance, the pixels near a segment, and the message helpers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "core/geometry_p.h"
#include "core/messages_p.h"
#include "subvec/core/error.h"
#include "subvec/mesh/vector_image.h"

namespace subvec {
namespace {

TEST(Geometry, SegmentDistanceClampsToTheEndpoints) {
  const Vec2 a{1, 1}, b{5, 1};
  Vec2 q;
  EXPECT_DOUBLE_EQ(detail::segment_distance(Vec2{3, 4}, a, b, &q), 3.0);  // beside the middle
  EXPECT_EQ(q, (Vec2{3, 1}));
  EXPECT_DOUBLE_EQ(detail::segment_distance(Vec2{-2, 5}, a, b, &q), 5.0);  // beyond a
  EXPECT_EQ(q, a);
  EXPECT_DOUBLE_EQ(detail::segment_distance(Vec2{8, 5}, a, b, &q), 5.0);  // beyond b
  EXPECT_EQ(q, b);
  EXPECT_DOUBLE_EQ(detail::segment_distance(Vec2{4, 5}, a, a, &q), 5.0);  // a point
  EXPECT_EQ(q, a);
}

TEST(Geometry, FloatEndpointsTakeTheirDifferencesInFloat) {
  // The fit stores tear segments as floats and always took b - a in float: the same formula on
  // float endpoints must be the one with the float difference, widened.
  const float ax = 0.1f, ay = 0.7f, bx = 3.3f, by = 2.9f;
  const double px = 1.234567, py = 3.21;
  const double dx = bx - ax, dy = by - ay, len2 = dx * dx + dy * dy;
  const double t = std::clamp(((px - ax) * dx + (py - ay) * dy) / len2, 0.0, 1.0);
  EXPECT_EQ(detail::segment_distance(px, py, ax, ay, bx, by), std::hypot(px - (ax + t * dx), py - (ay + t * dy)));
}

TEST(Geometry, PixelsNearASegmentAreThoseWhoseCentresAreCloserThanR) {
  const int w = 12, h = 9;
  const double r = 1.5;
  const Vec2 a{2.2, 3.1}, b{9.6, 6.4};
  std::vector<std::pair<int, int>> visited;
  detail::for_pixels_near_segment(a.x, a.y, b.x, b.y, r, w, h, [&](int x, int y) { visited.push_back({x, y}); });
  std::vector<std::pair<int, int>> expected;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (detail::segment_distance(Vec2{x + 0.5, y + 0.5}, a, b) < r) expected.push_back({x, y});
  EXPECT_FALSE(expected.empty());
  EXPECT_EQ(visited, expected);  // every one, once, row by row
}

TEST(Messages, NumPrintsSignificantDigitsAndInvalidThrowsInvalidArgument) {
  EXPECT_EQ(detail::num(0.1234567891), "0.123457");
  EXPECT_EQ(detail::num(1e21), "1e+21");
  EXPECT_EQ(detail::num(2.5, 4), "2.5");
  EXPECT_EQ(detail::num(3.14159265, 4), "3.142");
  try {
    detail::invalid("bad thing");
    FAIL() << "no throw";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_STREQ(e.what(), "bad thing");
  }
}

}  // namespace
}  // namespace subvec
