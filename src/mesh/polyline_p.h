// Walking along polylines (the sampled limit curves of mesh/curves.h), for the layers that measure
// along features: levels (vectorize/levels.cpp) and stylization (edit/stylize.cpp).
#pragma once

#include <cmath>
#include <cstddef>
#include <span>

#include "subvec/mesh/vector_image.h"

namespace subvec::detail {

// The length of the polyline, in pixels.
inline double polyline_length(std::span<const Vec2> line) {
  double length = 0;
  for (size_t i = 0; i + 1 < line.size(); ++i)
    length += std::hypot(line[i + 1].x - line[i].x, line[i + 1].y - line[i].y);
  return length;
}

// Calls visit(point, unit tangent) at points `step` pixels apart along the polyline, the first
// half a step in.
template <class Visit>
void walk(std::span<const Vec2> line, double step, Visit&& visit) {
  double next = step / 2;
  double at = 0;
  for (size_t i = 0; i + 1 < line.size(); ++i) {
    const double dx = line[i + 1].x - line[i].x, dy = line[i + 1].y - line[i].y;
    const double len = std::hypot(dx, dy);
    if (len <= 0) continue;
    while (next <= at + len) {
      const double u = (next - at) / len;
      visit(Vec2{line[i].x + u * dx, line[i].y + u * dy}, Vec2{dx / len, dy / len});
      next += step;
    }
    at += len;
  }
}

}  // namespace subvec::detail
