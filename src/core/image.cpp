#include "subvec/core/image.h"

#include <algorithm>

namespace subvec {

std::array<double, 3> sample_bilinear(const Image8& image, double x, double y) {
  const double fx = std::clamp(x - 0.5, 0.0, double(image.width - 1));
  const double fy = std::clamp(y - 0.5, 0.0, double(image.height - 1));
  const int x0 = std::min(int(fx), image.width - 1), y0 = std::min(int(fy), image.height - 1);
  const int x1 = std::min(x0 + 1, image.width - 1), y1 = std::min(y0 + 1, image.height - 1);
  const double ax = fx - x0, ay = fy - y0;
  const uint8_t* r0 = image.row(y0);
  const uint8_t* r1 = image.row(y1);
  const int c = image.channels;
  std::array<double, 3> out;
  for (int k = 0; k < 3; ++k) {
    out[k] = (1 - ay) * ((1 - ax) * r0[x0 * c + k] + ax * r0[x1 * c + k]) +
             ay * ((1 - ax) * r1[x0 * c + k] + ax * r1[x1 * c + k]);
  }
  return out;
}

}  // namespace subvec
