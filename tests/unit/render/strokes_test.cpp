// Strokes in the CPU renderer: drawn anti-aliased over the colors, where the view puts them, with
// the width scaled by the zoom and linear tapers at the ends.
#include <gtest/gtest.h>

#include <filesystem>

#include "subvec/io/svec.h"
#include "subvec/mesh/validate.h"
#include "subvec/render/renderer.h"

namespace subvec {
namespace {

VectorImage disk_with_stroke(float taper) {
  VectorImage img = read_svec(std::filesystem::path(SUBVEC_SOURCE_DIR) / "examples" / "01-disk.svec.json");
  // A straight stroke (collinear, evenly spaced points: the clamped B-spline is the segment).
  Stroke s;
  s.points = {{10, 30.25}, {30, 30.25}, {50, 30.25}, {70, 30.25}};
  s.width = 4;
  s.color = {255, 0, 255};
  s.taper = taper;
  img.strokes.push_back(s);
  validate(img);
  return img;
}

const uint8_t* pixel(const Image8& im, int x, int y) { return im.row(y) + size_t(x) * im.channels; }

TEST(Strokes, AreDrawnAntialiasedOverTheColors) {
  const VectorImage img = disk_with_stroke(0);
  const Image8 out = render(img, RenderOptions{});
  // The band y in [28.25, 32.25]: rows 29..31 covered, row 28 three quarters, row 32 a quarter.
  for (int y = 29; y <= 31; ++y) {
    const uint8_t* p = pixel(out, 40, y);
    EXPECT_EQ(p[0], 255);
    EXPECT_EQ(p[1], 0);
    EXPECT_EQ(p[2], 255);
  }
  VectorImage bare = img;
  bare.strokes.clear();
  const Image8 under = render(bare, RenderOptions{});
  const auto mix = [&](int y, double a) {
    const uint8_t* p = pixel(out, 40, y);
    const uint8_t* q = pixel(under, 40, y);
    EXPECT_NEAR(p[1], (1 - a) * q[1], 1.01) << "row " << y;
    EXPECT_NEAR(p[0], a * 255 + (1 - a) * q[0], 1.01) << "row " << y;
  };
  mix(28, 0.75);
  mix(32, 0.25);
  mix(26, 0);
  mix(34, 0);
  // Beyond the ends nothing is drawn.
  EXPECT_EQ(pixel(out, 75, 30)[1], pixel(under, 75, 30)[1]);
}

TEST(Strokes, FollowTheWindowAndTheZoom) {
  const VectorImage img = disk_with_stroke(0);
  RenderOptions o;
  o.window = Window{20, 20, 60, 40};
  o.width = 160;  // 4x
  const Image8 out = render(img, o);
  ASSERT_EQ(out.height, 80);
  // y = 30.25 -> (30.25 - 20) * 4 = 41 in the output, 16 output pixels wide: rows 33..48.
  for (const int y : {34, 41, 47}) EXPECT_EQ(pixel(out, 80, y)[1], 0) << "row " << y;
  for (const int y : {30, 52}) EXPECT_NE(pixel(out, 80, y)[1], 0) << "row " << y;
}

TEST(Strokes, TaperLinearlyAtBothEnds) {
  const VectorImage img = disk_with_stroke(0.25f);  // 60 px long: 15 px ramps
  RenderOptions o;
  o.width = 96 * 4;
  const Image8 out = render(img, o);
  // Fully covered rows at 3 px from the start, in the middle, and 3 px from the end.
  auto covered_rows = [&](double x) {
    int rows = 0;
    for (int y = 0; y < out.height; ++y) {
      const uint8_t* q = pixel(out, int(x * 4), y);
      rows += q[0] == 255 && q[1] == 0 && q[2] == 255;
    }
    return rows;
  };
  const int start = covered_rows(13), mid = covered_rows(40), end = covered_rows(67);
  EXPECT_EQ(mid, 16);
  EXPECT_LT(start, mid / 2);
  EXPECT_NEAR(start, end, 1);
}

}  // namespace
}  // namespace subvec
