// New and deleted features (edit/feature_edit.h).
#include "subvec/edit/feature_edit.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "core/geometry_p.h"
#include "core/messages_p.h"
#include "subvec/core/error.h"
#include "subvec/mesh/curves.h"
#include "subvec/mesh/topology.h"
#include "subvec/mesh/validate.h"
#include "subvec/subdiv/subdivision.h"
#include "subvec/vectorize/fit.h"
#include "vectorize/fit_p.h"

namespace subvec {
namespace {

using detail::invalid;
using detail::num;

std::string point(Vec2 p) { return "(" + num(p.x, 4) + ", " + num(p.y, 4) + ")"; }

double orient(Vec2 a, Vec2 b, Vec2 c) { return detail::cross(b.x - a.x, b.y - a.y, c.x - a.x, c.y - a.y); }

// ---- the C^2 fit -------------------------------------------------------------------------------

// Uniform cubic B-spline basis at t in [0, 1].
std::array<double, 4> basis(double t) {
  const double s = 1 - t, t2 = t * t, t3 = t2 * t;
  return {s * s * s / 6, (3 * t3 - 6 * t2 + 4) / 6, (-3 * t3 + 3 * t2 + 3 * t + 1) / 6, t3 / 6};
}

// A point of the curve of n control points (open: n - 1 spans, clamped by the phantoms
// 2 P0 - P1 and 2 Pn-1 - Pn-2; closed: n spans) as weights on the control points.
struct Weights {
  std::array<int, 6> index{};
  std::array<double, 6> weight{};
  int size = 0;
  void add(int i, double w) {
    for (int k = 0; k < size; ++k)
      if (index[k] == i) {
        weight[k] += w;
        return;
      }
    index[size] = i, weight[size] = w, ++size;
  }
};

Weights curve_weights(int n, bool closed, double u) {
  const int spans = closed ? n : n - 1;
  const int span = std::clamp(static_cast<int>(std::floor(u)), 0, spans - 1);
  const std::array<double, 4> b = basis(u - span);
  Weights w;
  for (int k = 0; k < 4; ++k) {
    const int j = span - 1 + k;  // control point index, before wrapping or clamping
    if (closed) {
      w.add(((j % n) + n) % n, b[k]);
    } else if (j < 0) {  // 2 P0 - P1
      w.add(0, 2 * b[k]), w.add(1, -b[k]);
    } else if (j > n - 1) {  // 2 Pn-1 - Pn-2
      w.add(n - 1, 2 * b[k]), w.add(n - 2, -b[k]);
    } else {
      w.add(j, b[k]);
    }
  }
  return w;
}

// The polyline resampled by arc length: points and their arc length.
struct Resampled {
  std::vector<Vec2> points;
  std::vector<double> s;
  double length = 0;
};

Resampled resample(const std::vector<Vec2>& poly) {
  Resampled r;
  std::vector<double> cumulative{0};
  for (size_t i = 1; i < poly.size(); ++i)
    cumulative.push_back(cumulative.back() + std::hypot(poly[i].x - poly[i - 1].x, poly[i].y - poly[i - 1].y));
  r.length = cumulative.back();
  const int count = std::clamp(static_cast<int>(std::ceil(r.length / 0.25)), 8, 20000);
  size_t seg = 1;
  for (int i = 0; i <= count; ++i) {
    const double s = r.length * i / count;
    while (seg + 1 < poly.size() && cumulative[seg] < s) ++seg;
    const double len = cumulative[seg] - cumulative[seg - 1];
    const double t = len > 0 ? std::clamp((s - cumulative[seg - 1]) / len, 0.0, 1.0) : 0;
    r.points.push_back({poly[seg - 1].x + t * (poly[seg].x - poly[seg - 1].x),
                        poly[seg - 1].y + t * (poly[seg].y - poly[seg - 1].y)});
    r.s.push_back(s);
  }
  return r;
}

// Least squares for n control points: the resampled points at uniform arc-length parameters, the
// ends interpolated when open, and a light second-difference term against wiggles.
std::vector<Vec2> solve_fit(const Resampled& r, int n, bool closed, Vec2 first, Vec2 last) {
  const int spans = closed ? n : n - 1;
  // Open: P0 and Pn-1 are the polyline's ends; the unknowns are the others.
  const int lo = closed ? 0 : 1, hi = closed ? n : n - 1, m = hi - lo;
  std::vector<Vec2> p(n);
  if (!closed) p.front() = first, p.back() = last;
  if (m <= 0) return p;
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::MatrixX2d rhs = Eigen::MatrixX2d::Zero(m, 2);
  auto add_row = [&](const Weights& w, Vec2 target, double weight) {
    double tx = target.x, ty = target.y;
    for (int k = 0; k < w.size; ++k) {
      const int i = w.index[k];
      if (i < lo || i >= hi) tx -= w.weight[k] * p[i].x, ty -= w.weight[k] * p[i].y;
    }
    for (int a = 0; a < w.size; ++a) {
      const int i = w.index[a];
      if (i < lo || i >= hi) continue;
      rhs(i - lo, 0) += weight * w.weight[a] * tx;
      rhs(i - lo, 1) += weight * w.weight[a] * ty;
      for (int b = 0; b < w.size; ++b) {
        const int j = w.index[b];
        if (j >= lo && j < hi) triplets.emplace_back(i - lo, j - lo, weight * w.weight[a] * w.weight[b]);
      }
    }
  };
  const size_t samples = r.points.size();
  for (size_t i = 0; i < samples; ++i) add_row(curve_weights(n, closed, r.s[i] / r.length * spans), r.points[i], 1.0);
  // Second differences, weighted lightly against the samples of a span.
  const double smooth = 1e-3 * double(samples) / spans;
  for (int i = closed ? 0 : 1; i < (closed ? n : n - 1); ++i) {
    Weights w;
    w.add(((i - 1) % n + n) % n, 1.0), w.add(i, -2.0), w.add((i + 1) % n, 1.0);
    add_row(w, {0, 0}, smooth);
  }
  Eigen::SparseMatrix<double> a(m, m);
  a.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(a);
  if (ldlt.info() != Eigen::Success) invalid("the drawn curve could not be fitted (singular system)");
  const Eigen::MatrixX2d x = ldlt.solve(rhs);
  for (int i = lo; i < hi; ++i) p[i] = {x(i - lo, 0), x(i - lo, 1)};
  return p;
}

// Largest distance from the resampled polyline to the curve (sampled 32 times a span, searched
// in the spans next to each point's parameter).
double deviation(const Resampled& r, const std::vector<Vec2>& p, bool closed) {
  const int n = static_cast<int>(p.size()), spans = closed ? n : n - 1;
  constexpr int kPerSpan = 32;
  const std::vector<Vec2> curve = sample_bspline(p, closed, kPerSpan);
  double worst = 0;
  for (size_t i = 0; i < r.points.size(); ++i) {
    const int span = std::clamp(static_cast<int>(r.s[i] / r.length * spans), 0, spans - 1);
    double best = std::numeric_limits<double>::infinity();
    for (int s = span - 2; s <= span + 2; ++s) {
      const int w = closed ? ((s % spans) + spans) % spans : s;
      if (w < 0 || w >= spans) continue;
      for (int k = w * kPerSpan; k < (w + 1) * kPerSpan; ++k)
        best = std::min(best, detail::segment_distance(r.points[i], curve[k], curve[k + 1]));
    }
    worst = std::max(worst, best);
  }
  return worst;
}

}  // namespace

CurveFit fit_curve(std::span<const Vec2> polyline, double spacing, double tolerance) {
  detail::check_positive("spacing", spacing);
  detail::check_positive("tolerance", tolerance);
  std::vector<Vec2> poly;
  for (const Vec2& q : polyline) {
    if (!std::isfinite(q.x) || !std::isfinite(q.y)) invalid("the drawn curve has a point that is not finite");
    if (poly.empty() || std::hypot(q.x - poly.back().x, q.y - poly.back().y) > 1e-9) poly.push_back(q);
  }
  if (poly.size() < 2) invalid("the drawn curve needs at least 2 distinct points");
  CurveFit fit;
  const double gap = std::hypot(poly.back().x - poly.front().x, poly.back().y - poly.front().y);
  Resampled r = resample(poly);
  if (r.length < kMinLength) {
    invalid("the drawn curve is " + num(r.length, 3) + " px long, shorter than " + num(kMinLength) + " px");
  }
  fit.closed = poly.size() > 3 && gap <= kCloseDistance && r.length > 4 * kCloseDistance;
  if (fit.closed) {
    poly.back() = poly.front();
    r = resample(poly);
  }
  const int min_points = fit.closed ? 3 : 2;
  int n = std::max(min_points, static_cast<int>(std::lround(r.length / spacing)) + (fit.closed ? 0 : 1));
  for (;;) {
    fit.points = solve_fit(r, n, fit.closed, poly.front(), poly.back());
    fit.deviation = deviation(r, fit.points, fit.closed);
    const int spans = fit.closed ? n : n - 1;
    if (fit.deviation <= tolerance || r.length / spans < 1.5 * kMinSpacing) break;
    n = std::max(n + 1, static_cast<int>(std::ceil(n * 1.5)));
    n = std::min(n, static_cast<int>(r.length / kMinSpacing) + 1);
  }
  return fit;
}

namespace {

// ---- the editable mesh -------------------------------------------------------------------------

uint64_t key(int32_t a, int32_t b) { return uint64_t(uint32_t(a)) << 32 | uint32_t(b); }
uint64_t undirected(int32_t a, int32_t b) { return a < b ? key(a, b) : key(b, a); }

// Positions, triangles and corner colors under local changes (splits and flips), with the
// directed-edge map that finds the triangle across an edge.
class Editable {
 public:
  Editable(ControlMesh& mesh, int width, int height)
      : m_(mesh), width_(width), height_(height), changed_(mesh.num_triangles(), 0) {
    for (int t = 0; t < mesh.num_triangles(); ++t) link(t);
    for (const Feature& f : mesh.features)
      for (size_t i = 0; i + 1 < f.vertices.size(); ++i) sharp_[undirected(f.vertices[i], f.vertices[i + 1])] = 1 + int(&f - mesh.features.data());
    for (const EdgeVerts& e : mesh.creases) sharp_[undirected(e[0], e[1])] = 0;
  }

