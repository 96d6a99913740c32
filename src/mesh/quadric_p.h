// The 5D quadric error metric of simplification and of the levels (paper §4, "Mesh
// simplification": Garland & Heckbert's quadrics with the color channels as height fields, and §5,
// whose coarsening between levels uses the same metric). One quadric, built one way, for both.
//
// Design note. Q(x) = x'Ax + 2b'x + c over x = (x, y, r, g, b), colors scaled by the caller's
// color_scale. Quadrics live on color values, not vertices: a vertex on a tear has one color per
// side and each side sums its own faces. A is symmetric and kept as its upper triangle, row by row
// (xx xy xr xg xb | yy yr yg yb | rr rg rb | gg gb | bb): 21 doubles padded to three cache lines,
// so that merging and reducing two quadrics touch six lines. Colors are eliminated in closed form
// (the Schur complement of the color block), leaving a 2D quadric in the position: the cost of a
// placement is cheap, and the best point on an edge has a closed form.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "core/parallel_p.h"

namespace subvec::detail {

using Point5 = std::array<double, 5>;  // (x, y, r, g, b)

struct alignas(64) Quadric5 {
  std::array<double, 15> a{};  // upper triangle of A, row by row
  std::array<double, 5> b{};
  double c = 0;
  Quadric5& operator+=(const Quadric5& o) {
    for (int i = 0; i < 15; ++i) a[i] += o.a[i];
    for (int i = 0; i < 5; ++i) b[i] += o.b[i];
    c += o.c;
    return *this;
  }
  // Q(x).
  double operator()(const Point5& x) const;
};

// Index of A(i, j) in Quadric5::a, i <= j.
constexpr int packed_index(int i, int j) { return i * 5 - i * (i - 1) / 2 + (j - i); }

// The quadric of the plane through three 5D points (the squared distance to it), weighted by the
// triangle's area in xy. Zero for a degenerate triangle.
Quadric5 plane_quadric(const Point5& p, const Point5& q, const Point5& r);

// The quadric with the colors minimized out: R(p) = p'Mp + 2g'p + k over positions p, with M
// symmetric (m00, m01, m11).
struct Quadric2 {
  double m00 = 0, m01 = 0, m11 = 0, g0 = 0, g1 = 0, k = 0;
  double operator()(double x, double y) const {
    return x * (m00 * x + m01 * y) + y * (m01 * x + m11 * y) + 2 * (g0 * x + g1 * y) + k;
  }
  Quadric2& operator+=(const Quadric2& o) {
    m00 += o.m00, m01 += o.m01, m11 += o.m11, g0 += o.g0, g1 += o.g1, k += o.k;
    return *this;
  }
};

// min over the colors of q(p, colors), as a quadric in p (the color block regularized by 1e-9 I).
Quadric2 reduce(const Quadric5& q);

// The colors minimizing q at position (x, y) (same regularization).
std::array<double, 3> best_color(const Quadric5& q, double x, double y);

// A collapse along an edge merges the quadrics side by side: for each of the `npairs` (color of u,
// color of v) on the edge (collapse_p.h, edge_color_pairs), u's quadric into v's.
template <class Quadrics>
void merge_side_by_side(Quadrics& quadrics, const std::array<std::array<int32_t, 2>, 2>& pairs, int npairs) {
  for (int i = 0; i < npairs; ++i) quadrics[pairs[i][1]] += quadrics[pairs[i][0]];
}

// The quadric of every color value: the sum, in face order, of the plane quadrics of the faces with
// a corner of that value. `corner(f, k, point)` returns the color index of corner k of face f and
// sets its 5D point. The color indices are cut into ranges over up to `threads` threads; each
// visits every face and computes the quadric of those with a corner in its range (when colors
// follow the vertex order, few faces straddle two ranges and are computed twice). The sums do not
// depend on the thread count.
template <class Corner>
std::vector<Quadric5> color_quadrics(int num_faces, int num_colors, int threads, const Corner& corner) {
  std::vector<Quadric5> quadric(num_colors);
  const int parts = std::min(resolve_threads(threads), std::max(1, num_colors / 4096));
  parallel_for(parts, parts, [&](int part) {
    const int32_t begin = static_cast<int32_t>(int64_t(num_colors) * part / parts);
    const int32_t end = static_cast<int32_t>(int64_t(num_colors) * (part + 1) / parts);
    for (int f = 0; f < num_faces; ++f) {
      Point5 p[3];
      int32_t color[3];
      bool any = false;
      for (int k = 0; k < 3; ++k) {
        color[k] = corner(f, k, p[k]);
        any |= color[k] >= begin && color[k] < end;
      }
      if (!any) continue;
      const Quadric5 q = plane_quadric(p[0], p[1], p[2]);
      for (int k = 0; k < 3; ++k)
        if (color[k] >= begin && color[k] < end) quadric[color[k]] += q;
    }
  });
  return quadric;
}

}  // namespace subvec::detail
