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
#include "subvec/core/metrics.h"

#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

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

// One channel of an interleaved image as a double matrix.
cv::Mat channel_plane(const Image8& image, int channel) {
  cv::Mat plane(image.height, image.width, CV_64F);
  for (int y = 0; y < image.height; ++y) {
    const uint8_t* src = image.row(y);
    double* dst = plane.ptr<double>(y);
    for (int x = 0; x < image.width; ++x) dst[x] = src[size_t(x) * image.channels + channel];
  }
  return plane;
}

cv::Mat gaussian(const cv::Mat& m) {
  cv::Mat out;
  cv::GaussianBlur(m, out, cv::Size(11, 11), 1.5, 1.5, cv::BORDER_REFLECT_101);
  return out;
}

double ssim_channel(const cv::Mat& x, const cv::Mat& y) {
  constexpr double kL = 255, kC1 = (0.01 * kL) * (0.01 * kL), kC2 = (0.03 * kL) * (0.03 * kL);
  const cv::Mat mu_x = gaussian(x), mu_y = gaussian(y);
  const cv::Mat mu_xx = mu_x.mul(mu_x), mu_yy = mu_y.mul(mu_y), mu_xy = mu_x.mul(mu_y);
  // Local (co)variances: E[xy] - E[x]E[y] under the window.
  const cv::Mat var_x = gaussian(x.mul(x)) - mu_xx;
  const cv::Mat var_y = gaussian(y.mul(y)) - mu_yy;
  const cv::Mat cov_xy = gaussian(x.mul(y)) - mu_xy;
  const cv::Mat numerator = (2 * mu_xy + kC1).mul(2 * cov_xy + kC2);
  const cv::Mat denominator = (mu_xx + mu_yy + kC1).mul(var_x + var_y + kC2);
  cv::Mat map;
  cv::divide(numerator, denominator, map);
  return cv::mean(map)[0];
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

  double ssim_sum = 0;
  for (int c = 0; c < 3; ++c)
    ssim_sum += ssim_channel(channel_plane(reference, c), channel_plane(test, c));
  d.ssim = ssim_sum / 3;
  return d;
}

}  // namespace subvec
