#include "subvec/core/image.h"

#include <gtest/gtest.h>

namespace subvec {
namespace {

TEST(SampleBilinear, ExactAtCentresLinearBetweenClampedOutside) {
  Image8 img(3, 2, 3);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 3; ++x)
      for (int k = 0; k < 3; ++k) img.row(y)[3 * x + k] = static_cast<uint8_t>(10 * x + 100 * y + k);
  EXPECT_EQ(sample_bilinear(img, 1.5, 0.5)[0], 10.0);            // centre of pixel (1, 0)
  EXPECT_EQ(sample_bilinear(img, 2.5, 1.5)[2], 20.0 + 100 + 2);  // centre of pixel (2, 1)
  EXPECT_DOUBLE_EQ(sample_bilinear(img, 1.0, 1.0)[0], 55.0);     // between four centres
  EXPECT_DOUBLE_EQ(sample_bilinear(img, -5, -5)[1], 1.0);        // clamped to pixel (0, 0)
  EXPECT_DOUBLE_EQ(sample_bilinear(img, 99, 99)[0], 120.0);      // clamped to pixel (2, 1)
}

}  // namespace
}  // namespace subvec