  ControlMesh& mesh() { return m_; }
  const std::vector<uint8_t>& changed() const { return changed_; }
  int flips = 0;

  // The triangle holding the directed edge (a, b), or -1.
  int triangle_of(int a, int b) const {
    auto it = half_.find(key(a, b));
    return it == half_.end() ? -1 : it->second;
  }
  bool is_edge(int a, int b) const { return triangle_of(a, b) >= 0 || triangle_of(b, a) >= 0; }
  // -1: smooth; 0: a crease; f + 1: an edge of feature f. Border edges are found by their one side.
  int sharp(int a, int b) const {
    auto it = sharp_.find(undirected(a, b));
    return it == sharp_.end() ? -1 : it->second;
  }
  void mark(int a, int b, int value) { sharp_[undirected(a, b)] = value; }

  // Corner k of triangle t rotated so that it starts at vertex v.
  int corner(int t, int v) const {
    for (int k = 0; k < 3; ++k)
      if (m_.triangles[t][k] == v) return k;
    return -1;
  }

  int add_vertex(Vec2 p) {
    m_.positions.push_back(p);
    return m_.num_vertices() - 1;
  }
  int add_color(Color c) {
    m_.colors.push_back(c);
    return m_.num_colors() - 1;
  }

  void set(int t, Tri v, Tri c) {
    if (t == m_.num_triangles()) {
      m_.triangles.push_back(v), m_.triangle_colors.push_back(c), changed_.push_back(1);
    } else {
      unlink(t);
      m_.triangles[t] = v, m_.triangle_colors[t] = c, changed_[t] = 1;
    }
    link(t);
  }

