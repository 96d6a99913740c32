// Image comparison (core/metrics.h).
//
// MAE and PSNR are computed directly over the RGB samples. SSIM follows Wang, Bovik, Sheikh and
// Simoncelli, "Image quality assessment: from error visibility to structural similarity" (2004):
// local means, variances and covariance under an 11x11 Gaussian window (sigma 1.5), with
//
//               (2 mu_x mu_y + C1) (2 sigma_xy + C2)
//   SSIM = -------------------------------------------------------,
//          (mu_x^2 + mu_y^2 + C1) (sigma_x^2 + sigma_y^2 + C2)
//
//   C1 = (K1 L)^2, C2 = (K2 L)^2, K1 = 0.01, K2 = 0.03, L = 255,
//
// averaged over every pixel, per channel, then over R, G and B. Unlike the authors' MATLAB code,
// which drops a 5-pixel margin ("valid" filtering), the window is mirrored at the image border
// (OpenCV's BORDER_REFLECT_101), so every pixel counts and images smaller than the window work.
// Computed in bands of rows with the window's two passes per row (no image-sized temporaries:
// OpenCV's whole-image blurs took 1.5 s and 560 MB for a 4 MP image); the test's definition
// (metrics_test.cpp, naive_ssim) is the reference.
#include "subvec/core/metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "core/parallel_p.h"
#include "subvec/core/error.h"

