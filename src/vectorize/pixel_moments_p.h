// Sums over the pixel centres inside a triangle, for quantities that are affine over it.
//
// Refinement (refine.cpp) measures a triangle's error under a linear color interpolation and sums a
// vertex's Gauss-Newton system over its one-ring. Every per-pixel term there is a product of two
// functions that are affine in the pixel centre s (barycentric weights, interpolated colors, their
// derivatives), or of one such function and the pixel's color t. So each sum is fixed by a handful
// of moments of the triangle's pixels: the count, Σu, Σv, Σu², Σuv, Σv² of the centres (u, v
// relative to an origin near the triangle, so that no sum cancels large numbers), and per channel
// Σt, Σtu, Σtv, with Σt² over the channels. Along a row u steps by one, so the centres' moments of
// each row's span are closed forms, and the image enters only through integer sums of t and of t
// times the column: a few integer adds per pixel instead of the terms' dozens of multiplications.
//
// for_each_pixel() visits the same pixels one by one: the slow, obvious reference
// (tests/unit/vectorize/pixel_moments_test.cpp).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "mesh/collapse_p.h"  // signed_area
#include "subvec/core/image.h"

namespace subvec::detail {

// c + u (s.x - origin.x) + v (s.y - origin.y) for a point s, about an origin given elsewhere.
struct Affine {
  double c = 0, u = 0, v = 0;

  Affine operator+(const Affine& b) const { return {c + b.c, u + b.u, v + b.v}; }
  Affine operator-(const Affine& b) const { return {c - b.c, u - b.u, v - b.v}; }
  Affine operator*(double k) const { return {c * k, u * k, v * k}; }
  double at(double du, double dv) const { return c + u * du + v * dv; }
};

// Barycentric weights of a triangle (p0, p1, p2) of non-zero area as affine functions about
// `origin`: w[i](s) = area of the triangle with s in place of p[i], over the triangle's area.
inline std::array<Affine, 3> barycentric(Vec2 p0, Vec2 p1, Vec2 p2, Vec2 origin) {
  const double inv = 1 / signed_area(p0, p1, p2);
  // area(s, q, r) = ((q.x - s.x)(r.y - s.y) - (r.x - s.x)(q.y - s.y)) / 2, affine in s.
  auto weight = [&](Vec2 q, Vec2 r) {
    return Affine{signed_area(origin, q, r), 0.5 * (q.y - r.y), 0.5 * (r.x - q.x)} * inv;
  };
  return {weight(p1, p2), weight(p2, p0), weight(p0, p1)};
}

// Calls row(y, xa, xb) for every image row y with pixel centres (x + 0.5, y + 0.5) inside the
// triangle (p0, p1, p2) of either orientation, xa..xb being those x (a pixel centre on an edge is
// inside). Returns false, and visits nothing, when the triangle's area is at most `min_area`. The
// weights are affine, so the inside of a row is one span: found from each weight's zero crossing
// with a pixel of slack, then tightened by the weights themselves.
template <class Row>
bool for_each_row(Vec2 p0, Vec2 p1, Vec2 p2, int width, int height, double min_area, const Row& row) {
  const double area = signed_area(p0, p1, p2);
  if (!(std::abs(area) > min_area)) return false;
  const double inv = 1 / area;
  const int x0 = std::max(0, static_cast<int>(std::ceil(std::min({p0.x, p1.x, p2.x}) - 0.5)));
  const int x1 = std::min(width - 1, static_cast<int>(std::floor(std::max({p0.x, p1.x, p2.x}) - 0.5)));
  const int y0 = std::max(0, static_cast<int>(std::ceil(std::min({p0.y, p1.y, p2.y}) - 0.5)));
  const int y1 = std::min(height - 1, static_cast<int>(std::floor(std::max({p0.y, p1.y, p2.y}) - 0.5)));
  // w_i at the centre (x0 + 0.5, y0 + 0.5), and its steps along x and y.
  const Vec2 start{x0 + 0.5, y0 + 0.5};
  const double s0 = signed_area(start, p1, p2) * inv, s1 = signed_area(p0, start, p2) * inv;
  const std::array<double, 3> s{s0, s1, 1 - s0 - s1};
  const double d0 = 0.5 * (p1.y - p2.y) * inv, d1 = 0.5 * (p2.y - p0.y) * inv;
  const std::array<double, 3> d{d0, d1, -d0 - d1};
  const double e0 = 0.5 * (p2.x - p1.x) * inv, e1 = 0.5 * (p0.x - p2.x) * inv;
  const std::array<double, 3> e{e0, e1, -e0 - e1};
  std::array<double, 3> inv_d{};
  for (int i = 0; i < 3; ++i) inv_d[i] = d[i] != 0 ? 1 / d[i] : 0;
  for (int y = y0; y <= y1; ++y) {
    // w_i(x) = r_i + (x - x0) d_i >= 0 for all three: a span, found with a pixel of slack.
    std::array<double, 3> r;
    for (int i = 0; i < 3; ++i) r[i] = s[i] + (y - y0) * e[i];
    double lo = x0, hi = x1;
    bool empty = false;
    for (int i = 0; i < 3; ++i) {
      if (d[i] > 0) lo = std::max(lo, x0 - r[i] * inv_d[i] - 1);
      else if (d[i] < 0) hi = std::min(hi, x0 - r[i] * inv_d[i] + 1);
      else if (r[i] < 0) empty = true;
    }
    if (empty || lo > hi) continue;
    auto inside = [&](int x) {
      const double w0 = r[0] + (x - x0) * d[0], w1 = r[1] + (x - x0) * d[1];
      return w0 >= 0 && w1 >= 0 && 1 - w0 - w1 >= 0;
    };
    int xa = std::max(x0, static_cast<int>(std::ceil(lo))), xb = std::min(x1, static_cast<int>(std::floor(hi)));
    while (xa <= xb && !inside(xa)) ++xa;
    while (xb >= xa && !inside(xb)) --xb;
    if (xa <= xb) row(y, xa, xb);
  }
  return true;
}

// Calls fn(x, y) for every pixel centre inside the triangle, as for_each_row() finds them.
template <class Fn>
bool for_each_pixel(Vec2 p0, Vec2 p1, Vec2 p2, int width, int height, double min_area, const Fn& fn) {
  return for_each_row(p0, p1, p2, width, height, min_area, [&](int y, int xa, int xb) {
    for (int x = xa; x <= xb; ++x) fn(x, y);
  });
}

// The moments of the pixel centres inside one triangle and of their colors (the first three
// channels), the centres taken relative to `origin`.
struct PixelMoments {
  Vec2 origin;
  double n = 0, su = 0, sv = 0, suu = 0, suv = 0, svv = 0;
  std::array<double, 3> t{}, tu{}, tv{};  // per channel: Σt, Σtu, Σtv
  double tt = 0;                          // Σt² over the three channels

