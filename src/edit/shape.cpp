// Shape editing (edit/shape.h).
#include "subvec/edit/shape.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
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
  Handles h;
  h.vertices = {vertex};
  h.targets = {{p.x + displacement.x, p.y + displacement.y}};
  return h;
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
  h.center = center;
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
    : rest_(mesh.positions), triangles_(mesh.triangles), width_(width), height_(height) {
  sides_.assign(rest_.size(), 0);
  if (width < 0) {
    // An object's mesh: its boundary (the edges of one triangle) holds it in place, as the frame
    // holds a level's.
    std::map<std::pair<int32_t, int32_t>, int> uses;
    for (const Tri& t : triangles_) {
      for (int k = 0; k < 3; ++k) ++uses[std::minmax(t[k], t[(k + 1) % 3])];
    }
    pinned_.assign(rest_.size(), 0);
    for (const auto& [edge, count] : uses) {
      if (count == 1) pinned_[edge.first] = pinned_[edge.second] = 1;
    }
  }
  for (size_t v = 0; v < rest_.size() && width >= 0; ++v) {
    const Vec2 p = rest_[v];
    sides_[v] = static_cast<uint8_t>((p.x == 0 ? 1 : 0) | (p.x == width ? 2 : 0) |
                                     (p.y == 0 ? 4 : 0) | (p.y == height ? 8 : 0));
  }
}

