// Two renderers' frames of one view, compared channel value by channel value (alpha included): the
// GPU renderer against the CPU renderer in tests/gpu and bench/gpu_bench.cpp. Unlike compare()
// (subvec/core/metrics.h) it keeps the largest difference, counts alpha and computes no SSIM.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdlib>

#include "subvec/core/image.h"

namespace subvec::test {

struct FrameDifference {
  double mae = 0;  // mean absolute difference over every channel value
  int max = 0;     // largest channel difference
};

// Frames of different sizes or channel counts, or empty ones, are as far apart as can be.
inline FrameDifference frame_difference(const Image8& a, const Image8& b) {
  if (a.width != b.width || a.height != b.height || a.channels != b.channels || a.pixels.empty()) {
    return {255, 255};
  }
  FrameDifference d;
  int64_t sum = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    const int e = std::abs(int(a.pixels[i]) - int(b.pixels[i]));
    sum += e;
    d.max = std::max(d.max, e);
  }
  d.mae = double(sum) / double(a.pixels.size());
  return d;
}

}  // namespace subvec::test