  // Σ a(s) b(s) over the pixel centres.
  double sum(const Affine& a, const Affine& b) const {
    return a.c * b.c * n + (a.c * b.u + a.u * b.c) * su + (a.c * b.v + a.v * b.c) * sv + a.u * b.u * suu +
           (a.u * b.v + a.v * b.u) * suv + a.v * b.v * svv;
  }
  // Σ a(s) t(s) over the pixel centres, for channel ch.
  double sum_t(const Affine& a, int ch) const { return a.c * t[ch] + a.u * tu[ch] + a.v * tv[ch]; }
};

// The moments of the triangle (p0, p1, p2) about `origin`; false when its area is at most
// `min_area` (and then `m` is left empty).
inline bool pixel_moments(const Image8& image, Vec2 p0, Vec2 p1, Vec2 p2, Vec2 origin, double min_area,
                          PixelMoments& m) {
  m = PixelMoments{};
  m.origin = origin;
  const int stride = image.channels;
  return for_each_row(p0, p1, p2, image.width, image.height, min_area, [&](int y, int xa, int xb) {
    // The image's part: integer sums over the span, the column counted from xa.
    const uint8_t* px = image.row(y) + size_t(xa) * stride;
    int64_t t0 = 0, t1 = 0, t2 = 0, k0 = 0, k1 = 0, k2 = 0, tt = 0;
    for (int k = 0; k <= xb - xa; ++k, px += stride) {
      const int r = px[0], g = px[1], b = px[2];
      t0 += r, t1 += g, t2 += b;
      k0 += k * r, k1 += k * g, k2 += k * b;
      tt += r * r + g * g + b * b;
    }
    // The centres' part: u = ua + k for k = 0 .. count - 1, v constant along the row.
    const double count = xb - xa + 1, ua = xa + 0.5 - origin.x, v = y + 0.5 - origin.y;
    const double sk = count * (count - 1) / 2, skk = (count - 1) * count * (2 * count - 1) / 6;
    const double su = count * ua + sk, suu = count * ua * ua + 2 * ua * sk + skk;
    m.n += count, m.su += su, m.sv += count * v;
    m.suu += suu, m.suv += su * v, m.svv += count * v * v;
    const std::array<double, 3> ts{double(t0), double(t1), double(t2)}, ks{double(k0), double(k1), double(k2)};
    for (int ch = 0; ch < 3; ++ch) {
      m.t[ch] += ts[ch];
      m.tu[ch] += ks[ch] + ua * ts[ch];
      m.tv[ch] += v * ts[ch];
    }
    m.tt += double(tt);
  });
}

}  // namespace subvec::detail
