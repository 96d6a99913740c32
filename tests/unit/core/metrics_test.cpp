#include "subvec/core/metrics.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

#include "subvec/core/error.h"

namespace subvec {
namespace {

// A smooth RGB gradient with some structure, so that SSIM has local variance to work with.
Image8 gradient(int w, int h, int channels = 3) {
  Image8 img(w, h, channels);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      uint8_t* p = img.row(y) + size_t(x) * channels;
      p[0] = uint8_t(20 + (200 * x) / w);
      p[1] = uint8_t(20 + (200 * y) / h);
      p[2] = uint8_t((x / 8 + y / 8) % 2 ? 60 : 180);
      if (channels == 4) p[3] = 255;
    }
  }
  return img;
}

Image8 add_noise(const Image8& img, int amplitude, unsigned seed) {
  Image8 out = img;
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> noise(-amplitude, amplitude);
  for (uint8_t& v : out.pixels) v = uint8_t(std::clamp(int(v) + noise(rng), 0, 255));
  return out;
}

TEST(Metrics, IdenticalImages) {
  const Image8 a = gradient(40, 30);
  const ImageDifference d = compare(a, a);
  for (double m : d.mae) EXPECT_EQ(m, 0.0);
  EXPECT_EQ(d.mae_mean, 0.0);
  EXPECT_TRUE(std::isinf(d.psnr));
  EXPECT_GT(d.psnr, 0);
  EXPECT_NEAR(d.ssim, 1.0, 1e-12);
}

TEST(Metrics, ConstantOffset) {
  const Image8 a = gradient(40, 30);
  Image8 b = a;
  for (uint8_t& v : b.pixels) v = uint8_t(v + 10);  // the gradient stays below 245
  const ImageDifference d = compare(a, b);
  for (double m : d.mae) EXPECT_NEAR(m, 10.0, 1e-12);
  EXPECT_NEAR(d.mae_mean, 10.0, 1e-12);
  EXPECT_NEAR(d.psnr, 20 * std::log10(255.0 / 10.0), 1e-9);
  // A brightness shift keeps structure and contrast: SSIM only loses through the luminance term.
  EXPECT_LT(d.ssim, 1.0);
  EXPECT_GT(d.ssim, 0.95);
}

TEST(Metrics, PerChannelErrors) {
  Image8 a(8, 8, 3), b(8, 8, 3);
  for (size_t i = 0; i < b.pixels.size(); i += 3) {
    b.pixels[i + 0] = 3;  // R off by 3
    b.pixels[i + 2] = 9;  // B off by 9
  }
  const ImageDifference d = compare(a, b);
  EXPECT_NEAR(d.mae[0], 3.0, 1e-12);
  EXPECT_NEAR(d.mae[1], 0.0, 1e-12);
  EXPECT_NEAR(d.mae[2], 9.0, 1e-12);
  EXPECT_NEAR(d.mae_mean, 4.0, 1e-12);
  // MSE = (9 + 0 + 81) / 3 = 30.
  EXPECT_NEAR(d.psnr, 10 * std::log10(255.0 * 255.0 / 30.0), 1e-9);
}

TEST(Metrics, SsimOfNoiseIsSymmetricAndBelowOne) {
  const Image8 a = gradient(64, 48);
  const Image8 b = add_noise(a, 40, 1);
  const ImageDifference ab = compare(a, b), ba = compare(b, a);
  EXPECT_NEAR(ab.ssim, ba.ssim, 1e-12);
  EXPECT_NEAR(ab.mae_mean, ba.mae_mean, 1e-12);
  EXPECT_LT(ab.ssim, 0.9);
  EXPECT_GT(ab.ssim, 0.0);
  // More noise, lower similarity.
  const ImageDifference more = compare(a, add_noise(a, 80, 1));
  EXPECT_LT(more.ssim, ab.ssim);
  EXPECT_GT(more.mae_mean, ab.mae_mean);
  EXPECT_LT(more.psnr, ab.psnr);
}

// Checks the SSIM formula on a flat pair, where every local statistic is known: for constant
// images x = a, y = b the variances vanish and SSIM = (2ab + C1) / (a^2 + b^2 + C1).
TEST(Metrics, SsimOfFlatImagesMatchesFormula) {
  Image8 a(20, 20, 3), b(20, 20, 3);
  std::fill(a.pixels.begin(), a.pixels.end(), uint8_t(100));
  std::fill(b.pixels.begin(), b.pixels.end(), uint8_t(140));
  const double c1 = (0.01 * 255) * (0.01 * 255);
  const double expected = (2 * 100.0 * 140.0 + c1) / (100.0 * 100.0 + 140.0 * 140.0 + c1);
  EXPECT_NEAR(compare(a, b).ssim, expected, 1e-9);
}

