// Shared by the pyramid tests: a synthetic photograph with features of many lengths and contrasts,
// vectorized once with three levels.
#pragma once

#include <cmath>
#include <filesystem>

#include "subvec/core/image.h"
#include "subvec/vectorize/levels.h"
#include "subvec/vectorize/vectorize.h"

namespace subvec::test {

// Shapes over a textured background, anti-aliased by 4x4 supersampling: a large high-contrast disk,
// a rectangle, and small blobs of falling contrast, so that saliency orders them.
inline Image8 shapes_image(int w = 192, int h = 144) {
  Image8 img(w, h, 3);
  struct Blob {
    double cx, cy, rx, ry;
    double color[3];
    bool box;
  };
  const Blob blobs[] = {
      {60, 62, 34, 34, {235, 210, 40}, false},  {145, 45, 30, 20, {30, 40, 160}, true},
      {150, 110, 16, 12, {200, 90, 90}, false}, {35, 125, 12, 9, {150, 150, 120}, true},
      {105, 125, 9, 7, {120, 140, 110}, false}, {178, 132, 6, 6, {130, 120, 100}, false},
      {100, 20, 10, 6, {140, 100, 100}, true},
  };
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      double acc[3] = {0, 0, 0};
      for (int sy = 0; sy < 4; ++sy) {
        for (int sx = 0; sx < 4; ++sx) {
          const double px = x + (sx + 0.5) / 4, py = y + (sy + 0.5) / 4;
          // A smooth background with fine texture (a few pixels across, like foliage or fabric):
          // the detail that smoothing should take away.
          const double texture = 14 * std::sin(px * 0.9 + 2 * std::sin(py * 0.31)) * std::sin(py * 0.7);
          double c[3] = {90 + 60.0 * px / w + texture, 110 + 30 * std::sin(py / 17) + texture, 120 - 50.0 * py / h};
          for (const Blob& b : blobs) {
            const double dx = (px - b.cx) / b.rx, dy = (py - b.cy) / b.ry;
            const bool in = b.box ? std::abs(dx) < 1 && std::abs(dy) < 1 : dx * dx + dy * dy < 1;
            if (!in) continue;
            for (int k = 0; k < 3; ++k) c[k] = b.color[k] + 0.15 * (px - b.cx);
          }
          for (int k = 0; k < 3; ++k) acc[k] += c[k] / 16;
        }
      }
      uint8_t* p = img.row(y) + 3 * x;
      for (int k = 0; k < 3; ++k) p[k] = static_cast<uint8_t>(std::clamp(std::lround(acc[k]), 0L, 255L));
    }
  }
  return img;
}

inline VectorImage shapes_levels(const Image8& img, LevelOptions options = {}, LevelReport* report = nullptr) {
  VectorizeOptions v;
  v.ratio = 0.04;
  v.levels.levels = 1;  // built below with `options`
  VectorImage image = vectorize(img, v);
  build_levels(image, img, options, report);
  return image;
}

inline std::filesystem::path shared_images() {
  return std::filesystem::path(SUBVEC_SOURCE_DIR) / ".." / "shared" / "images";
}

}  // namespace subvec::test
