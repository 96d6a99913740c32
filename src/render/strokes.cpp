// Stroke drawing (strokes_p.h).
//
// A stroke is flattened, in output pixels, into a polyline of chords at most about 2 pixels long
// (at most 256 per span), and each chord is drawn as a capsule whose radius varies linearly along
// it (the taper). Coverage of a pixel by a capsule of radius r whose axis passes at distance d
// from the pixel centre is the box-filtered band coverage clamp(min(d + r, 1/2) - max(d - r, -1/2),
// 0, 1), exact for a straight band and right for strokes thinner than a pixel. Within one stroke
// the coverage is the maximum over its chords (joints are not darkened twice); strokes are
// composited one after another.
#include <algorithm>
#include <cmath>
#include <vector>

#include "render/strokes_p.h"
#include "subvec/mesh/curves.h"

namespace subvec::detail {
namespace {

uint8_t to_u8(float v) {
  v = v > 0.f ? v : 0.f;
  v = v < 255.f ? v : 255.f;
  return static_cast<uint8_t>(static_cast<int>(v + 0.5f));
}

struct Chord {
  float x0, y0, x1, y1, r0, r1;
};

}  // namespace

void draw_strokes(std::span<const Stroke> strokes, int level, const ViewTransform& view, Image8& out) {
  draw_strokes(strokes, level, view, PixelRect{0, 0, out.width, out.height}, out);
}

void draw_strokes(std::span<const Stroke> strokes, int level, const ViewTransform& view,
                  const PixelRect& clip, Image8& out) {
  const int width = view.width, height = view.height;
  const double scale = std::sqrt(view.sx * view.sy);
  std::vector<float> coverage;
  std::vector<Chord> chords;
  for (const Stroke& stroke : strokes) {
    if (stroke.level != level || stroke.points.size() < 2) continue;
    const double half = 0.5 * stroke.width * scale;
    // Control points in output pixels, and a bound of the stroke (the curve lies in their hull).
    std::vector<Vec2> points;
    double bx0 = INFINITY, by0 = INFINITY, bx1 = -INFINITY, by1 = -INFINITY, longest = 0;
    for (size_t i = 0; i < stroke.points.size(); ++i) {
      const auto o = view.to_output(stroke.points[i].x, stroke.points[i].y);
      points.push_back({o[0], o[1]});
      bx0 = std::min(bx0, o[0]), by0 = std::min(by0, o[1]);
      bx1 = std::max(bx1, o[0]), by1 = std::max(by1, o[1]);
      if (i > 0) longest = std::max(longest, std::hypot(o[0] - points[i - 1].x, o[1] - points[i - 1].y));
    }
    // The phantom end points reach one span past the ends.
    bx0 -= longest + half + 1, by0 -= longest + half + 1, bx1 += longest + half + 1, by1 += longest + half + 1;
    if (!(bx1 >= 0 && by1 >= 0 && bx0 <= width && by0 <= height)) continue;
    const int per_span = static_cast<int>(std::clamp(std::ceil(longest / 2), 1.0, 256.0));
    const std::vector<Vec2> line = sample_bspline(points, false, per_span);

    // Arc length, then the taper: radius half * min(1, s / (taper L), (L - s) / (taper L)).
    std::vector<double> at(line.size(), 0);
    for (size_t i = 1; i < line.size(); ++i)
      at[i] = at[i - 1] + std::hypot(line[i].x - line[i - 1].x, line[i].y - line[i - 1].y);
    const double length = at.back(), ramp = stroke.taper * length;
    auto radius = [&](double s) {
      if (ramp <= 0) return half;
      return half * std::min({1.0, s / ramp, (length - s) / ramp});
    };
    chords.clear();
    for (size_t i = 0; i + 1 < line.size(); ++i) {
      chords.push_back({float(line[i].x), float(line[i].y), float(line[i + 1].x), float(line[i + 1].y),
                        float(std::max(0.0, radius(at[i]))), float(std::max(0.0, radius(at[i + 1])))});
    }

    // Coverage over the stroke's pixels, clipped to the frame.
    const int x0 = std::max(clip.x0, static_cast<int>(std::floor(std::max(bx0, -1.0))));
    const int y0 = std::max(clip.y0, static_cast<int>(std::floor(std::max(by0, -1.0))));
    const int x1 = std::min(clip.x1 - 1, static_cast<int>(std::min(bx1, double(width))));
    const int y1 = std::min(clip.y1 - 1, static_cast<int>(std::min(by1, double(height))));
    if (x0 > x1 || y0 > y1) continue;
    const int cw = x1 - x0 + 1, ch = y1 - y0 + 1;
    coverage.assign(size_t(cw) * ch, 0.f);
    for (const Chord& c : chords) {
      const float reach = std::max(c.r0, c.r1) + 1.f;
      const int px0 = std::max(x0, static_cast<int>(std::floor(std::min(c.x0, c.x1) - reach)));
      const int px1 = std::min(x1, static_cast<int>(std::floor(std::max(c.x0, c.x1) + reach)));
      const int py0 = std::max(y0, static_cast<int>(std::floor(std::min(c.y0, c.y1) - reach)));
      const int py1 = std::min(y1, static_cast<int>(std::floor(std::max(c.y0, c.y1) + reach)));
      const float dx = c.x1 - c.x0, dy = c.y1 - c.y0, len2 = dx * dx + dy * dy;
      for (int py = py0; py <= py1; ++py) {
        float* row = coverage.data() + size_t(py - y0) * cw;
        const float y = float(py) + 0.5f;
        for (int px = px0; px <= px1; ++px) {
          const float x = float(px) + 0.5f;
          float u = len2 > 0 ? ((x - c.x0) * dx + (y - c.y0) * dy) / len2 : 0.f;
          u = std::clamp(u, 0.f, 1.f);
          const float ex = x - (c.x0 + u * dx), ey = y - (c.y0 + u * dy);
          const float d = std::sqrt(ex * ex + ey * ey), r = c.r0 + u * (c.r1 - c.r0);
          const float cov = std::min(d + r, 0.5f) - std::max(d - r, -0.5f);
          row[px - x0] = std::max(row[px - x0], std::clamp(cov, 0.f, 1.f));
        }
      }
    }
    // Source-over with straight alpha.
    const float color[3] = {stroke.color.r, stroke.color.g, stroke.color.b};
    for (int py = y0; py <= y1; ++py) {
      const float* row = coverage.data() + size_t(py - y0) * cw;
      uint8_t* dst = out.row(py - clip.y0);
      for (int px = x0; px <= x1; ++px) {
        const float a = row[px - x0];
        if (a <= 0.f) continue;
        uint8_t* p = dst + size_t(px) * out.channels;
        const float da = out.channels == 4 ? p[3] / 255.f : 1.f;
        const float oa = a + da * (1.f - a);
        for (int k = 0; k < 3; ++k) {
          p[k] = to_u8((std::clamp(color[k], 0.f, 255.f) * a + p[k] * da * (1.f - a)) / oa);
        }
        if (out.channels == 4) p[3] = to_u8(oa * 255.f);
      }
    }
  }
}

}  // namespace subvec::detail
