// Image comparison: the paper's mean reconstruction error and the usual companions.
#pragma once

#include <array>

#include "subvec/core/image.h"

namespace subvec {

struct ImageDifference {
  std::array<double, 3> mae{};  // mean absolute error per channel (R, G, B), 0-255 scale
  double mae_mean = 0;          // mean over the three channels: the paper's "mean error"
  double psnr = 0;              // dB over RGB, peak 255; +infinity for identical images
  double ssim = 0;              // mean SSIM (Gaussian 11x11, sigma 1.5) over the RGB channels
};

// Compares two images of the same size over RGB (alpha ignored). Throws Error(kInvalidArgument)
// when the sizes differ.
ImageDifference compare(const Image8& reference, const Image8& test);

}  // namespace subvec
