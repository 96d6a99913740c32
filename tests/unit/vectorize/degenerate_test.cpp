// Degenerate photographs (issue 9): a uniform image, pure noise, tiny images, a big flat sky, and
// features that touch the border and each other densely. Vectorization must succeed with a valid
// mesh and an error that makes sense for the picture. The images are generated here.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <tuple>
#include <vector>

#include "subvec/core/error.h"
#include "subvec/core/metrics.h"
#include "subvec/mesh/validate.h"
#include "subvec/render/renderer.h"
#include "subvec/vectorize/vectorize.h"

namespace subvec {
namespace {

Image8 generate(int w, int h, const std::function<void(int, int, uint8_t*)>& pixel) {
  Image8 img(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) pixel(x, y, img.row(y) + 3 * x);
  return img;
}

// The error of the best flat picture (the mean color): what a vectorization must beat, or match
// when there is nothing to represent.
double flat_mae(const Image8& img) {
  double mean[3] = {0, 0, 0};
  const double n = double(img.width) * img.height;
  for (size_t i = 0; i < img.pixels.size(); ++i) mean[i % 3] += img.pixels[i] / n;
  const Image8 flat = generate(img.width, img.height, [&](int, int, uint8_t* p) {
    for (int k = 0; k < 3; ++k) p[k] = static_cast<uint8_t>(std::lround(mean[k]));
  });
  return compare(img, flat).mae_mean;
}

// Vectorizes, checks the mesh and returns the MAE of the 1x render against the input.
double vectorize_and_check(const Image8& img, const VectorizeOptions& options) {
  VectorImage v;
  EXPECT_NO_THROW(v = vectorize(img, options)) << img.width << "x" << img.height;
  if (v.levels.empty()) return 1e9;
  EXPECT_EQ(v.width, img.width);
  EXPECT_EQ(v.height, img.height);
  EXPECT_NO_THROW(validate(v));
  const Image8 out = render(v, RenderOptions{});
  EXPECT_EQ(out.width, img.width);
  EXPECT_EQ(out.height, img.height);
  const double mae = compare(img, out).mae_mean;
  // The figures docs/reliability.md quotes.
  std::printf("degenerate: %dx%d, %d vertices, %d triangles, MAE %.3f\n", img.width, img.height,
              v.levels[0].num_vertices(), v.levels[0].num_triangles(), mae);
  return mae;
}

uint32_t next(uint32_t& state) {
  state = state * 1664525u + 1013904223u;
  return state >> 24;
}

TEST(Degenerate, UniformImageIsReproducedExactly) {
  const Image8 img = generate(200, 150, [](int, int, uint8_t* p) {
    p[0] = 90, p[1] = 140, p[2] = 200;
  });
  const double mae = vectorize_and_check(img, {});
  EXPECT_LT(mae, 0.5);
}

TEST(Degenerate, PureNoiseGivesAValidMeshNoWorseThanFlat) {
  uint32_t state = 7;
  const Image8 img = generate(160, 120, [&](int, int, uint8_t* p) {
    for (int k = 0; k < 3; ++k) p[k] = static_cast<uint8_t>(next(state));
  });
  const double mae = vectorize_and_check(img, {});
  // Uniform noise over 0-255: the mean color is off by 64 on average; a smooth surface through
  // the noise cannot do much better, but must not do worse.
  EXPECT_LT(mae, flat_mae(img) + 1.0);
  EXPECT_GT(mae, 40.0);  // the error is measured, not hidden
}

TEST(Degenerate, TinyImages) {
  int w = 0, h = 0;
  const auto gradient = [&](int x, int y, uint8_t* p) {
    p[0] = static_cast<uint8_t>(40 + 150 * x / w), p[1] = static_cast<uint8_t>(30 + 150 * y / h);
    p[2] = 100;
  };
  for (const auto& size : std::vector<std::pair<int, int>>{{2, 2}, {3, 2}, {2, 64}, {64, 2}, {3, 5}}) {
    std::tie(w, h) = size;
    SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
    const Image8 img = generate(w, h, gradient);
    const double mae = vectorize_and_check(img, {});
    EXPECT_LT(mae, 12.0);
  }
  for (const auto& size : std::vector<std::pair<int, int>>{{1, 1}, {1, 64}, {64, 1}}) {
    std::tie(w, h) = size;
    try {
      vectorize(generate(w, h, gradient), {});
      ADD_FAILURE() << w << "x" << h << " was vectorized";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("too small to vectorize"), std::string::npos) << e.what();
    }
  }
}

// A sky: a smooth vertical gradient with a faint horizontal one and +-1 level of noise, at
// 1500 x 1000 pixels. Few features, a huge smooth region.
TEST(Degenerate, HugeFlatSky) {
#ifdef SUBVEC_TEST_SANITIZED
  GTEST_SKIP() << "1.5 megapixels take minutes under the sanitizers; the release build runs it";
#endif
  uint32_t state = 11;
  const Image8 img = generate(1500, 1000, [&](int x, int y, uint8_t* p) {
    const double t = y / 999.0, s = x / 1499.0;
    const int noise = int(next(state) % 3) - 1;
    p[0] = static_cast<uint8_t>(std::lround(70 + 90 * t + 10 * s) + noise);
    p[1] = static_cast<uint8_t>(std::lround(130 + 70 * t) + noise);
    p[2] = static_cast<uint8_t>(std::lround(230 - 20 * t - 10 * s) + noise);
  });
  VectorizeOptions options;
  options.vertices = 400;
  const double mae = vectorize_and_check(img, options);
  EXPECT_LT(mae, 2.0);
}

// Features everywhere: vertical stripes 3 px wide whose edges run into the top and bottom borders,
// and a checkerboard of 5 px cells (junctions every 5 px, features touching each other).
TEST(Degenerate, DenseFeaturesTouchingTheBorder) {
  const Image8 stripes = generate(96, 64, [](int x, int, uint8_t* p) {
    const bool on = (x / 3) % 2 == 0;
    p[0] = on ? 230 : 20, p[1] = on ? 200 : 40, p[2] = on ? 60 : 120;
  });
  const Image8 checker = generate(80, 80, [](int x, int y, uint8_t* p) {
    const bool on = (x / 5 + y / 5) % 2 == 0;
    p[0] = p[1] = p[2] = on ? 240 : 15;
  });
  for (const Image8* img : {&stripes, &checker}) {
    SCOPED_TRACE(img == &stripes ? "stripes" : "checkerboard");
    VectorizeOptions options;
    options.ratio = 0.2;
    const double mae = vectorize_and_check(*img, options);
    // Far better than flat (a flat picture is off by about 100 levels).
    EXPECT_LT(mae, 0.5 * flat_mae(*img));
  }
}

// A disk cut by two borders: its boundary is an open feature that ends on the border.
TEST(Degenerate, FeatureCutByTheCorner) {
  const Image8 img = generate(90, 70, [](int x, int y, uint8_t* p) {
    const bool inside = std::hypot(x + 0.5 - 85, y + 0.5 - 66) < 40;
    p[0] = inside ? 220 : 30, p[1] = inside ? 60 : 90, p[2] = inside ? 40 : 200;
  });
  const double mae = vectorize_and_check(img, {});
  EXPECT_LT(mae, 0.25 * flat_mae(img));
}

}  // namespace
}  // namespace subvec