// A slow, obvious SSIM straight from the definition: per pixel, weighted sums over the 11x11
// Gaussian window with mirrored (reflect-101) borders.
double naive_ssim(const Image8& a, const Image8& b) {
  constexpr int kR = 5;
  double g[2 * kR + 1], g_sum = 0;
  for (int i = -kR; i <= kR; ++i) g_sum += g[i + kR] = std::exp(-i * i / (2 * 1.5 * 1.5));
  for (double& v : g) v /= g_sum;
  auto mirror = [](int i, int n) {
    if (n == 1) return 0;
    while (i < 0 || i >= n) i = i < 0 ? -i : 2 * (n - 1) - i;
    return i;
  };
  const double c1 = (0.01 * 255) * (0.01 * 255), c2 = (0.03 * 255) * (0.03 * 255);
  double total = 0;
  for (int c = 0; c < 3; ++c) {
    for (int y = 0; y < a.height; ++y) {
      for (int x = 0; x < a.width; ++x) {
        double mx = 0, my = 0, sxx = 0, syy = 0, sxy = 0;
        for (int dy = -kR; dy <= kR; ++dy) {
          for (int dx = -kR; dx <= kR; ++dx) {
            const double w = g[dx + kR] * g[dy + kR];
            const int xx = mirror(x + dx, a.width), yy = mirror(y + dy, a.height);
            const double va = a.row(yy)[xx * 3 + c], vb = b.row(yy)[xx * 3 + c];
            mx += w * va;
            my += w * vb;
            sxx += w * va * va;
            syy += w * vb * vb;
            sxy += w * va * vb;
          }
        }
        const double vx = sxx - mx * mx, vy = syy - my * my, cxy = sxy - mx * my;
        total += (2 * mx * my + c1) * (2 * cxy + c2) / ((mx * mx + my * my + c1) * (vx + vy + c2));
      }
    }
  }
  return total / (3.0 * a.width * a.height);
}

TEST(Metrics, SsimMatchesNaiveDefinition) {
  const Image8 a = gradient(23, 17);
  const Image8 b = add_noise(a, 30, 7);
  EXPECT_NEAR(compare(a, b).ssim, naive_ssim(a, b), 1e-6);
  const Image8 c = add_noise(gradient(4, 3), 50, 3);  // smaller than the window
  EXPECT_NEAR(compare(gradient(4, 3), c).ssim, naive_ssim(gradient(4, 3), c), 1e-6);
  // Several bands of rows (32 each), an odd width, RGBA against RGB.
  const Image8 d = gradient(157, 101, 4);
  const Image8 e = add_noise(gradient(157, 101), 20, 11);
  EXPECT_NEAR(compare(d, e).ssim, naive_ssim(gradient(157, 101), e), 1e-12);
}

TEST(Metrics, AlphaIsIgnored) {
  const Image8 rgb = gradient(16, 16, 3);
  Image8 rgba = gradient(16, 16, 4);
  for (size_t i = 3; i < rgba.pixels.size(); i += 4) rgba.pixels[i] = 0;
  const ImageDifference d = compare(rgb, rgba);
  EXPECT_EQ(d.mae_mean, 0.0);
  EXPECT_TRUE(std::isinf(d.psnr));
}

TEST(Metrics, TinyImagesWork) {
  Image8 a(1, 1, 3), b(1, 1, 3);
  b.pixels = {10, 20, 30};
  const ImageDifference d = compare(a, b);
  EXPECT_NEAR(d.mae_mean, 20.0, 1e-12);
  EXPECT_TRUE(std::isfinite(d.ssim));
  EXPECT_LT(d.ssim, 1.0);
}

TEST(Metrics, SizeMismatchThrows) {
  try {
    compare(gradient(10, 10), gradient(10, 11));
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("10x10 vs 10x11"), std::string::npos) << e.what();
  }
}

TEST(Metrics, MalformedImageThrows) {
  Image8 bad(4, 4, 3);
  bad.pixels.resize(5);
  EXPECT_THROW(compare(bad, bad), Error);
  EXPECT_THROW(compare(Image8{}, Image8{}), Error);
}

}  // namespace
}  // namespace subvec
