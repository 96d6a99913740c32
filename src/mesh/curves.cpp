#include "subvec/mesh/curves.h"

#include <algorithm>

namespace subvec {
namespace {

// Control point i of the extended sequence: phantoms past the ends (open), wrap-around (closed).
Vec2 control(std::span<const Vec2> p, bool closed, long i) {
  const long n = static_cast<long>(p.size());
  if (closed) return p[static_cast<size_t>(((i % n) + n) % n)];
  if (i < 0) return {2 * p[0].x - p[1].x, 2 * p[0].y - p[1].y};
  if (i >= n) return {2 * p[n - 1].x - p[n - 2].x, 2 * p[n - 1].y - p[n - 2].y};
  return p[static_cast<size_t>(i)];
}

}  // namespace

Vec2 eval_bspline(std::span<const Vec2> points, bool closed, int span, double t) {
  const Vec2 a = control(points, closed, span - 1), b = control(points, closed, span);
  const Vec2 c = control(points, closed, span + 1), d = control(points, closed, span + 2);
  const double s = 1 - t, t2 = t * t, t3 = t2 * t;
  const double w0 = s * s * s / 6, w1 = (3 * t3 - 6 * t2 + 4) / 6;
  const double w2 = (-3 * t3 + 3 * t2 + 3 * t + 1) / 6, w3 = t3 / 6;
  return {w0 * a.x + w1 * b.x + w2 * c.x + w3 * d.x, w0 * a.y + w1 * b.y + w2 * c.y + w3 * d.y};
}

std::vector<Vec2> sample_bspline(std::span<const Vec2> points, bool closed, int per_span) {
  if (points.size() < (closed ? 3u : 2u)) return {points.begin(), points.end()};
  per_span = std::max(per_span, 1);
  const int spans = static_cast<int>(points.size()) - (closed ? 0 : 1);
  std::vector<Vec2> out;
  out.reserve(size_t(spans) * per_span + 1);
  for (int s = 0; s < spans; ++s)
    for (int k = 0; k < per_span; ++k) out.push_back(eval_bspline(points, closed, s, double(k) / per_span));
  out.push_back(closed ? out.front() : points.back());
  return out;
}

}  // namespace subvec