  // Splits triangle t at p, a point strictly inside it; returns the new vertex.
  int split_triangle(int t, Vec2 p) {
    const Tri v = m_.triangles[t], c = m_.triangle_colors[t];
    const Vec2 a = m_.positions[v[0]], b = m_.positions[v[1]], d = m_.positions[v[2]];
    const double area = orient(a, b, d);
    const double w0 = orient(p, b, d) / area, w1 = orient(a, p, d) / area, w2 = 1 - w0 - w1;
    const int nv = add_vertex(p);
    const int nc = add_color(mix({c[0], c[1], c[2]}, {w0, w1, w2}));
    const int n = m_.num_triangles();
    set(t, {v[0], v[1], nv}, {c[0], c[1], nc});
    set(n, {v[1], v[2], nv}, {c[1], c[2], nc});
    set(n + 1, {v[2], v[0], nv}, {c[2], c[0], nc});
    return nv;
  }

  // Splits the smooth or border edge (a, b) at p = a + s (b - a); returns the new vertex.
  int split_edge(int a, int b, double s) {
    int t1 = triangle_of(a, b), t2 = triangle_of(b, a);
    if (t1 < 0) std::swap(a, b), std::swap(t1, t2), s = 1 - s;
    const Vec2 pa = m_.positions[a], pb = m_.positions[b];
    const int nv = add_vertex({pa.x + s * (pb.x - pa.x), pa.y + s * (pb.y - pa.y)});
    const int n = m_.num_triangles();
    {
      const int k = corner(t1, a);
      const Tri v = m_.triangles[t1], c = m_.triangle_colors[t1];
      const int ca = c[k], cb = c[(k + 1) % 3], cc = c[(k + 2) % 3], vc = v[(k + 2) % 3];
      const int nc = add_color(mix({ca, cb, 0}, {1 - s, s, 0}));
      set(t1, {a, nv, vc}, {ca, nc, cc});
      set(n, {nv, b, vc}, {nc, cb, cc});
      if (t2 >= 0) {
        const int j = corner(t2, b);
        const Tri w = m_.triangles[t2], e = m_.triangle_colors[t2];
        const int vd = w[(j + 2) % 3], cd = e[(j + 2) % 3];
        // A smooth edge: the corners of a and b are the same values on both sides.
        set(t2, {b, nv, vd}, {cb, nc, cd});
        set(n + 1, {nv, a, vd}, {nc, ca, cd});
      }
    }
    return nv;
  }

  // Flips the interior smooth edge (u, v) when the quad around it is strictly convex.
  bool flip(int u, int v) {
    const int t1 = triangle_of(u, v), t2 = triangle_of(v, u);
    if (t1 < 0 || t2 < 0 || sharp(u, v) >= 0) return false;
    const int i = corner(t1, u), j = corner(t2, v);
    const int p = m_.triangles[t1][(i + 2) % 3], q = m_.triangles[t2][(j + 2) % 3];
    const Vec2 P = m_.positions[p], Q = m_.positions[q], U = m_.positions[u], V = m_.positions[v];
    if (!(orient(Q, V, P) > 0 && orient(P, U, Q) > 0)) return false;
    if (is_edge(p, q)) return false;
    const int cu = m_.triangle_colors[t1][i], cv = m_.triangle_colors[t1][(i + 1) % 3];
    const int cp = m_.triangle_colors[t1][(i + 2) % 3], cq = m_.triangle_colors[t2][(j + 2) % 3];
    set(t1, {q, v, p}, {cq, cv, cp});
    set(t2, {p, u, q}, {cp, cu, cq});
    ++flips;
    return true;
  }

  // The sharp value of an edge at v (as sharp()), or -1 when none is.
  int sharp_at(int v) const {
    int found = -1;
    for (const auto& [edge, value] : sharp_)
      if (int(edge >> 32) == v || int(edge & 0xffffffffu) == v) found = std::max(found, value);
    return found;
  }

  // Moves the smooth interior vertex v by d when its triangles stay positive; false otherwise
  // (a vertex on the border, a feature or a crease does not move).
  bool step_aside(int v, Vec2 d) {
    const Vec2 p = m_.positions[v];
    if (p.x <= 0 || p.y <= 0 || p.x >= width_ || p.y >= height_ || sharp_at(v) >= 0) return false;
    m_.positions[v] = {p.x + d.x, p.y + d.y};
    std::vector<int> around;
    for (int t = 0; t < m_.num_triangles(); ++t) {
      const Tri& w = m_.triangles[t];
      if (w[0] != v && w[1] != v && w[2] != v) continue;
      around.push_back(t);
      if (!(orient(m_.positions[w[0]], m_.positions[w[1]], m_.positions[w[2]]) > 0)) {
        m_.positions[v] = p;
        return false;
      }
    }
    for (const int t : around) changed_[t] = 1;
    return true;
  }

  // The vertices opposite the edge (u, v) in its two triangles (-1 on the border).
  std::array<int, 2> opposite(int u, int v) const {
    const int t1 = triangle_of(u, v), t2 = triangle_of(v, u);
    return {t1 < 0 ? -1 : m_.triangles[t1][(corner(t1, u) + 2) % 3],
            t2 < 0 ? -1 : m_.triangles[t2][(corner(t2, v) + 2) % 3]};
  }