const ArapDeformer& ShapeEditor::deformer_for(std::vector<int32_t> handles, double region,
                                              std::optional<Vec2> center) {
  std::sort(handles.begin(), handles.end());
  for (auto it = cache_.begin(); it != cache_.end(); ++it) {
    if (it->handles == handles && it->region == region && it->center == center) {
      cache_.splice(cache_.begin(), cache_, it);
      return *cache_.front().deformer;
    }
  }
  std::vector<FixedAxes> fixed(rest_.size(), FixedAxes::kNone);
  for (size_t v = 0; v < rest_.size(); ++v) {
    const unsigned s = sides_[v];
    fixed[v] = static_cast<FixedAxes>(((s & 3u) ? 1u : 0u) | ((s & 12u) ? 2u : 0u));
    if (!pinned_.empty() && pinned_[v]) fixed[v] = FixedAxes::kXY;
  }
  if (region > 0) {
    const double r2 = region * region;
    for (size_t v = 0; v < rest_.size(); ++v) {
      bool near = false;
      if (center) {
        const double dx = rest_[v].x - center->x, dy = rest_[v].y - center->y;
        near = dx * dx + dy * dy <= r2;
      }
      for (int32_t h : handles) {
        if (center) break;
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
  cache_.push_front({std::move(handles), region, center, std::move(deformer)});
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
  framed_ = false;
  // The frame stops the handles a margin inside it. Taking each target past it to the margin put
  // every handle past it on one line, and a triangle of them flat: the drag stopped short (18 of
  // 400 random drags on the photographs). So on a side that targets pass, the targets from the
  // farthest one out to as far inside are squeezed, in order, into the inner half (an affine map
  // that halves their distances to the side at most), and no two handles meet.
  std::array<double, 4> past{0, 0, 0, 0};  // how far the targets pass each side: x = 0, x = w, y = 0, y = h
  if (width_ >= 0) {
    for (size_t i = 0; i < handles.vertices.size() && i < handles.targets.size(); ++i) {
      const int v = handles.vertices[i];
      const Vec2 t = handles.targets[i];
      if (v < 0 || v >= n || !std::isfinite(t.x) || !std::isfinite(t.y)) continue;  // refused below
      const unsigned s = sides_[v];
      if (!(s & 3u)) past[0] = std::max(past[0], kFrameMargin - t.x), past[1] = std::max(past[1], t.x - (width_ - kFrameMargin));
      if (!(s & 12u)) past[2] = std::max(past[2], kFrameMargin - t.y), past[3] = std::max(past[3], t.y - (height_ - kFrameMargin));
    }
  }
  // Coordinate c on an axis from 0 to `extent` whose targets pass the low side by `low` and the
  // high side by `high`.
  const auto squeeze = [](double c, double extent, double low, double high) {
    const double m = kFrameMargin, half = extent / 2;
    if (low > 0) {
      const double far = m - low, near = std::max(m, std::min(m + low, half));  // [far, near] -> [m, near]
      if (c < near) c = m + (c - far) * (near - m) / (near - far);
    }
    if (high > 0) {
      const double far = extent - m + high, near = std::min(extent - m, std::max(extent - m - high, half));
      if (c > near) c = near + (c - near) * (extent - m - near) / (far - near);
    }
    return c;
  };
  std::vector<uint8_t> seen(rest_.size(), 0);
  for (size_t i = 0; i < handles.vertices.size(); ++i) {
    const int v = handles.vertices[i];
    if (v < 0 || v >= n) invalid("handle vertex " + std::to_string(v) + " is out of range");
    if (seen[v]++) invalid("handle vertex " + std::to_string(v) + " is given twice");
    const Vec2 t = handles.targets[i];
    if (!std::isfinite(t.x) || !std::isfinite(t.y)) {
      invalid("the target of vertex " + std::to_string(v) + " is not finite");
    }
    // Border handles slide along their side; corners stay. The frame stops the others: a
    // target outside it is taken to the nearest point a margin inside.
    if (width_ < 0) {  // an object's mesh: no frame
      targets_[v] = t;
      continue;
    }
    const unsigned s = sides_[v];
    const double m = kFrameMargin;
    framed_ |= (!(s & 3u) && (t.x < kFrameMargin || t.x > width_ - kFrameMargin)) ||
               (!(s & 12u) && (t.y < kFrameMargin || t.y > height_ - kFrameMargin));
    const double x = squeeze(t.x, width_, past[0], past[1]), y = squeeze(t.y, height_, past[2], past[3]);
    targets_[v] = {(s & 3u) ? rest_[v].x : std::clamp(x, std::min(m, rest_[v].x), std::max(width_ - m, rest_[v].x)),
                   (s & 12u) ? rest_[v].y : std::clamp(y, std::min(m, rest_[v].y), std::max(height_ - m, rest_[v].y))};
  }
  if (!(handles.region >= 0) || !std::isfinite(handles.region)) {
    invalid("the region " + num(handles.region) + " is not a number >= 0");
  }
  if (handles.center && !(std::isfinite(handles.center->x) && std::isfinite(handles.center->y))) {
    invalid("the region's centre is not finite");
  }
  const ArapDeformer& deformer = deformer_for(handles.vertices, handles.region, handles.center);
  std::vector<Vec2> result(rest_.size());
  similarity_.resize(rest_.size());
  deformer.solve(targets_, result, similarity_);
  scale_fraction_ = 1;
  reached_ = 1;
  if (first_flip(result) >= 0) {
    // Repair: apply the scale adjustment only partly, v = s1 + lambda (s2 - s1), with the largest
    // lambda (bisection, to 1/1024) that flips nothing. When the similarity step flips too, the
    // fold-free path (below) takes over.
    if (first_flip(similarity_) >= 0) {
      fold_free(deformer, result);
      out = std::move(result);
      return;
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

namespace {

// The largest t in (0, 1] (or 1) such that moving every vertex from `from` by t (to - from) keeps
// each triangle's signed area above its floor all the way: the signed area along the path is a
// quadratic in t, and the bound is its first crossing of the floor. Returns 1 when no triangle
// reaches its floor before t = 1.
double area_bound(const std::vector<Vec2>& from, const std::vector<Vec2>& to,
                  const std::vector<Tri>& triangles, const std::vector<double>& floor2) {
  double bound = std::numeric_limits<double>::infinity();
  for (size_t f = 0; f < triangles.size(); ++f) {
    const Tri& t = triangles[f];
    const Vec2 a = from[t[0]], b = from[t[1]], c = from[t[2]];
    const Vec2 da = {to[t[0]].x - a.x, to[t[0]].y - a.y};
    const Vec2 e1 = {b.x - a.x, b.y - a.y}, e2 = {c.x - a.x, c.y - a.y};
    const Vec2 d1 = {to[t[1]].x - b.x - da.x, to[t[1]].y - b.y - da.y};
    const Vec2 d2 = {to[t[2]].x - c.x - da.x, to[t[2]].y - c.y - da.y};
    const auto cross = [](Vec2 u, Vec2 v) { return u.x * v.y - u.y * v.x; };
    // 2 area(t) - floor = c0 + c1 t + c2 t^2, with c0 > 0.
    const double c0 = cross(e1, e2) - floor2[f];
    const double c1 = cross(e1, d2) + cross(d1, e2);
    const double c2 = cross(d1, d2);
    double root = std::numeric_limits<double>::infinity();
    if (!(c0 > 0)) {
      root = 0;
    } else if (c2 == 0) {
      if (c1 < 0) root = -c0 / c1;
    } else {
      const double disc = c1 * c1 - 4 * c2 * c0;
      if (disc >= 0) {
        // The roots q / c2 and c0 / q (numerically stable); the first positive one counts.
        const double q = -0.5 * (c1 + std::copysign(std::sqrt(disc), c1));
        for (const double r : {q / c2, q != 0 ? c0 / q : std::numeric_limits<double>::infinity()}) {
          if (r > 0) root = std::min(root, r);
        }
      }
    }
    bound = std::min(bound, root);
  }
  return bound;
}

}  // namespace

// The symmetric Dirichlet energy of a deformation, sum over triangles of A_f (|J|^2 + |J^-1|^2)
// (J the map from the rest triangle to the deformed one, A_f its rest area): 4 times the area for
// a rigid motion, and infinite as a triangle degenerates, so a descent on it never folds and
// pushes the neighbours of a squeezed triangle away. Returns infinity when a triangle is at or
// below its floor; with `gradient`, adds the energy's gradient to it.
double ShapeEditor::distortion(const std::vector<Vec2>& x, std::vector<Vec2>* gradient) const {
  double energy = 0;
  for (size_t f = 0; f < triangles_.size(); ++f) {
    const Tri& t = triangles_[f];
    const Vec2 q0 = x[t[0]];
    const double a = x[t[1]].x - q0.x, c = x[t[2]].x - q0.x;  // Q = [a c; b d]
    const double b = x[t[1]].y - q0.y, d = x[t[2]].y - q0.y;
    const double cross = a * d - b * c;
    if (!(cross > floor2_[f])) return std::numeric_limits<double>::infinity();
    const Inverse& p = inverse_[f];
    // J = Q P^-1
    const double j00 = a * p.m00 + c * p.m10, j01 = a * p.m01 + c * p.m11;
    const double j10 = b * p.m00 + d * p.m10, j11 = b * p.m01 + d * p.m11;
    const double s = j00 * j00 + j01 * j01 + j10 * j10 + j11 * j11;
    const double det = j00 * j11 - j01 * j10;
    energy += p.area * s * (1 + 1 / (det * det));
    if (gradient) {
      // dE/dJ = A (2 J (1 + 1/det^2) - 2 s / det^3 cof(J)), then dE/dQ = dE/dJ P^-T.
      const double k1 = 2 * p.area * (1 + 1 / (det * det)), k2 = -2 * p.area * s / (det * det * det);
      const double g00 = k1 * j00 + k2 * j11, g01 = k1 * j01 - k2 * j10;
      const double g10 = k1 * j10 - k2 * j01, g11 = k1 * j11 + k2 * j00;
      const double m00 = g00 * p.m00 + g01 * p.m01, m01 = g00 * p.m10 + g01 * p.m11;
      const double m10 = g10 * p.m00 + g11 * p.m01, m11 = g10 * p.m10 + g11 * p.m11;
      std::vector<Vec2>& g = *gradient;
      g[t[1]].x += m00, g[t[1]].y += m10;
      g[t[2]].x += m01, g[t[2]].y += m11;
      g[t[0]].x -= m00 + m01, g[t[0]].y -= m10 + m11;
    }
  }
  return energy;
}

// One preconditioned descent step on the distortion with the fixed coordinates held (the
// Laplacian as the quadratic proxy, Kovalsky et al. 2016), as long as the floor and an Armijo
// decrease allow. Returns the relative decrease of the energy (0 when no step was taken).
double ShapeEditor::relax_step(const ArapDeformer& deformer, std::vector<Vec2>& x) {
  const size_t n = rest_.size();
  gradient_.assign(n, {0, 0});
  const double energy = distortion(x, &gradient_);
  direction_.assign(n, {0, 0});
  deformer.precondition(gradient_, direction_);
  double slope = 0;
  for (size_t v = 0; v < n; ++v) slope += gradient_[v].x * direction_[v].x + gradient_[v].y * direction_[v].y;
  if (!(slope < 0)) return 0;
  trial_.resize(n);
  for (size_t v = 0; v < n; ++v) trial_[v] = {x[v].x + direction_[v].x, x[v].y + direction_[v].y};
  const double bound = area_bound(x, trial_, triangles_, floor2_);
  for (double t = std::min(1.0, kStepShare * bound); t > 1e-12; t /= 2) {
    for (size_t v = 0; v < n; ++v) trial_[v] = {x[v].x + t * direction_[v].x, x[v].y + t * direction_[v].y};
    const double e = distortion(trial_, nullptr);
    if (e <= energy + 1e-4 * t * slope) {
      x.swap(trial_);
      return (energy - e) / energy;
    }
  }
  return 0;
}

void ShapeEditor::fold_free(const ArapDeformer& deformer, std::vector<Vec2>& x) {
  const size_t n = rest_.size();
  if (floor2_.size() != triangles_.size()) {
    floor2_.resize(triangles_.size());
    inverse_.resize(triangles_.size());
    for (size_t f = 0; f < triangles_.size(); ++f) {
      const Tri& t = triangles_[f];
      const Vec2 a = rest_[t[0]], b = rest_[t[1]], c = rest_[t[2]];
      const double ux = b.x - a.x, uy = b.y - a.y, vx = c.x - a.x, vy = c.y - a.y;  // P = [u v]
      const double cross = ux * vy - uy * vx;
      floor2_[f] = kAreaFloor * cross;
      inverse_[f] = {vy / cross, -vx / cross, -uy / cross, ux / cross, cross / 2};
    }
  }
  // Rounds: push the handles towards their targets along the ARAP step (the similarity step
  // first), as far as no triangle reaches its floor, then let the distortion's descent, handles
  // held, make room around them. It stops when the handles arrive, or when the rounds stop
  // gaining ground: the last fold-free position on the way.
  x = rest_;
  std::vector<Vec2> proposal = similarity_;
  trial_.resize(n);
  double left = 1;  // the fraction of the handles' way still to go
  int slow = 0;
  for (int round = 0; round < kFoldFreeRounds && left > 0; ++round) {
    double bound;
    if (round == 0) {
      bound = area_bound(x, proposal, triangles_, floor2_);
    } else {
      // Two ways towards the targets, the one that goes farther: the ARAP step, and the
      // distortion's preconditioned step with the handles moved the rest of their way (the
      // barrier in its gradient steers the free vertices around squeezed triangles).
      deformer.rigid_step(targets_, x, proposal);
      bound = area_bound(x, proposal, triangles_, floor2_);
      if (bound <= 1) {
        gradient_.assign(n, {0, 0});
        distortion(x, &gradient_);
        for (size_t v = 0; v < n; ++v) trial_[v] = {targets_[v].x - x[v].x, targets_[v].y - x[v].y};
        deformer.precondition(gradient_, trial_);
        for (size_t v = 0; v < n; ++v) trial_[v] = {x[v].x + trial_[v].x, x[v].y + trial_[v].y};
        const double other = area_bound(x, trial_, triangles_, floor2_);
        if (other > bound) proposal.swap(trial_), bound = other;
      }
    }
    const double t = bound > 1 ? 1 : kStepShare * bound;
    if (t == 1) {
      x.swap(proposal);
      left = 0;
      break;
    }
    for (size_t v = 0; v < n; ++v) {
      x[v] = {x[v].x + t * (proposal[v].x - x[v].x), x[v].y + t * (proposal[v].y - x[v].y)};
    }
    left *= 1 - t;
    slow = t < 1e-3 ? slow + 1 : 0;
    if (slow >= 8) break;
    for (int k = 0; k < (t < 0.1 ? 5 : 1) * kRelaxSteps; ++k) relax_step(deformer, x);
  }
  // Handles within 1 % of their way from their targets are put on them, if nothing reaches its
  // floor then. The rounds approach the targets geometrically, and near the frame they used to
  // stall at 99.9 % of the way (5 of 400 random drags on the photographs): the handles short of
  // their targets by a few hundredths of a pixel, and the drag reported as stopped.
  if (left > 0 && left < 1e-2) {
    proposal = x;
    for (size_t v = 0; v < n; ++v) {
      if (targets_[v].x != rest_[v].x || targets_[v].y != rest_[v].y) proposal[v] = targets_[v];
    }
    if (distortion(proposal, nullptr) < std::numeric_limits<double>::infinity()) x.swap(proposal), left = 0;
  }
  // Then the distortion's descent with the handles where they are, until it settles.
  for (int k = 0; k < kSettleSteps; ++k) {
    if (relax_step(deformer, x) < 1e-6) break;
  }
  reached_ = 1 - left;
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

DragExtent suggested_drag_extent(const ControlMesh& mesh, const Feature& f) {
  DragExtent e;
  for (const int32_t v : f.vertices)
    if (v < 0 || v >= mesh.num_vertices()) invalid("vertex " + std::to_string(v) + " is out of range");
  {
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
}

DragExtent suggested_drag_extent(const ControlMesh& mesh, int feature, int vertex) {
  DragExtent e;
  if (feature >= 0) {
    if (feature >= static_cast<int>(mesh.features.size())) {
      invalid("feature " + std::to_string(feature) + " is out of range");
    }
    return suggested_drag_extent(mesh, mesh.features[feature]);
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
