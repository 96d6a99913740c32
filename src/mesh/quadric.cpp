// The 5D quadric error metric; see quadric_p.h.
#include "mesh/quadric_p.h"

#include <cmath>

namespace subvec::detail {
namespace {

// Sums in the order of Eigen's vectorized 5-vector reductions (which earlier versions called):
// the same bits, a third of the instructions.
double dot5(const Point5& a, const Point5& b) {
  return ((a[0] * b[0] + a[2] * b[2]) + (a[1] * b[1] + a[3] * b[3])) + a[4] * b[4];
}

// The color block of a quadric, regularized, as the adjugate C (symmetric: c00 c01 c02 c11 c12
// c22) and determinant of Acc + 1e-9 I: (Acc + 1e-9 I)^-1 = C / det.
struct ColorInverse {
  double c00, c01, c02, c11, c12, c22, det;
};
ColorInverse color_inverse(const std::array<double, 15>& a) {
  constexpr double kEps = 1e-9;
  const double rr = a[9] + kEps, rg = a[10], rb = a[11], gg = a[12] + kEps, gb = a[13], bb = a[14] + kEps;
  ColorInverse v;
  v.c00 = gg * bb - gb * gb;
  v.c01 = rb * gb - rg * bb;
  v.c02 = rg * gb - rb * gg;
  v.c11 = rr * bb - rb * rb;
  v.c12 = rg * rb - rr * gb;
  v.c22 = rr * gg - rg * rg;
  v.det = rr * v.c00 + rg * v.c01 + rb * v.c02;
  return v;
}

}  // namespace

double Quadric5::operator()(const Point5& x) const {
  double s = 2 * dot5(b, x) + c;
  for (int i = 0; i < 5; ++i) {
    s += a[packed_index(i, i)] * x[i] * x[i];
    for (int j = i + 1; j < 5; ++j) s += 2 * a[packed_index(i, j)] * x[i] * x[j];
  }
  return s;
}

Quadric5 plane_quadric(const Point5& p, const Point5& q, const Point5& r) {
  Quadric5 out;
  Point5 e1, e2;  // orthonormal, spanning the triangle's plane
  for (int i = 0; i < 5; ++i) e1[i] = q[i] - p[i];
  const double l1 = std::sqrt(dot5(e1, e1));
  if (l1 <= 0) return out;
  for (int i = 0; i < 5; ++i) e1[i] /= l1;
  for (int i = 0; i < 5; ++i) e2[i] = r[i] - p[i];
  const double along = dot5(e1, e2);
  for (int i = 0; i < 5; ++i) e2[i] -= along * e1[i];
  const double l2 = std::sqrt(dot5(e2, e2));
  if (l2 <= 0) return out;
  for (int i = 0; i < 5; ++i) e2[i] /= l2;
  const double area = 0.5 * std::abs((q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]));
  const double pe1 = dot5(p, e1), pe2 = dot5(p, e2);
  // A = area (I - e1 e1' - e2 e2'), b = area (pe1 e1 + pe2 e2 - p), c = area (p'p - pe1^2 - pe2^2).
  for (int i = 0, n = 0; i < 5; ++i)
    for (int j = i; j < 5; ++j) out.a[n++] = area * (((i == j ? 1.0 : 0.0) - e1[i] * e1[j]) - e2[i] * e2[j]);
  for (int i = 0; i < 5; ++i) out.b[i] = area * ((pe1 * e1[i] + pe2 * e2[i]) - p[i]);
  out.c = area * ((dot5(p, p) - pe1 * pe1) - pe2 * pe2);
  return out;
}

Quadric2 reduce(const Quadric5& q) {
  const auto& a = q.a;
  const ColorInverse ci = color_inverse(a);
  // Columns x and y of the color-position block, and the color part of b.
  const double xr = a[2], xg = a[3], xb = a[4], yr = a[6], yg = a[7], yb = a[8];
  const double br = q.b[2], bg = q.b[3], bb = q.b[4];
  // C times (x column, y column, b colors).
  const double wx0 = ci.c00 * xr + ci.c01 * xg + ci.c02 * xb, wx1 = ci.c01 * xr + ci.c11 * xg + ci.c12 * xb,
               wx2 = ci.c02 * xr + ci.c12 * xg + ci.c22 * xb;
  const double wy0 = ci.c00 * yr + ci.c01 * yg + ci.c02 * yb, wy1 = ci.c01 * yr + ci.c11 * yg + ci.c12 * yb,
               wy2 = ci.c02 * yr + ci.c12 * yg + ci.c22 * yb;
  const double wb0 = ci.c00 * br + ci.c01 * bg + ci.c02 * bb, wb1 = ci.c01 * br + ci.c11 * bg + ci.c12 * bb,
               wb2 = ci.c02 * br + ci.c12 * bg + ci.c22 * bb;
  const double inv_det = 1 / ci.det;
  Quadric2 r;
  r.m00 = a[0] - (xr * wx0 + xg * wx1 + xb * wx2) * inv_det;
  r.m01 = a[1] - (xr * wy0 + xg * wy1 + xb * wy2) * inv_det;
  r.m11 = a[5] - (yr * wy0 + yg * wy1 + yb * wy2) * inv_det;
  r.g0 = q.b[0] - (xr * wb0 + xg * wb1 + xb * wb2) * inv_det;
  r.g1 = q.b[1] - (yr * wb0 + yg * wb1 + yb * wb2) * inv_det;
  r.k = q.c - (br * wb0 + bg * wb1 + bb * wb2) * inv_det;
  return r;
}

std::array<double, 3> best_color(const Quadric5& q, double x, double y) {
  const auto& a = q.a;
  const ColorInverse ci = color_inverse(a);
  const double r = a[2] * x + a[6] * y + q.b[2], g = a[3] * x + a[7] * y + q.b[3], b = a[4] * x + a[8] * y + q.b[4];
  return {-(ci.c00 * r + ci.c01 * g + ci.c02 * b) / ci.det, -(ci.c01 * r + ci.c11 * g + ci.c12 * b) / ci.det,
          -(ci.c02 * r + ci.c12 * g + ci.c22 * b) / ci.det};
}

}  // namespace subvec::detail
