// Shape editing (edit/shape.h).
#include "subvec/edit/shape.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <cstdio>
#include <numbers>
#include <string>

#include "core/messages_p.h"
#include "subvec/core/error.h"

namespace subvec {
namespace {

using detail::invalid;

constexpr size_t kCachedSets = 4;

std::string num(double v) { return detail::num(v, 4); }

}  // namespace

Handles drag_vertex(const ControlMesh& mesh, int vertex, Vec2 displacement) {
  if (vertex < 0 || vertex >= mesh.num_vertices()) {
    invalid("vertex " + std::to_string(vertex) + " is out of range");
  }
  const Vec2 p = mesh.positions[vertex];
  return {{vertex}, {{p.x + displacement.x, p.y + displacement.y}}};
}

Handles move_vertices(const ControlMesh& mesh, std::span<const int32_t> vertices, Vec2 translate) {
  if (vertices.empty()) invalid("no vertices to move");
  std::vector<uint8_t> seen(mesh.positions.size(), 0);
  Handles h;
  for (const int32_t v : vertices) {
    if (v < 0 || v >= mesh.num_vertices()) {
      invalid("vertex " + std::to_string(v) + " is out of range (the level has " +
              std::to_string(mesh.num_vertices()) + ")");
    }
    if (seen[v]++) invalid("vertex " + std::to_string(v) + " is given twice");
    const Vec2 p = mesh.positions[v];
    h.vertices.push_back(v);
    h.targets.push_back({p.x + translate.x, p.y + translate.y});
  }
  return h;
}

namespace {

// The feature's vertices once each (a closed chain repeats its first vertex).
std::vector<int32_t> unique_vertices(const Feature& feature) {
  std::vector<int32_t> vs = feature.vertices;
  if (feature.closed()) vs.pop_back();
  return vs;
}

}  // namespace

Handles drag_feature(const ControlMesh& mesh, const Feature& feature, Vec2 center,
                     Vec2 displacement, double sigma) {
  if (!(sigma > 0) || !std::isfinite(sigma)) invalid("sigma " + num(sigma) + " is not a positive number");
  Handles h;
  h.vertices = unique_vertices(feature);
  for (int32_t v : h.vertices) {
    const Vec2 p = mesh.positions[v];
    const double d2 = (p.x - center.x) * (p.x - center.x) + (p.y - center.y) * (p.y - center.y);
    const double g = std::exp(-d2 / (2 * sigma * sigma));
    h.targets.push_back({p.x + g * displacement.x, p.y + g * displacement.y});
  }
  return h;
}

Handles move_feature(const ControlMesh& mesh, const Feature& feature, Vec2 translate,
                     double degrees) {
  Handles h;
  h.vertices = unique_vertices(feature);
  double cx = 0, cy = 0;
  for (int32_t v : h.vertices) cx += mesh.positions[v].x, cy += mesh.positions[v].y;
  cx /= double(h.vertices.size()), cy /= double(h.vertices.size());
  const double a = degrees * std::numbers::pi / 180, c = std::cos(a), s = std::sin(a);
  for (int32_t v : h.vertices) {
    const double x = mesh.positions[v].x - cx, y = mesh.positions[v].y - cy;
    h.targets.push_back({cx + c * x - s * y + translate.x, cy + s * x + c * y + translate.y});
  }
  return h;
}

ShapeEditor::ShapeEditor(const ControlMesh& mesh, int width, int height)
    : rest_(mesh.positions), triangles_(mesh.triangles) {
  sides_.resize(rest_.size());
  for (size_t v = 0; v < rest_.size(); ++v) {
    const Vec2 p = rest_[v];
    sides_[v] = static_cast<uint8_t>((p.x == 0 ? 1 : 0) | (p.x == width ? 2 : 0) |
                                     (p.y == 0 ? 4 : 0) | (p.y == height ? 8 : 0));
  }
}

const ArapDeformer& ShapeEditor::deformer_for(std::vector<int32_t> handles, double region) {
  std::sort(handles.begin(), handles.end());
  for (auto it = cache_.begin(); it != cache_.end(); ++it) {
    if (it->handles == handles && it->region == region) {
      cache_.splice(cache_.begin(), cache_, it);
      return *cache_.front().deformer;
    }
  }
  std::vector<FixedAxes> fixed(rest_.size(), FixedAxes::kNone);
  for (size_t v = 0; v < rest_.size(); ++v) {
    const unsigned s = sides_[v];
    fixed[v] = static_cast<FixedAxes>(((s & 3u) ? 1u : 0u) | ((s & 12u) ? 2u : 0u));
  }
  if (region > 0) {
    const double r2 = region * region;
    for (size_t v = 0; v < rest_.size(); ++v) {
      bool near = false;
      for (int32_t h : handles) {
        const double dx = rest_[v].x - rest_[h].x, dy = rest_[v].y - rest_[h].y;
        if (dx * dx + dy * dy <= r2) {
          near = true;
          break;
        }
      }
      if (!near) fixed[v] = FixedAxes::kXY;
    }
  }
  for (int32_t v : handles) fixed[v] = FixedAxes::kXY;
  auto deformer = std::make_shared<const ArapDeformer>(rest_, triangles_, fixed);
  cache_.push_front({std::move(handles), region, std::move(deformer)});
  if (cache_.size() > kCachedSets) cache_.pop_back();
  return *cache_.front().deformer;
}

std::vector<Vec2> ShapeEditor::deform(const Handles& handles) {
  std::vector<Vec2> out;
  deform(handles, out);
  return out;
}

void ShapeEditor::deform(const Handles& handles, std::vector<Vec2>& out) {
  const int n = static_cast<int>(rest_.size());
  if (handles.vertices.size() != handles.targets.size()) {
    invalid(std::to_string(handles.vertices.size()) + " handle vertices but " +
            std::to_string(handles.targets.size()) + " targets");
  }
  targets_ = rest_;
  std::vector<uint8_t> seen(rest_.size(), 0);
  for (size_t i = 0; i < handles.vertices.size(); ++i) {
    const int v = handles.vertices[i];
    if (v < 0 || v >= n) invalid("handle vertex " + std::to_string(v) + " is out of range");
    if (seen[v]++) invalid("handle vertex " + std::to_string(v) + " is given twice");
    const Vec2 t = handles.targets[i];
    if (!std::isfinite(t.x) || !std::isfinite(t.y)) {
      invalid("the target of vertex " + std::to_string(v) + " is not finite");
    }
    // Border handles slide along their side; corners stay.
    const unsigned s = sides_[v];
    targets_[v] = {(s & 3u) ? rest_[v].x : t.x, (s & 12u) ? rest_[v].y : t.y};
  }
  if (!(handles.region >= 0) || !std::isfinite(handles.region)) {
    invalid("the region " + num(handles.region) + " is not a number >= 0");
  }
  const ArapDeformer& deformer = deformer_for(handles.vertices, handles.region);
  std::vector<Vec2> result(rest_.size());
  similarity_.resize(rest_.size());
  deformer.solve(targets_, result, similarity_);
  scale_fraction_ = 1;
  if (first_flip(result) >= 0) {
    // Repair: apply the scale adjustment only partly, v = s1 + lambda (s2 - s1), with the largest
    // lambda (bisection, to 1/1024) that flips nothing. Refused when the similarity step flips.
    const int f = first_flip(similarity_);
    if (f >= 0) {
      const Tri& t = triangles_[f];
      const Vec2 r = rest_[t[0]];
      invalid("the edit would flip control triangle " + std::to_string(f) + " (vertices " +
              std::to_string(t[0]) + ", " + std::to_string(t[1]) + ", " + std::to_string(t[2]) +
              " near (" + num(r.x) + ", " + num(r.y) +
              ")); refused: try a smaller displacement, a larger sigma or several smaller steps");
    }
    std::vector<Vec2> blend(rest_.size());
    // A result that is not finite (a numerically singular scale step) counts as flipped, and
    // lambda 0 is the similarity step exactly: 0 * NaN would carry the NaN through.
    auto mix = [&](double lambda) {
      if (lambda == 0) {
        blend = similarity_;
        return;
      }
      for (size_t v = 0; v < rest_.size(); ++v) {
        blend[v] = {similarity_[v].x + lambda * (result[v].x - similarity_[v].x),
                    similarity_[v].y + lambda * (result[v].y - similarity_[v].y)};
        // Constrained coordinates are equal in both: keep them exact.
        if (similarity_[v].x == result[v].x) blend[v].x = result[v].x;
        if (similarity_[v].y == result[v].y) blend[v].y = result[v].y;
      }
    };
    double lo = 0, hi = 1;
    for (int i = 0; i < 10; ++i) {
      const double mid = (lo + hi) / 2;
      mix(mid);
      (first_flip(blend) < 0 ? lo : hi) = mid;
    }
    mix(lo);
    result.swap(blend);
    scale_fraction_ = lo;
  }
  for (const Vec2& p : result) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) {
      invalid("the edit could not be solved (a numerically singular system); try a smaller "
              "displacement or a larger region");
    }
  }
  out = std::move(result);
}