 private:
  Color mix(std::array<int, 3> c, std::array<double, 3> w) const {
    double r = 0, g = 0, b = 0;
    for (int k = 0; k < 3; ++k) {
      if (w[k] == 0) continue;
      r += w[k] * m_.colors[c[k]].r, g += w[k] * m_.colors[c[k]].g, b += w[k] * m_.colors[c[k]].b;
    }
    return {float(r), float(g), float(b)};
  }
  void link(int t) {
    const Tri& v = m_.triangles[t];
    for (int k = 0; k < 3; ++k) half_[key(v[k], v[(k + 1) % 3])] = t;
  }
  void unlink(int t) {
    const Tri& v = m_.triangles[t];
    for (int k = 0; k < 3; ++k) {
      auto it = half_.find(key(v[k], v[(k + 1) % 3]));
      if (it != half_.end() && it->second == t) half_.erase(it);  // a neighbour may have it by now
    }
  }

  ControlMesh& m_;
  int width_, height_;
  std::vector<uint8_t> changed_;
  std::unordered_map<uint64_t, int32_t> half_;
  std::unordered_map<uint64_t, int> sharp_;
};

std::string sharp_name(const ControlMesh& mesh, int value) {
  if (value == 0) return "a crease";
  return "feature " + std::to_string(value - 1) + " (id " + std::to_string(mesh.features[value - 1].id) + ")";
}

// Inserts p: an existing vertex within 1e-6 px, else a split of the edge it lies on (within
// 1e-9 of the triangle's area) or of the triangle that holds it.
int insert_point(Editable& e, Vec2 p) {
  const ControlMesh& m = e.mesh();
  for (int v = 0; v < m.num_vertices(); ++v)
    if (std::hypot(m.positions[v].x - p.x, m.positions[v].y - p.y) < 1e-6) return v;
  int best = -1;
  double best_min = -std::numeric_limits<double>::infinity();
  std::array<double, 3> best_w{};
  for (int t = 0; t < m.num_triangles(); ++t) {
    const Tri& v = m.triangles[t];
    const Vec2 a = m.positions[v[0]], b = m.positions[v[1]], c = m.positions[v[2]];
    if (p.x < std::min({a.x, b.x, c.x}) - 1e-6 || p.x > std::max({a.x, b.x, c.x}) + 1e-6 ||
        p.y < std::min({a.y, b.y, c.y}) - 1e-6 || p.y > std::max({a.y, b.y, c.y}) + 1e-6) {
      continue;
    }
    const double area = orient(a, b, c);
    const std::array<double, 3> w{orient(p, b, c) / area, orient(a, p, c) / area, orient(a, b, p) / area};
    const double lowest = std::min({w[0], w[1], w[2]});
    if (lowest > best_min) best_min = lowest, best = t, best_w = w;
  }
  if (best < 0 || best_min < -1e-6) invalid("the point " + point(p) + " lies on no control triangle");
  constexpr double kOnEdge = 1e-9;
  for (int k = 0; k < 3; ++k) {
    if (best_w[k] > kOnEdge) continue;
    const int a = m.triangles[best][(k + 1) % 3], b = m.triangles[best][(k + 2) % 3];
    const int s = e.sharp(a, b);
    if (s >= 0) invalid("the curve touches " + sharp_name(m, s) + " at " + point(p));
    const Vec2 pa = m.positions[a], pb = m.positions[b];
    const double len2 = (pb.x - pa.x) * (pb.x - pa.x) + (pb.y - pa.y) * (pb.y - pa.y);
    const double t = std::clamp(((p.x - pa.x) * (pb.x - pa.x) + (p.y - pa.y) * (pb.y - pa.y)) / len2, 1e-6, 1 - 1e-6);
    return e.split_edge(a, b, t);
  }
  return e.split_triangle(best, p);
}

// Whether the open segments (a, b) and (c, d) cross properly.
bool crosses(Vec2 a, Vec2 b, Vec2 c, Vec2 d) {
  const double o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
  return ((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0));
}

// Makes (a, b) an edge by flipping the smooth edges that cross it (Sloan's method: a crossing edge
// whose quad is not convex waits for its neighbours).
void recover_edge(Editable& e, int a, int b) {
  if (e.is_edge(a, b)) return;
  const ControlMesh& m = e.mesh();
  const Vec2 pa = m.positions[a], pb = m.positions[b];
  const double length = std::hypot(pb.x - pa.x, pb.y - pa.y);
  // A smooth vertex on the segment steps off it (a hundredth of a pixel): the edge must pass by.
  for (int v = 0; v < m.num_vertices(); ++v) {
    if (v == a || v == b) continue;
    if (detail::segment_distance(m.positions[v], pa, pb) >= 1e-6 * std::max(1.0, length)) continue;
    if (!e.step_aside(v, {-(pb.y - pa.y) / length * 1e-2, (pb.x - pa.x) / length * 1e-2})) {
      const int s = e.sharp_at(v);
      invalid("the curve " + (s >= 0 ? "crosses " + sharp_name(m, s) + " at" : std::string("passes through")) +
              " control vertex " + std::to_string(v) + " " + point(m.positions[v]) +
              (s >= 0 ? "; features cannot cross yet, so draw it up to the other one" : ""));
    }
  }
  std::vector<EdgeVerts> crossing;
  for (int t = 0; t < m.num_triangles(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const int u = m.triangles[t][k], v = m.triangles[t][(k + 1) % 3];
      if (u > v && e.triangle_of(v, u) >= 0) continue;  // each interior edge once
      if (!crosses(pa, pb, m.positions[u], m.positions[v])) continue;
      const int s = e.sharp(u, v);
      if (s >= 0 || e.triangle_of(v, u) < 0) {
        const Vec2 pu = m.positions[u], pv = m.positions[v];
        const double den = orient(pa, pb, pu) - orient(pa, pb, pv);
        const double x = orient(pa, pb, pu) / den;
        invalid("the curve crosses " + (s >= 0 ? sharp_name(m, s) : std::string("the image border")) + " near " +
                point({pu.x + x * (pv.x - pu.x), pu.y + x * (pv.y - pu.y)}) +
                "; features cannot cross yet, so draw it up to the other one");
      }
      crossing.push_back({u, v});
    }
  }
  size_t guard = 0, limit = 50 * crossing.size() * crossing.size() + 100;
  while (!crossing.empty()) {
    if (++guard > limit) invalid("the curve's edge from " + point(pa) + " to " + point(pb) + " could not be made");
    const EdgeVerts uv = crossing.front();
    crossing.erase(crossing.begin());
    const auto [p, q] = e.opposite(uv[0], uv[1]);
    if (!e.flip(uv[0], uv[1])) {
      crossing.push_back(uv);
      continue;
    }
    if (p != a && p != b && q != a && q != b && crosses(pa, pb, m.positions[p], m.positions[q])) {
      crossing.push_back({p, q});
    }
  }
  if (!e.is_edge(a, b)) invalid("the curve's edge from " + point(pa) + " to " + point(pb) + " could not be made");
}

// Whether d lies inside the circumcircle of the positively oriented (a, b, c).
bool in_circle(Vec2 a, Vec2 b, Vec2 c, Vec2 d) {
  const double ax = a.x - d.x, ay = a.y - d.y, bx = b.x - d.x, by = b.y - d.y, cx = c.x - d.x, cy = c.y - d.y;
  const double det = (ax * ax + ay * ay) * (bx * cy - cx * by) - (bx * bx + by * by) * (ax * cy - cx * ay) +
                     (cx * cx + cy * cy) * (ax * by - bx * ay);
  return det > 1e-9 * (ax * ax + ay * ay + bx * bx + by * by + cx * cx + cy * cy);
}

// Lawson flips over the smooth edges of the changed triangles until they are locally Delaunay.
void make_delaunay(Editable& e) {
  const ControlMesh& m = e.mesh();
  std::vector<EdgeVerts> queue;
  for (int t = 0; t < m.num_triangles(); ++t)
    if (e.changed()[t])
      for (int k = 0; k < 3; ++k) queue.push_back({m.triangles[t][k], m.triangles[t][(k + 1) % 3]});
  const size_t limit = 20 * queue.size() + 100;
  for (size_t i = 0; i < queue.size() && i < limit; ++i) {
    const auto [u, v] = queue[i];
    if (e.sharp(u, v) >= 0) continue;
    const int t1 = e.triangle_of(u, v), t2 = e.triangle_of(v, u);
    if (t1 < 0 || t2 < 0) continue;
    const auto [p, q] = e.opposite(u, v);
    if (!in_circle(m.positions[u], m.positions[v], m.positions[p], m.positions[q])) continue;
    if (!e.flip(u, v)) continue;
    for (const EdgeVerts f : {EdgeVerts{q, v}, EdgeVerts{v, p}, EdgeVerts{p, u}, EdgeVerts{u, q}}) queue.push_back(f);
  }
}

// ---- the color refit ---------------------------------------------------------------------------

// Vertices within `rings` edges of the seeds.
std::vector<uint8_t> grow(const MeshTopology& topology, std::vector<uint8_t> in, int rings) {
  for (int r = 0; r < rings; ++r) {
    std::vector<uint8_t> next = in;
    for (const EdgeVerts& e : topology.edges)
      if (in[e[0]] || in[e[1]]) next[e[0]] = next[e[1]] = 1;
    in = std::move(next);
  }
  return in;
}

// The colors of `mesh` (the edited level) refitted where `free_vertex` says, to `targets` (per
// pixel, the surface before the edit; a pixel is left out where `band` is 1 and its control face
// is in `band_faces`) plus
// `membrane` times the squared differences of the free color values with their neighbours on the
// triangles, plus a light pull to their current values. Returns the number of color values fitted.
int refit_colors(ControlMesh& mesh, const MeshTopology& topology, int width, int height,
                 const std::vector<uint8_t>& free_vertex, const std::vector<std::array<float, 3>>& targets,
                 const std::vector<uint8_t>& band, const std::vector<uint8_t>& band_faces, double membrane) {
  std::vector<int32_t> slot(mesh.num_colors(), -1);
  std::vector<int32_t> owner(mesh.num_colors(), -1);
  for (int t = 0; t < mesh.num_triangles(); ++t)
    for (int k = 0; k < 3; ++k) owner[mesh.triangle_colors[t][k]] = mesh.triangles[t][k];
  int n = 0;
  for (int c = 0; c < mesh.num_colors(); ++c)
    if (free_vertex[owner[c]]) slot[c] = n++;
  if (n == 0) return 0;
  fit_detail::FitSystem system(mesh, topology, width, height, default_fit_depth(mesh));
  fit_detail::locate_pixels(system);
  const SparseMatrix& s = system.s;
  using Triplet = Eigen::Triplet<double>;
  std::vector<Triplet> normal;
  Eigen::MatrixX3d rhs = Eigen::MatrixX3d::Zero(n, 3);
  std::map<int, double> row;  // control color -> weight, for one pixel
  for (int py = 0; py < height; ++py) {
    for (int px = 0; px < width; ++px) {
      const size_t pixel = size_t(py) * width + px;
      const fit_detail::Location& loc = system.located[pixel];
      if (loc.triangle < 0) continue;
      if (band[pixel] && band_faces[system.refined.triangle_parent[loc.triangle]]) continue;
      const Tri& rc = system.refined.triangle_colors[loc.triangle];
      const double w[3] = {1.0 - loc.b1 - loc.b2, loc.b1, loc.b2};
      row.clear();
      bool any = false;
      for (int k = 0; k < 3; ++k) {
        for (SparseMatrix::InnerIterator it(s, rc[k]); it; ++it) {
          row[static_cast<int>(it.col())] += w[k] * it.value();
          any |= slot[it.col()] >= 0;
        }
      }
      if (!any) continue;
      double target[3] = {targets[pixel][0], targets[pixel][1], targets[pixel][2]};
      for (const auto& [c, value] : row) {
        if (slot[c] >= 0) continue;
        target[0] -= value * mesh.colors[c].r, target[1] -= value * mesh.colors[c].g, target[2] -= value * mesh.colors[c].b;
      }
      for (const auto& [c, value] : row) {
        if (slot[c] < 0) continue;
        for (int k = 0; k < 3; ++k) rhs(slot[c], k) += value * target[k];
        for (const auto& [d, other] : row)
          if (slot[d] >= 0) normal.emplace_back(slot[c], slot[d], value * other);
      }
    }
  }
  // The membrane: each color edge of a triangle (counted once per triangle side) with a free end.
  std::set<uint64_t> edges;
  for (const Tri& c : mesh.triangle_colors)
    for (int k = 0; k < 3; ++k) edges.insert(undirected(c[k], c[(k + 1) % 3]));
  const auto value = [&](int c, int k) { return double(k == 0 ? mesh.colors[c].r : k == 1 ? mesh.colors[c].g : mesh.colors[c].b); };
  for (const uint64_t e : edges) {
    const int a = int(e >> 32), b = int(e & 0xffffffffu);
    if (membrane <= 0 || (slot[a] < 0 && slot[b] < 0)) continue;
    for (const auto& [x, y] : {std::pair{a, b}, std::pair{b, a}}) {
      if (slot[x] < 0) continue;
      normal.emplace_back(slot[x], slot[x], membrane);
      if (slot[y] >= 0) {
        normal.emplace_back(slot[x], slot[y], -membrane);
      } else {
        for (int k = 0; k < 3; ++k) rhs(slot[x], k) += membrane * value(y, k);
      }
    }
  }
  // A light pull to the current values keeps every value determined.
  constexpr double kPull = 1e-10;
  for (int c = 0; c < mesh.num_colors(); ++c) {
    if (slot[c] < 0) continue;
    normal.emplace_back(slot[c], slot[c], kPull);
    for (int k = 0; k < 3; ++k) rhs(slot[c], k) += kPull * value(c, k);
  }
  Eigen::SparseMatrix<double> a(n, n);
  a.setFromTriplets(normal.begin(), normal.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(a);
  if (ldlt.info() != Eigen::Success) invalid("the colors around the feature could not be refitted");
  const Eigen::MatrixX3d x = ldlt.solve(rhs);
  for (int c = 0; c < mesh.num_colors(); ++c) {
    if (slot[c] < 0) continue;
    mesh.colors[c] = {float(x(slot[c], 0)), float(x(slot[c], 1)), float(x(slot[c], 2))};
  }
  return n;
}

// The surface of `mesh` at every pixel centre, on the fit's subdivision (float targets).
std::vector<std::array<float, 3>> surface_at_pixels(const ControlMesh& mesh, const MeshTopology& topology,
                                                    int width, int height, int depth) {
  fit_detail::FitSystem system(mesh, topology, width, height, depth);
  fit_detail::locate_pixels(system);
  Eigen::MatrixX3d control(mesh.num_colors(), 3);
  for (int c = 0; c < mesh.num_colors(); ++c) control.row(c) << mesh.colors[c].r, mesh.colors[c].g, mesh.colors[c].b;
  const Eigen::MatrixX3d values = system.s * control;
  std::vector<std::array<float, 3>> out(size_t(width) * height, {0, 0, 0});
  for (size_t p = 0; p < out.size(); ++p) {
    const fit_detail::Location& loc = system.located[p];
    if (loc.triangle < 0) continue;
    const Tri& rc = system.refined.triangle_colors[loc.triangle];
    for (int k = 0; k < 3; ++k) out[p][k] = float(fit_detail::predict(loc, rc, values, k));
  }
  return out;
}

// Re-derives the face-varying color values from the tears: each new value takes the value its
// corners had (they agree: a new tear only splits groups of corners).
void split_colors_at_tears(ControlMesh& mesh, const MeshTopology& topology) {
  int count = 0;
  const std::vector<Tri> fv = face_varying_indices(mesh, topology, count);
  std::vector<Color> colors(count);
  std::vector<double> sum(size_t(count) * 3, 0);
  std::vector<int> seen(count, 0);
  for (int t = 0; t < mesh.num_triangles(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const Color& c = mesh.colors[mesh.triangle_colors[t][k]];
      const int i = fv[t][k];
      sum[3 * i] += c.r, sum[3 * i + 1] += c.g, sum[3 * i + 2] += c.b;
      ++seen[i];
    }
  }
  for (int i = 0; i < count; ++i)
    colors[i] = {float(sum[3 * i] / seen[i]), float(sum[3 * i + 1] / seen[i]), float(sum[3 * i + 2] / seen[i])};
  mesh.colors = std::move(colors);
  mesh.triangle_colors = fv;
}

double mean_edge_near(const ControlMesh& mesh, std::span<const Vec2> points) {
  double sum = 0;
  int count = 0;
  for (const Tri& t : mesh.triangles) {
    const Vec2 a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
    const double x0 = std::min({a.x, b.x, c.x}), x1 = std::max({a.x, b.x, c.x});
    const double y0 = std::min({a.y, b.y, c.y}), y1 = std::max({a.y, b.y, c.y});
    bool near = false;
    for (const Vec2& p : points) near |= p.x >= x0 && p.x <= x1 && p.y >= y0 && p.y <= y1;
    if (!near) continue;
    sum += std::hypot(b.x - a.x, b.y - a.y) + std::hypot(c.x - b.x, c.y - b.y) + std::hypot(a.x - c.x, a.y - c.y);
    count += 3;
  }
  return count ? sum / count : 8.0;
}

}  // namespace

FeatureEditResult add_feature(ControlMesh& mesh_in, int width, int height, std::span<const Vec2> polyline,
                              FeatureKind kind) {
  const MeshTopology before = validate_level(mesh_in, width, height);
  FeatureEditResult result;
  for (const Vec2& p : polyline)
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) invalid("the drawn curve has a point that is not finite");
  const double spacing = std::clamp(mean_edge_near(mesh_in, polyline), 3.0, 30.0);
  result.curve = fit_curve(polyline, spacing);
  std::vector<Vec2> points = result.curve.points;
  // The frame: ends within 1 px of the border go onto it; every other point stays inside.
  constexpr double kMargin = 0.25;
  for (size_t i = 0; i < points.size(); ++i) {
    Vec2& p = points[i];
    const bool end = !result.curve.closed && (i == 0 || i + 1 == points.size());
    if (end) {
      const double dx = std::min(p.x, width - p.x), dy = std::min(p.y, height - p.y);
      if (std::min(dx, dy) <= 1.0) {
        if (dx <= dy) p.x = p.x < width - p.x ? 0.0 : double(width);
        else p.y = p.y < height - p.y ? 0.0 : double(height);
        p.x = std::clamp(p.x, 0.0, double(width)), p.y = std::clamp(p.y, 0.0, double(height));
        continue;
      }
    }
    p.x = std::clamp(p.x, kMargin, width - kMargin), p.y = std::clamp(p.y, kMargin, height - kMargin);
  }
  // The control polygon must not cross itself.
  const size_t spans = result.curve.closed ? points.size() : points.size() - 1;
  for (size_t i = 0; i < spans; ++i)
    for (size_t j = i + 2; j < spans; ++j) {
      if (result.curve.closed && i == 0 && j == spans - 1) continue;
      if (crosses(points[i], points[(i + 1) % points.size()], points[j], points[(j + 1) % points.size()])) {
        invalid("the drawn curve crosses itself near " + point(points[j]));
      }
    }

