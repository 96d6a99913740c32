// Private plane-geometry helpers shared by the layers above core (vectorize, edit, pyramid): one
// point-to-segment distance, one cross product and one "pixels near a segment" loop, so that every
// caller does the same floating-point operations in the same order.
//
// Core sits below mesh, so these take coordinates (or any point type with members x and y), not
// Vec2. Endpoint coordinates may be float: differences of endpoints are taken in their own type and
// widened, as the callers always did (src/vectorize/fit.cpp stores tear segments as floats).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace subvec::detail {

// z of the cross product (ax, ay) x (bx, by).
inline double cross(double ax, double ay, double bx, double by) { return ax * by - ay * bx; }

// Distance from (px, py) to the segment (ax, ay)-(bx, by); the nearest point in *nx, *ny when given.
template <class T>
double segment_distance(double px, double py, T ax, T ay, T bx, T by, double* nx = nullptr,
                        double* ny = nullptr) {
  const double dx = bx - ax, dy = by - ay, len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? ((px - ax) * dx + (py - ay) * dy) / len2 : 0;
  t = std::clamp(t, 0.0, 1.0);
  const double qx = ax + t * dx, qy = ay + t * dy;
  if (nx) *nx = qx;
  if (ny) *ny = qy;
  return std::hypot(px - qx, py - qy);
}

// The same for points with members x and y; the nearest point in *nearest when given.
template <class P>
double segment_distance(const P& p, const P& a, const P& b, P* nearest = nullptr) {
  double qx = 0, qy = 0;
  const double d = segment_distance(p.x, p.y, a.x, a.y, b.x, b.y, &qx, &qy);
  if (nearest) *nearest = P{qx, qy};
  return d;
}

// Calls visit(x, y) for every pixel (x, y) of a width x height grid whose centre (x + 0.5, y + 0.5)
// lies closer than r to the segment (ax, ay)-(bx, by), row by row.
template <class T, class Visit>
void for_pixels_near_segment(T ax, T ay, T bx, T by, double r, int width, int height, const Visit& visit) {
  const int x0 = std::max(0, int(std::floor(std::min(ax, bx) - r - 0.5)));
  const int x1 = std::min(width - 1, int(std::ceil(std::max(ax, bx) + r - 0.5)));
  const int y0 = std::max(0, int(std::floor(std::min(ay, by) - r - 0.5)));
  const int y1 = std::min(height - 1, int(std::ceil(std::max(ay, by) + r - 0.5)));
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x)
      if (segment_distance(x + 0.5, y + 0.5, ax, ay, bx, by) < r) visit(x, y);
}

// Whether (px, py) is inside the closed polygon through `points` (members x and y; the last joined
// to the first, a repeated first point adding nothing), by the crossings of a ray to its right.
template <class Points>
bool inside_polygon(const Points& points, double px, double py) {
  bool inside = false;
  for (size_t i = 0, j = points.size() - 1; i < points.size(); j = i++) {
    const auto a = points[j], b = points[i];
    if ((a.y > py) != (b.y > py) && px < a.x + (py - a.y) * (b.x - a.x) / (b.y - a.y)) inside = !inside;
  }
  return inside;
}

}  // namespace subvec::detail