int ShapeEditor::first_flip(const std::vector<Vec2>& p) const {
  for (size_t f = 0; f < triangles_.size(); ++f) {
    const Tri& t = triangles_[f];
    const Vec2 a = p[t[0]], b = p[t[1]], c = p[t[2]];
    if (!((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x) > 0)) return static_cast<int>(f);
  }
  return -1;
}

namespace {

// Barycentric coordinates of p in (a, b, c), a triangle of positive area.
std::array<double, 3> barycentric(Vec2 p, Vec2 a, Vec2 b, Vec2 c) {
  const double d = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
  const double la = ((b.x - p.x) * (c.y - p.y) - (b.y - p.y) * (c.x - p.x)) / d;
  const double lb = ((c.x - p.x) * (a.y - p.y) - (c.y - p.y) * (a.x - p.x)) / d;
  return {la, lb, 1 - la - lb};
}

// How far p lies outside the triangle with these coordinates (0 inside): the most negative one.
double outside(const std::array<double, 3>& l) { return -std::min({l[0], l[1], l[2], 0.0}); }

}  // namespace

DragExtent suggested_drag_extent(const ControlMesh& mesh, int feature, int vertex) {
  DragExtent e;
  if (feature >= 0) {
    if (feature >= static_cast<int>(mesh.features.size())) {
      invalid("feature " + std::to_string(feature) + " is out of range");
    }
    const Feature& f = mesh.features[feature];
    double length = 0;
    double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
    for (size_t i = 0; i < f.vertices.size(); ++i) {
      const Vec2 p = mesh.positions[f.vertices[i]];
      x0 = std::min(x0, p.x), x1 = std::max(x1, p.x), y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
      if (i > 0) {
        const Vec2 q = mesh.positions[f.vertices[i - 1]];
        length += std::hypot(p.x - q.x, p.y - q.y);
      }
    }
    const double diagonal = std::hypot(x1 - x0, y1 - y0);
    e.sigma = f.closed() && diagonal <= 60 ? std::max(2 * diagonal, 8.0) : std::clamp(length / 4, 8.0, 60.0);
    e.region = std::max(3 * e.sigma, 30.0);
    return e;
  }
  if (vertex < 0 || vertex >= mesh.num_vertices()) invalid("vertex " + std::to_string(vertex) + " is out of range");
  double longest = 0;
  const Vec2 p = mesh.positions[vertex];
  for (const Tri& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      if (t[k] != vertex) continue;
      for (int m = 1; m <= 2; ++m) {
        const Vec2 q = mesh.positions[t[(k + m) % 3]];
        longest = std::max(longest, std::hypot(q.x - p.x, q.y - p.y));
      }
    }
  }
  e.region = std::max(4 * longest, 30.0);
  return e;
}

