// 8-bit raster images: what the renderer produces and the metrics compare.
#pragma once

#include <cstddef>
#include <array>
#include <cstdint>
#include <vector>

namespace subvec {

// Interleaved 8-bit pixels, rows top to bottom, channels 3 (RGB) or 4 (RGBA, straight alpha).
struct Image8 {
  int width = 0, height = 0, channels = 3;
  std::vector<uint8_t> pixels;  // height * width * channels

  Image8() = default;
  Image8(int w, int h, int c) : width(w), height(h), channels(c), pixels(size_t(w) * h * c) {}
  uint8_t* row(int y) { return pixels.data() + size_t(y) * width * channels; }
  const uint8_t* row(int y) const { return pixels.data() + size_t(y) * width * channels; }
};

// Bilinear sample of the RGB channels at image coordinates (x, y), pixel centres at +0.5; clamped
// to the image. Values on the 0-255 scale.
std::array<double, 3> sample_bilinear(const Image8& image, double x, double y);

}  // namespace subvec
