// Measures of rendered vector images (image_measures.h).
#include "support/image_measures.h"

#include <algorithm>
#include <cmath>

#include "mesh/polyline_p.h"
#include "subvec/mesh/curves.h"
#include "subvec/render/renderer.h"

namespace subvec::test {

std::vector<uint8_t> away_from_features(const VectorImage& image, double margin) {
  std::vector<uint8_t> away(size_t(image.width) * image.height, 1);
  for (const Feature& f : image.levels[0].features) {
    for (size_t i = 0; i + 1 < f.vertices.size(); ++i) {
      const Vec2 a = image.levels[0].positions[f.vertices[i]], b = image.levels[0].positions[f.vertices[i + 1]];
      const int steps = static_cast<int>(std::ceil(std::hypot(b.x - a.x, b.y - a.y) * 2)) + 1;
      for (int s = 0; s <= steps; ++s) {
        const double x = a.x + (b.x - a.x) * s / steps, y = a.y + (b.y - a.y) * s / steps;
        for (int py = std::max(0, int(y - margin - 1)); py <= std::min(image.height - 1, int(y + margin + 1)); ++py)
          for (int px = std::max(0, int(x - margin - 1)); px <= std::min(image.width - 1, int(x + margin + 1)); ++px)
            if (std::hypot(px + 0.5 - x, py + 0.5 - y) <= margin) away[size_t(py) * image.width + px] = 0;
      }
    }
  }
  return away;
}

namespace {

// Mean squared 5-point Laplacian over the interior pixels that `mask` keeps, channels summed;
// `at(x, y, channel)` gives a pixel's value.
template <class At>
double masked_laplacian_energy(int width, int height, const std::vector<uint8_t>& mask, At at) {
  double sum = 0;
  int n = 0;
  for (int y = 1; y + 1 < height; ++y) {
    for (int x = 1; x + 1 < width; ++x) {
      if (!mask[size_t(y) * width + x]) continue;
      for (int k = 0; k < 3; ++k) {
        const double l = at(x - 1, y, k) + at(x + 1, y, k) + at(x, y - 1, k) + at(x, y + 1, k) -
                         4 * at(x, y, k);
        sum += l * l;
      }
      ++n;
    }
  }
  return sum / std::max(n, 1);
}

}  // namespace

double laplacian_energy(const Image8& img, const std::vector<uint8_t>& mask) {
  return masked_laplacian_energy(img.width, img.height, mask,
                                 [&](int x, int y, int k) { return double(img.row(y)[3 * x + k]); });
}

double fine_laplacian_energy(const VectorImage& image, const std::vector<uint8_t>& mask) {
  constexpr int kRenders = 16;
  const int w = image.width, h = image.height;
  std::vector<double> sum(size_t(w) * h * 3, 0);
  Renderer renderer(image);  // refines once; each offset only re-evaluates the colors
  std::vector<Color> shifted(image.levels[0].colors.size());
  Image8 img;
  for (int j = 0; j < kRenders; ++j) {
    const float offset = static_cast<float>((j + 0.5) / kRenders - 0.5);
    for (size_t k = 0; k < shifted.size(); ++k) {
      const Color c = image.levels[0].colors[k];
      shifted[k] = {c.r + offset, c.g + offset, c.b + offset};
    }
    renderer.set_colors(0, shifted);
    renderer.render({}, img);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < 3 * w; ++x) sum[size_t(y) * w * 3 + x] += img.row(y)[x];
  }
  return masked_laplacian_energy(w, h, mask, [&](int x, int y, int k) {
    return sum[(size_t(y) * w + x) * 3 + k] / kRenders;
  });
}

double contrast_across(const Image8& img, const ControlMesh& mesh, const Feature& f, double offset) {
  std::vector<Vec2> points;
  for (size_t i = 0; i + (f.closed() ? 1 : 0) < f.vertices.size(); ++i) points.push_back(mesh.positions[f.vertices[i]]);
  const std::vector<Vec2> curve = sample_bspline(points, f.closed(), 8);
  double sum = 0;
  int n = 0;
  detail::walk(curve, 1.0, [&](Vec2 p, Vec2 t) {
    const auto a = sample_bilinear(img, p.x - t.y * offset, p.y + t.x * offset);
    const auto b = sample_bilinear(img, p.x + t.y * offset, p.y - t.x * offset);
    sum += std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    ++n;
  });
  return n ? sum / n : 0;
}

}  // namespace subvec::test
