// The pixel moments of a triangle (vectorize/pixel_moments_p.h), which refinement's errors and
// Gauss-Newton systems are made of, against plain per-pixel sums; and the pixels a triangle covers
// against a test of every pixel centre of the image by its barycentric weights.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "vectorize/pixel_moments_p.h"

namespace subvec {
namespace {

using detail::Affine;
using detail::PixelMoments;

Image8 noise_image(int width, int height, int channels, unsigned seed) {
  Image8 image(width, height, channels);
  std::mt19937 rng(seed);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width * channels; ++x)
      image.row(y)[x] = static_cast<uint8_t>((x * 7 + y * 3 + rng() % 64) % 256);
  return image;
}

struct Triangle {
  Vec2 p0, p1, p2;
};

// Random triangles of every size and orientation, some past the border, some slivers, and some
// with corners on pixel centres (so that centres fall on their edges).
std::vector<Triangle> test_triangles(int width, int height, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  auto point = [&](double cx, double cy, double r) {
    return Vec2{cx + r * (2 * unit(rng) - 1), cy + r * (2 * unit(rng) - 1)};
  };
  std::vector<Triangle> out;
  for (int i = 0; i < 300; ++i) {
    const double cx = -20 + (width + 40) * unit(rng), cy = -20 + (height + 40) * unit(rng);
    const double r = std::pow(10.0, -0.5 + 3 * unit(rng));
    Triangle t{point(cx, cy, r), point(cx, cy, r), point(cx, cy, r)};
    if (i % 5 == 0) {  // corners on pixel centres
      for (Vec2* p : {&t.p0, &t.p1, &t.p2}) *p = {std::floor(p->x) + 0.5, std::floor(p->y) + 0.5};
    }
    if (i % 7 == 0) t.p2 = {t.p0.x + 1e-3 * (t.p1.x - t.p0.x), t.p0.y + 1e-3 * (t.p1.y - t.p0.y) + 0.5};  // sliver
    out.push_back(t);
  }
  return out;
}

// Barycentric weights of s in (p0, p1, p2).
std::array<double, 3> weights(const Triangle& t, Vec2 s) {
  const double area = detail::signed_area(t.p0, t.p1, t.p2);
  const double w0 = detail::signed_area(s, t.p1, t.p2) / area, w1 = detail::signed_area(t.p0, s, t.p2) / area;
  return {w0, w1, 1 - w0 - w1};
}

TEST(PixelMoments, RowsCoverExactlyThePixelCentresInside) {
  constexpr int kWidth = 90, kHeight = 70;
  for (const Triangle& t : test_triangles(kWidth, kHeight, 1)) {
    std::vector<char> visited(kWidth * kHeight, 0);
    const bool thick = detail::for_each_pixel(t.p0, t.p1, t.p2, kWidth, kHeight, 0, [&](int x, int y) {
      ASSERT_TRUE(x >= 0 && x < kWidth && y >= 0 && y < kHeight);
      EXPECT_EQ(visited[y * kWidth + x]++, 0) << "a pixel visited twice";
    });
    ASSERT_EQ(thick, std::abs(detail::signed_area(t.p0, t.p1, t.p2)) > 0);
    if (!thick) continue;
    for (int y = 0; y < kHeight; ++y) {
      for (int x = 0; x < kWidth; ++x) {
        const auto w = weights(t, {x + 0.5, y + 0.5});
        const double least = std::min({w[0], w[1], w[2]});
        // Centres clearly inside are visited and clearly outside are not; on an edge, either.
        if (least > 1e-9) {
          EXPECT_TRUE(visited[y * kWidth + x]) << x << ", " << y << " inside";
        } else if (least < -1e-9) {
          EXPECT_FALSE(visited[y * kWidth + x]) << x << ", " << y << " outside";
        }
      }
    }
  }
}

TEST(PixelMoments, TooThinVisitsNothing) {
  int visits = 0;
  EXPECT_FALSE(detail::for_each_pixel({0, 0}, {10, 0}, {20, 0}, 30, 30, 0, [&](int, int) { ++visits; }));
  EXPECT_FALSE(detail::for_each_pixel({0, 0}, {10, 0}, {0, 10}, 30, 30, 50, [&](int, int) { ++visits; }));
  EXPECT_TRUE(detail::for_each_pixel({0, 0}, {10, 0}, {0, 10}, 30, 30, 49, [&](int, int) { ++visits; }));
  EXPECT_GT(visits, 0);
}

// Σ a b and Σ a t from the moments against the sums over the visited pixels, for triangles of up
// to a thousand pixels across, far from the image's origin, in RGB and RGBA images.
TEST(PixelMoments, SumsAreThePerPixelSums) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coefficient(-3, 3);
  for (int channels : {3, 4}) {
    const Image8 image = noise_image(1200, 900, channels, 3 + channels);
    int nonempty = 0;
    for (const Triangle& t : test_triangles(image.width, image.height, 11 + channels)) {
      const Vec2 origin = t.p1;
      PixelMoments m;
      if (!detail::pixel_moments(image, t.p0, t.p1, t.p2, origin, 0, m)) continue;
      const Affine a{coefficient(rng) * 100, coefficient(rng), coefficient(rng)};
      const Affine b{coefficient(rng) * 100, coefficient(rng), coefficient(rng)};
      double n = 0, ab = 0, tt = 0, scale_ab = 0;
      std::array<double, 3> at{}, scale_at{};
      detail::for_each_pixel(t.p0, t.p1, t.p2, image.width, image.height, 0, [&](int x, int y) {
        const double du = x + 0.5 - origin.x, dv = y + 0.5 - origin.y;
        const uint8_t* px = image.row(y) + x * channels;
        n += 1, ab += a.at(du, dv) * b.at(du, dv), scale_ab += std::abs(a.at(du, dv) * b.at(du, dv));
        for (int ch = 0; ch < 3; ++ch) {
          at[ch] += a.at(du, dv) * px[ch], scale_at[ch] += std::abs(a.at(du, dv) * px[ch]);
          tt += double(px[ch]) * px[ch];
        }
      });
      nonempty += n > 0;
      EXPECT_EQ(m.n, n);
      EXPECT_EQ(m.tt, tt);
      EXPECT_NEAR(m.sum(a, b), ab, 1e-9 * scale_ab + 1e-9);
      for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(m.sum_t(a, ch), at[ch], 1e-9 * scale_at[ch] + 1e-9);
    }
    EXPECT_GT(nonempty, 150);
  }
}

TEST(PixelMoments, BarycentricWeightsAreAffine) {
  const Vec2 p0{3.2, 1.1}, p1{40.5, 7.25}, p2{12, 30}, origin{100, -50};
  const auto w = detail::barycentric(p0, p1, p2, origin);
  for (Vec2 s : {p0, p1, p2, Vec2{20, 12}, Vec2{-7, 44}}) {
    const auto expected = weights({p0, p1, p2}, s);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(w[i].at(s.x - origin.x, s.y - origin.y), expected[i], 1e-12);
  }
}

}  // namespace
}  // namespace subvec