  ControlMesh mesh = mesh_in;
  mesh.parent_vertices.clear(), mesh.collapses.clear();
  const int old_vertices = mesh.num_vertices();
  Editable e(mesh, width, height);
  std::vector<int32_t> chain;
  for (const Vec2& p : points) {
    const int v = insert_point(e, p);
    if (v < old_vertices) {
      const Vec2 q = mesh.positions[v];
      const bool corner = (q.x == 0 || q.x == width) && (q.y == 0 || q.y == height);
      if (!corner) invalid("the curve's control point " + point(p) + " falls on control vertex " + std::to_string(v));
    }
    if (std::find(chain.begin(), chain.end(), v) != chain.end()) {
      invalid("the curve's control points " + point(p) + " repeat a vertex");
    }
    chain.push_back(v);
  }
  if (result.curve.closed) chain.push_back(chain.front());
  for (size_t i = 0; i + 1 < chain.size(); ++i) {
    recover_edge(e, chain[i], chain[i + 1]);
    if (e.triangle_of(chain[i + 1], chain[i]) < 0 || e.triangle_of(chain[i], chain[i + 1]) < 0) {
      invalid("the curve runs along the image border near " + point(mesh.positions[chain[i]]));
    }
    e.mark(chain[i], chain[i + 1], 0);  // kept by the flips that follow
  }
  make_delaunay(e);
  result.flips = e.flips;
  result.vertices_added = mesh.num_vertices() - old_vertices;