DragExtent suggested_drag_extent(const ControlMesh& mesh, std::span<const int32_t> vertices) {
  if (vertices.empty()) invalid("no vertices");
  std::vector<double> longest(mesh.positions.size(), 0);
  for (const int32_t v : vertices) {
    if (v < 0 || v >= mesh.num_vertices()) invalid("vertex " + std::to_string(v) + " is out of range");
  }
  for (const Tri& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const Vec2 p = mesh.positions[t[k]], q = mesh.positions[t[(k + 1) % 3]];
      const double l = std::hypot(q.x - p.x, q.y - p.y);
      longest[t[k]] = std::max(longest[t[k]], l);
      longest[t[(k + 1) % 3]] = std::max(longest[t[(k + 1) % 3]], l);
    }
  }
  DragExtent e;
  e.region = 30;
  for (const int32_t v : vertices) e.region = std::max(e.region, 4 * longest[v]);
  return e;
}

void transport_points(const std::vector<Vec2>& rest, const std::vector<Vec2>& moved,
                      const std::vector<Tri>& triangles, std::span<Vec2> points) {
  if (rest.size() != moved.size()) invalid("transport_points: rest and moved differ in size");
  if (triangles.empty() || points.empty()) return;
  for (const Tri& t : triangles) {
    for (int32_t v : t) {
      if (v < 0 || v >= static_cast<int32_t>(rest.size())) invalid("transport_points: vertex out of range");
    }
  }
  // A uniform grid over the triangles' boxes, about two triangles per cell.
  double x0 = rest[triangles[0][0]].x, y0 = rest[triangles[0][0]].y, x1 = x0, y1 = y0;
  for (const Tri& t : triangles) {
    for (int32_t v : t) {
      x0 = std::min(x0, rest[v].x), x1 = std::max(x1, rest[v].x);
      y0 = std::min(y0, rest[v].y), y1 = std::max(y1, rest[v].y);
    }
  }
  const double span_x = std::max(x1 - x0, 1e-9), span_y = std::max(y1 - y0, 1e-9);
  const double cells = std::max(1.0, std::ceil(static_cast<double>(triangles.size()) / 2));
  const int nx = std::clamp(static_cast<int>(std::sqrt(cells * span_x / span_y)), 1, 4096);
  const int ny = std::clamp(static_cast<int>(cells / nx), 1, 4096);
  const auto cell_x = [&](double x) { return std::clamp(static_cast<int>((x - x0) / span_x * nx), 0, nx - 1); };
  const auto cell_y = [&](double y) { return std::clamp(static_cast<int>((y - y0) / span_y * ny), 0, ny - 1); };
  std::vector<int32_t> start(static_cast<size_t>(nx) * ny + 1, 0), entries;
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<int32_t> fill(start.begin(), start.end() - 1);
    for (size_t f = 0; f < triangles.size(); ++f) {
      const Tri& t = triangles[f];
      const Vec2 a = rest[t[0]], b = rest[t[1]], c = rest[t[2]];
      const int cx0 = cell_x(std::min({a.x, b.x, c.x})), cx1 = cell_x(std::max({a.x, b.x, c.x}));
      const int cy0 = cell_y(std::min({a.y, b.y, c.y})), cy1 = cell_y(std::max({a.y, b.y, c.y}));
      for (int cy = cy0; cy <= cy1; ++cy) {
        for (int cx = cx0; cx <= cx1; ++cx) {
          const size_t cell = static_cast<size_t>(cy) * nx + cx;
          if (pass == 0) ++start[cell + 1];
          else entries[fill[cell]++] = static_cast<int32_t>(f);
        }
      }
    }
    if (pass == 0) {
      for (size_t i = 1; i < start.size(); ++i) start[i] += start[i - 1];
      entries.resize(start.back());
    }
  }
  const auto coordinates = [&](size_t f, Vec2 p) {
    const Tri& t = triangles[f];
    return barycentric(p, rest[t[0]], rest[t[1]], rest[t[2]]);
  };
  for (Vec2& p : points) {
    // The containing triangle of p's cell (the first, in triangle order: the map is continuous,
    // so a point on a shared edge goes to the same place either way); else the least outside of
    // all triangles, its coordinates clamped.
    size_t best = 0;
    double best_out = std::numeric_limits<double>::infinity();
    const size_t cell = static_cast<size_t>(cell_y(p.y)) * nx + cell_x(p.x);
    for (int32_t i = start[cell]; i < start[cell + 1] && best_out > 0; ++i) {
      const double o = outside(coordinates(entries[i], p));
      if (o < best_out) best = entries[i], best_out = o;
    }
    if (best_out > 1e-12) {
      for (size_t f = 0; f < triangles.size(); ++f) {
        const double o = outside(coordinates(f, p));
        if (o < best_out) best = f, best_out = o;
      }
    }
    std::array<double, 3> l = coordinates(best, p);
    if (best_out > 0) {
      for (double& x : l) x = std::max(x, 0.0);
      const double sum = l[0] + l[1] + l[2];
      for (double& x : l) x /= sum;
    }
    const Tri& t = triangles[best];
    p = {l[0] * moved[t[0]].x + l[1] * moved[t[1]].x + l[2] * moved[t[2]].x,
         l[0] * moved[t[0]].y + l[1] * moved[t[1]].y + l[2] * moved[t[2]].y};
  }
}

}  // namespace subvec