namespace subvec {
namespace {

void check_image(const Image8& image, const char* which) {
  if (image.width <= 0 || image.height <= 0 || (image.channels != 3 && image.channels != 4) ||
      image.pixels.size() != size_t(image.width) * size_t(image.height) * size_t(image.channels)) {
    throw Error(ErrorCode::kInvalidArgument,
                std::string("compare: the ") + which + " image is empty or malformed");
  }
}

// The SSIM window, 11 taps of a Gaussian of sigma 1.5, normalized.
constexpr int kRadius = 5, kTaps = 2 * kRadius + 1;
std::array<double, kTaps> gaussian_taps() {
  std::array<double, kTaps> g{};
  double sum = 0;
  for (int i = -kRadius; i <= kRadius; ++i) sum += g[i + kRadius] = std::exp(-i * i / (2 * 1.5 * 1.5));
  for (double& v : g) v /= sum;
  return g;
}

// Reflect-101 (OpenCV's BORDER_REFLECT_101): ... 2 1 | 0 1 2 ... n-1 | n-2 ..., repeated for
// images smaller than the window.
int mirror(int i, int n) {
  if (n == 1) return 0;
  while (i < 0 || i >= n) i = i < 0 ? -i : 2 * (n - 1) - i;
  return i;
}

// The SSIM map of one channel summed over rows [y0, y1): the five moments (x, y, xx, yy, xy)
// filtered down the columns for each row, then along it. Separable and exact: the 2D window is the
// product of the 1D ones, as in the definition.
double ssim_rows(const Image8& a, const Image8& b, int channel, int y0, int y1) {
  constexpr double kL = 255, kC1 = (0.01 * kL) * (0.01 * kL), kC2 = (0.03 * kL) * (0.03 * kL);
  static const std::array<double, kTaps> g = gaussian_taps();
  const int w = a.width, h = a.height;
  // Column-filtered moments of one row, padded by kRadius mirrored columns each side.
  std::vector<std::array<double, 5>> column(size_t(w) + 2 * kRadius);
  std::array<const uint8_t*, kTaps> rows_a{}, rows_b{};
  double sum = 0;
  for (int y = y0; y < y1; ++y) {
    for (int k = 0; k < kTaps; ++k) {
      rows_a[k] = a.row(mirror(y + k - kRadius, h));
      rows_b[k] = b.row(mirror(y + k - kRadius, h));
    }
    for (int x = 0; x < w; ++x) {
      std::array<double, 5> m{};
      const size_t ia = size_t(x) * a.channels + channel, ib = size_t(x) * b.channels + channel;
      for (int k = 0; k < kTaps; ++k) {
        const double va = rows_a[k][ia], vb = rows_b[k][ib], gk = g[k];
        m[0] += gk * va;
        m[1] += gk * vb;
        m[2] += gk * va * va;
        m[3] += gk * vb * vb;
        m[4] += gk * va * vb;
      }
      column[size_t(x) + kRadius] = m;
    }
    for (int x = -kRadius; x < 0; ++x) column[size_t(x + kRadius)] = column[size_t(mirror(x, w) + kRadius)];
    for (int x = w; x < w + kRadius; ++x) column[size_t(x + kRadius)] = column[size_t(mirror(x, w) + kRadius)];
    double row_sum = 0;
    for (int x = 0; x < w; ++x) {
      double mx = 0, my = 0, sxx = 0, syy = 0, sxy = 0;
      for (int k = 0; k < kTaps; ++k) {
        const std::array<double, 5>& m = column[size_t(x + k)];
        const double gk = g[k];
        mx += gk * m[0];
        my += gk * m[1];
        sxx += gk * m[2];
        syy += gk * m[3];
        sxy += gk * m[4];
      }
      const double mxy = mx * my, mxx = mx * mx, myy = my * my;
      row_sum += (2 * mxy + kC1) * (2 * (sxy - mxy) + kC2) /
                 ((mxx + myy + kC1) * ((sxx - mxx) + (syy - myy) + kC2));
    }
    sum += row_sum;
  }
  return sum;
}

// Mean SSIM over the three channels, in bands of rows on all cores; each band's sum is added in
// band order, so the value does not depend on the thread count.
double mean_ssim(const Image8& a, const Image8& b) {
  constexpr int kBand = 32;
  const int bands = (a.height + kBand - 1) / kBand;
  std::vector<double> sums(size_t(bands) * 3, 0.0);
  detail::parallel_for(bands * 3, 0, [&](int job) {
    const int band = job / 3, channel = job % 3;
    sums[size_t(job)] = ssim_rows(a, b, channel, band * kBand, std::min(a.height, (band + 1) * kBand));
  });
  double total = 0;
  for (const double v : sums) total += v;
  return total / (3.0 * a.width * a.height);
}

}  // namespace

ImageDifference compare(const Image8& reference, const Image8& test) {
  check_image(reference, "reference");
  check_image(test, "test");
  if (reference.width != test.width || reference.height != test.height) {
    throw Error(ErrorCode::kInvalidArgument,
                "images differ in size: " + std::to_string(reference.width) + "x" +
                    std::to_string(reference.height) + " vs " + std::to_string(test.width) + "x" +
                    std::to_string(test.height));
  }

  ImageDifference d;
  const double pixels = double(reference.width) * double(reference.height);
  double squared_sum = 0;
  for (int y = 0; y < reference.height; ++y) {
    const uint8_t* a = reference.row(y);
    const uint8_t* b = test.row(y);
    std::array<int64_t, 3> abs_row{}, sq_row{};
    for (int x = 0; x < reference.width; ++x) {
      for (int c = 0; c < 3; ++c) {
        const int diff =
            int(a[size_t(x) * reference.channels + c]) - int(b[size_t(x) * test.channels + c]);
        abs_row[c] += diff < 0 ? -diff : diff;
        sq_row[c] += diff * diff;
      }
    }
    for (int c = 0; c < 3; ++c) {
      d.mae[c] += double(abs_row[c]);
      squared_sum += double(sq_row[c]);
    }
  }
  for (double& m : d.mae) m /= pixels;
  d.mae_mean = (d.mae[0] + d.mae[1] + d.mae[2]) / 3;

  // PSNR = 10 log10(peak^2 / MSE), MSE over all RGB samples.
  const double mse = squared_sum / (3 * pixels);
  d.psnr =
      mse == 0 ? std::numeric_limits<double>::infinity() : 10 * std::log10(255.0 * 255.0 / mse);

  d.ssim = mean_ssim(reference, test);
  return d;
}

}  // namespace subvec