  int32_t id = 0;
  for (const Feature& f : mesh.features) id = std::max(id, f.id + 1);
  if (kind == FeatureKind::kTear) {
    Feature f;
    f.id = id;
    f.vertices = chain;
    mesh.features.push_back(std::move(f));
    result.feature = static_cast<int>(mesh.features.size()) - 1;
    result.id = id;
  } else {
    for (size_t i = 0; i + 1 < chain.size(); ++i) mesh.creases.push_back({chain[i], chain[i + 1]});
  }
  const MeshTopology topology = MeshTopology::build(mesh, width, height);
  split_colors_at_tears(mesh, topology);

  // Refit the colors of the vertices within two rings of a changed triangle to the old surface.
  std::vector<uint8_t> touched(mesh.num_vertices(), 0);
  for (int t = 0; t < mesh.num_triangles(); ++t)
    if (e.changed()[t])
      for (const int v : mesh.triangles[t]) touched[v] = 1;
  const std::vector<uint8_t> free_vertex = grow(topology, touched, 2);
  const std::vector<std::array<float, 3>> targets =
      surface_at_pixels(mesh_in, before, width, height, default_fit_depth(mesh));
  result.colors_refit = refit_colors(mesh, topology, width, height, free_vertex, targets,
                                     std::vector<uint8_t>(size_t(width) * height, 0),
                                     std::vector<uint8_t>(mesh.num_triangles(), 0), 0.0);
  validate_level(mesh, width, height);
  mesh_in = std::move(mesh);
  return result;
}

FeatureEditResult delete_feature(ControlMesh& mesh_in, int width, int height, int feature) {
  const MeshTopology before = validate_level(mesh_in, width, height);
  if (feature < 0 || feature >= static_cast<int>(mesh_in.features.size())) {
    invalid("feature " + std::to_string(feature) + " is out of range (the level has " +
            std::to_string(mesh_in.features.size()) + " features)");
  }
  FeatureEditResult result;
  result.feature = feature;
  const Feature gone = mesh_in.features[feature];
  result.id = gone.id;
  ControlMesh mesh = mesh_in;
  mesh.parent_vertices.clear(), mesh.collapses.clear();
  mesh.features.erase(mesh.features.begin() + feature);
  const MeshTopology topology = MeshTopology::build(mesh, width, height);
  split_colors_at_tears(mesh, topology);  // merges the two sides' values (their mean)

  // The jump across the feature at each of its vertices: the largest channel difference between
  // the color values there.
  std::vector<std::vector<int32_t>> values(mesh_in.num_vertices());
  for (int t = 0; t < mesh_in.num_triangles(); ++t)
    for (int k = 0; k < 3; ++k) values[mesh_in.triangles[t][k]].push_back(mesh_in.triangle_colors[t][k]);
  std::vector<double> jump;
  std::vector<Vec2> polygon;
  for (const int v : gone.vertices) {
    double j = 0;
    for (const int a : values[v])
      for (const int b : values[v]) {
        // Control values may overshoot the 8-bit range; what shows is clamped.
        const Color ca = mesh_in.colors[a], cb = mesh_in.colors[b];
        const auto shown = [](float c) { return std::clamp(double(c), 0.0, 255.0); };
        j = std::max({j, std::abs(shown(ca.r) - shown(cb.r)), std::abs(shown(ca.g) - shown(cb.g)),
                      std::abs(shown(ca.b) - shown(cb.b))});
      }
    jump.push_back(j);
    polygon.push_back(mesh_in.positions[v]);
  }
  // The band where the membrane alone sets the colors: the ramp across it climbs about
  // kRampSlope levels a pixel, and it is at least 1.5 control edges wide on each side.
  constexpr double kRampSlope = 1.5;
  constexpr double kBandEdges = 3.5;
  // The membrane's weight against one pixel's: light, so that outside the band the data holds the
  // colors; inside it, where there is no data, the membrane alone sets them.
  constexpr double kMembrane = 1e-3;
  const double edge = mean_edge_near(mesh_in, polygon);
  auto band_for = [&](double j) { return std::max({kBandEdges * edge, j / (2 * kRampSlope), 2.0}); };
  const double widest = band_for(*std::max_element(jump.begin(), jump.end()));
  const int rings = std::min(16, 2 + static_cast<int>(std::ceil(widest / std::max(edge, 1.0))));
  std::vector<uint8_t> seeds(mesh.num_vertices(), 0);
  for (const int v : gone.vertices) seeds[v] = 1;
  const std::vector<uint8_t> free_vertex = grow(topology, seeds, rings);

  // The pixels within the band of the curve as it was drawn (its limit, 8 samples a span, each
  // with the jump interpolated between the span's vertices).
  const bool closed = gone.closed();
  if (closed) polygon.pop_back(), jump.pop_back();
  constexpr int kPerSpan = 8;
  const std::vector<Vec2> curve = sample_bspline(polygon, closed, kPerSpan);
  std::vector<uint8_t> band(size_t(width) * height, 0);
  const size_t n = polygon.size();
  for (size_t i = 0; i + 1 < curve.size(); ++i) {
    const size_t span = i / kPerSpan;
    const double t = double(i % kPerSpan) / kPerSpan;
    const double j = (1 - t) * jump[span % n] + t * jump[(span + 1) % n];
    detail::for_pixels_near_segment(curve[i].x, curve[i].y, curve[i + 1].x, curve[i + 1].y, band_for(j), width,
                                    height, [&](int x, int y) { band[size_t(y) * width + x] = 1; });
  }
  // The band stops at the tears that stay: its control faces are those reached from the feature
  // without crossing a sharp edge, within the widest band (and two edges) of the curve.
  std::vector<uint8_t> band_faces(mesh.num_triangles(), 0);
  {
    const double reach = widest + 2 * edge;
    auto near_curve = [&](int f) {
      const Tri& t = mesh.triangles[f];
      const Vec2 c{(mesh.positions[t[0]].x + mesh.positions[t[1]].x + mesh.positions[t[2]].x) / 3,
                   (mesh.positions[t[0]].y + mesh.positions[t[1]].y + mesh.positions[t[2]].y) / 3};
      for (size_t i = 0; i + 1 < curve.size(); ++i)
        if (detail::segment_distance(c, curve[i], curve[i + 1]) <= reach) return true;
      return false;
    };
    std::vector<int> queue;
    for (size_t i = 0; i + 1 < gone.vertices.size(); ++i) {
      const int e = topology.find_edge(gone.vertices[i], gone.vertices[i + 1]);
      for (const int f : topology.edge_faces[e])
        if (f >= 0 && !band_faces[f]) band_faces[f] = 1, queue.push_back(f);
    }
    for (size_t q = 0; q < queue.size(); ++q) {
      for (const int e : topology.face_edges[queue[q]]) {
        if (is_sharp(topology.edge_tags[e])) continue;
        for (const int f : topology.edge_faces[e])
          if (f >= 0 && !band_faces[f] && near_curve(f)) band_faces[f] = 1, queue.push_back(f);
      }
    }
  }
  const std::vector<std::array<float, 3>> targets =
      surface_at_pixels(mesh_in, before, width, height, default_fit_depth(mesh_in));
  result.colors_refit = refit_colors(mesh, topology, width, height, free_vertex, targets, band, band_faces, kMembrane);
  validate_level(mesh, width, height);
  mesh_in = std::move(mesh);
  return result;
}

}  // namespace subvec
