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
#include "edit/feature_edit_p.h"
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

CurveFit fit_curve(std::span<const Vec2> polyline, double spacing, double tolerance, bool may_close) {
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
  fit.closed = may_close && poly.size() > 3 && gap <= kCloseDistance && r.length > 4 * kCloseDistance;
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
    // More control points, up to one every kMinSpacing; none more to add ends it. (Without that
    // stop a piece 2.9 px long between two junctions, held to 2 points, looped forever: a
    // GrabCut rectangle on a photograph hung `subvec edit`.)
    const int more = std::min(std::max(n + 1, static_cast<int>(std::ceil(n * 1.5))),
                              static_cast<int>(r.length / kMinSpacing) + 1);
    if (more <= n) break;
    n = more;
  }
  return fit;
}

namespace edit_detail {

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

}  // namespace edit_detail

using edit_detail::split_colors_at_tears;

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

  // Splits the edge (a, b) at p = a + s (b - a); returns the new vertex. Each side of an interior
  // edge gets its own new color value, interpolated on that side: equal values across a smooth
  // edge or a crease (the caller merges them with face_varying_indices), different across a tear.
  // A sharp edge's two halves stay sharp.
  int split_edge(int a, int b, double s) {
    int t1 = triangle_of(a, b), t2 = triangle_of(b, a);
    if (t1 < 0) std::swap(a, b), std::swap(t1, t2), s = 1 - s;
    const Vec2 pa = m_.positions[a], pb = m_.positions[b];
    const int nv = add_vertex({pa.x + s * (pb.x - pa.x), pa.y + s * (pb.y - pa.y)});
    const int n = m_.num_triangles();
    const int k = corner(t1, a);
    const Tri v = m_.triangles[t1], c = m_.triangle_colors[t1];
    const int ca = c[k], cb = c[(k + 1) % 3], cc = c[(k + 2) % 3], vc = v[(k + 2) % 3];
    const int nc = add_color(mix({ca, cb, 0}, {1 - s, s, 0}));
    int j = -1, vd = -1, cd = -1, ca2 = -1, cb2 = -1, nc2 = -1;
    if (t2 >= 0) {
      j = corner(t2, b);
      vd = m_.triangles[t2][(j + 2) % 3];
      cb2 = m_.triangle_colors[t2][j], ca2 = m_.triangle_colors[t2][(j + 1) % 3], cd = m_.triangle_colors[t2][(j + 2) % 3];
      nc2 = add_color(mix({ca2, cb2, 0}, {1 - s, s, 0}));
    }
    set(t1, {a, nv, vc}, {ca, nc, cc});
    set(n, {nv, b, vc}, {nc, cb, cc});
    if (t2 >= 0) {
      set(t2, {b, nv, vd}, {cb2, nc2, cd});
      set(n + 1, {nv, a, vd}, {nc2, ca2, cd});
    }
    auto it = sharp_.find(undirected(a, b));
    if (it != sharp_.end()) {
      const int value = it->second;
      sharp_.erase(it);
      sharp_[undirected(a, nv)] = sharp_[undirected(nv, b)] = value;
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

// The sharp value of the new curve's own edges.
constexpr int kDrawn = 1 << 30;

std::string sharp_name(const ControlMesh& mesh, int value) {
  if (value == kDrawn) return "itself";
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
              (s >= 0 ? " (draw it across between two control points)" : ""));
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
                (s >= 0 && s != kDrawn ? " between two of its control points (draw it more steeply across)" : ""));
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
// is in `band_faces`) plus `membrane` times the Dirichlet energy of the free color values (their
// squared differences with their neighbours on the triangles, cotangent-weighted), plus a light
// pull to their current values. Returns the number of color values fitted.
// `system` is the fit's system of `mesh` (its positions and topology), its pixels located.
int refit_colors(ControlMesh& mesh, const fit_detail::FitSystem& system, int width, int height,
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
  const SparseMatrix& s = system.s;
  using Triplet = Eigen::Triplet<double>;
  std::vector<Triplet> normal;
  Eigen::MatrixX3d rhs = Eigen::MatrixX3d::Zero(n, 3);
  // The refined color values whose stencil reaches a free color: only pixels on them have a row
  // (the others depend on fixed colors alone), so most of the image is skipped at once.
  std::vector<uint8_t> reaches(size_t(s.rows()), 0);
  for (int r = 0; r < s.rows(); ++r)
    for (SparseMatrix::InnerIterator it(s, r); it; ++it) reaches[r] |= slot[it.col()] >= 0;
  std::map<int, double> row;  // control color -> weight, for one pixel
  for (int py = 0; py < height; ++py) {
    for (int px = 0; px < width; ++px) {
      const size_t pixel = size_t(py) * width + px;
      const fit_detail::Location& loc = system.located[pixel];
      if (loc.triangle < 0) continue;
      if (band[pixel] && band_faces[system.refined.triangle_parent[loc.triangle]]) continue;
      const Tri& rc = system.refined.triangle_colors[loc.triangle];
      if (!reaches[rc[0]] && !reaches[rc[1]] && !reaches[rc[2]]) continue;
      const double w[3] = {1.0 - loc.b1 - loc.b2, loc.b1, loc.b2};
      row.clear();
      for (int k = 0; k < 3; ++k)
        for (SparseMatrix::InnerIterator it(s, rc[k]); it; ++it) row[static_cast<int>(it.col())] += w[k] * it.value();
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
  // The membrane: the Dirichlet energy of the colors' piecewise linear interpolant on the control
  // triangles, the squared differences of each triangle's corner values weighted by half the
  // cotangent of the angle opposite. Unit weights, tried first, bunched the ramp where the former
  // tear's vertices lie dense along it; with the cotangents a linear ramp is the membrane's own.
  const auto value = [&](int c, int k) { return double(k == 0 ? mesh.colors[c].r : k == 1 ? mesh.colors[c].g : mesh.colors[c].b); };
  if (membrane > 0) {
    for (int t = 0; t < mesh.num_triangles(); ++t) {
      const Tri& v = mesh.triangles[t];
      const Tri& c = mesh.triangle_colors[t];
      if (slot[c[0]] < 0 && slot[c[1]] < 0 && slot[c[2]] < 0) continue;
      const Vec2 p[3] = {mesh.positions[v[0]], mesh.positions[v[1]], mesh.positions[v[2]]};
      const double area2 = std::abs((p[1].x - p[0].x) * (p[2].y - p[0].y) - (p[1].y - p[0].y) * (p[2].x - p[0].x));
      for (int k = 0; k < 3; ++k) {
        // The edge (k+1, k+2) and the corner k opposite it: cot = dot / |cross|.
        const Vec2 o = p[k], u = p[(k + 1) % 3], w = p[(k + 2) % 3];
        const double dot = (u.x - o.x) * (w.x - o.x) + (u.y - o.y) * (w.y - o.y);
        const double weight = membrane * 0.5 * dot / std::max(area2, 1e-9);
        const int a = c[(k + 1) % 3], b = c[(k + 2) % 3];
        for (const auto& [x, y] : {std::pair{a, b}, std::pair{b, a}}) {
          if (slot[x] < 0) continue;
          normal.emplace_back(slot[x], slot[x], weight);
          if (slot[y] >= 0) {
            normal.emplace_back(slot[x], slot[y], -weight);
          } else {
            for (int j = 0; j < 3; ++j) rhs(slot[x], j) += weight * value(y, j);
          }
        }
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

int refit_colors(ControlMesh& mesh, const MeshTopology& topology, int width, int height,
                 const std::vector<uint8_t>& free_vertex, const std::vector<std::array<float, 3>>& targets,
                 const std::vector<uint8_t>& band, const std::vector<uint8_t>& band_faces, double membrane) {
  fit_detail::FitSystem system(mesh, topology, width, height, default_fit_depth(mesh));
  fit_detail::locate_pixels(system);
  return refit_colors(mesh, system, width, height, free_vertex, targets, band, band_faces, membrane);
}

// The refined color values of `mesh` on its fit's `system`: the stencils times its colors.
Eigen::MatrixX3d refined_colors(const ControlMesh& mesh, const fit_detail::FitSystem& system) {
  Eigen::MatrixX3d control(mesh.num_colors(), 3);
  for (int c = 0; c < mesh.num_colors(); ++c) control.row(c) << mesh.colors[c].r, mesh.colors[c].g, mesh.colors[c].b;
  return system.s * control;
}

// The surface of `mesh` at every pixel centre, on the fit's subdivision (float targets).
std::vector<std::array<float, 3>> surface_at_pixels(const ControlMesh& mesh, const MeshTopology& topology,
                                                    int width, int height, int depth) {
  fit_detail::FitSystem system(mesh, topology, width, height, depth);
  fit_detail::locate_pixels(system);
  const Eigen::MatrixX3d values = refined_colors(mesh, system);
  std::vector<std::array<float, 3>> out(size_t(width) * height, {0, 0, 0});
  for (size_t p = 0; p < out.size(); ++p) {
    const fit_detail::Location& loc = system.located[p];
    if (loc.triangle < 0) continue;
    const Tri& rc = system.refined.triangle_colors[loc.triangle];
    for (int k = 0; k < 3; ++k) out[p][k] = float(fit_detail::predict(loc, rc, values, k));
  }
  return out;
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

// ---- junctions ---------------------------------------------------------------------------------

// Where a drawn polyline meets an existing feature or crease: its arc length along the polyline,
// the point, and the sharp edge (a, b) it lies on.
struct Junction {
  double s = 0;
  Vec2 at;
  int32_t a = -1, b = -1;
};

// The sharp interior edges of the mesh (feature chains, creases).
std::vector<EdgeVerts> sharp_edges(const ControlMesh& mesh) {
  std::vector<EdgeVerts> out = mesh.creases;
  for (const Feature& f : mesh.features)
    for (size_t i = 0; i + 1 < f.vertices.size(); ++i) out.push_back({f.vertices[i], f.vertices[i + 1]});
  return out;
}

// The junctions of `poly` with the mesh's sharp edges: every crossing, and an open end within
// kJoinDistance of a sharp edge (the end then moves onto it). Sorted along the polyline; one per
// kJoinDistance of arc length.
std::vector<Junction> find_junctions(const ControlMesh& mesh, std::vector<Vec2>& poly, bool closed) {
  const std::vector<EdgeVerts> sharp = sharp_edges(mesh);
  std::vector<Junction> out;
  std::vector<double> arc{0};
  for (size_t i = 1; i < poly.size(); ++i)
    arc.push_back(arc.back() + std::hypot(poly[i].x - poly[i - 1].x, poly[i].y - poly[i - 1].y));
  for (size_t i = 0; i + 1 < poly.size(); ++i) {
    const Vec2 p = poly[i], q = poly[i + 1];
    for (const EdgeVerts& e : sharp) {
      const Vec2 a = mesh.positions[e[0]], b = mesh.positions[e[1]];
      if (std::max(a.x, b.x) < std::min(p.x, q.x) || std::min(a.x, b.x) > std::max(p.x, q.x) ||
          std::max(a.y, b.y) < std::min(p.y, q.y) || std::min(a.y, b.y) > std::max(p.y, q.y) || !crosses(p, q, a, b)) {
        continue;
      }
      const double t = orient(a, b, p) / (orient(a, b, p) - orient(a, b, q));
      out.push_back({arc[i] + t * (arc[i + 1] - arc[i]), {p.x + t * (q.x - p.x), p.y + t * (q.y - p.y)}, e[0], e[1]});
    }
  }
  // A segment through a vertex of a chain meets it there.
  std::vector<int32_t> chain_vertices;
  for (const EdgeVerts& e : sharp) chain_vertices.push_back(e[0]), chain_vertices.push_back(e[1]);
  std::sort(chain_vertices.begin(), chain_vertices.end());
  chain_vertices.erase(std::unique(chain_vertices.begin(), chain_vertices.end()), chain_vertices.end());
  for (size_t i = 0; i + 1 < poly.size(); ++i) {
    const Vec2 p = poly[i], q = poly[i + 1];
    const double len = std::hypot(q.x - p.x, q.y - p.y);
    for (const int32_t w : chain_vertices) {
      const Vec2 c = mesh.positions[w];
      Vec2 foot;
      if (detail::segment_distance(c, p, q, &foot) >= 1e-6 * std::max(1.0, len)) continue;
      const double t = len > 0 ? std::hypot(foot.x - p.x, foot.y - p.y) / len : 0;
      out.push_back({arc[i] + t * (arc[i + 1] - arc[i]), c, w, w});
    }
  }
  // Ends near a feature or crease join it.
  auto join_end = [&](bool last) {
    const Vec2 p = last ? poly.back() : poly.front();
    double best = kJoinDistance;
    Junction j;
    for (const EdgeVerts& e : sharp) {
      Vec2 q;
      const double d = detail::segment_distance(p, mesh.positions[e[0]], mesh.positions[e[1]], &q);
      if (d < best) best = d, j = {last ? arc.back() : 0.0, q, e[0], e[1]};
    }
    if (j.a < 0) return;
    for (const Junction& k : out)
      if (std::abs(k.s - j.s) < kJoinDistance) return;  // it crosses there already
    (last ? poly.back() : poly.front()) = j.at;
    out.push_back(j);
  };
  if (!closed) join_end(false), join_end(true);
  std::sort(out.begin(), out.end(), [](const Junction& x, const Junction& y) { return x.s < y.s; });
  std::vector<Junction> kept;
  for (const Junction& j : out)
    if (kept.empty() || j.s - kept.back().s >= kJoinDistance) kept.push_back(j);
  return kept;
}

// The part of `poly` between arc lengths s0 and s1, its ends interpolated.
std::vector<Vec2> sub_polyline(const std::vector<Vec2>& poly, double s0, double s1) {
  std::vector<Vec2> out;
  double arc = 0;
  auto at = [&](size_t i, double s) {
    const double len = std::hypot(poly[i + 1].x - poly[i].x, poly[i + 1].y - poly[i].y);
    const double t = len > 0 ? std::clamp((s - arc) / len, 0.0, 1.0) : 0;
    return Vec2{poly[i].x + t * (poly[i + 1].x - poly[i].x), poly[i].y + t * (poly[i + 1].y - poly[i].y)};
  };
  for (size_t i = 0; i + 1 < poly.size(); ++i) {
    const double len = std::hypot(poly[i + 1].x - poly[i].x, poly[i + 1].y - poly[i].y);
    if (arc + len >= s0 && arc <= s1) {
      if (out.empty()) out.push_back(at(i, s0));
      if (arc + len <= s1) {
        out.push_back(poly[i + 1]);
      } else {
        out.push_back(at(i, s1));
        break;
      }
    }
    arc += len;
  }
  return out;
}

// Puts control points in the frame: an open curve's end within 1 px of the border goes onto it
// (unless it is a junction); every other point stays kMargin inside.
void frame_points(std::vector<Vec2>& points, bool closed, bool first_fixed, bool last_fixed, int width, int height) {
  constexpr double kMargin = 0.25;
  for (size_t i = 0; i < points.size(); ++i) {
    Vec2& p = points[i];
    if ((i == 0 && first_fixed) || (i + 1 == points.size() && last_fixed)) continue;
    const bool end = !closed && (i == 0 || i + 1 == points.size());
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
  const size_t spans = closed ? points.size() : points.size() - 1;
  for (size_t i = 0; i < spans; ++i)
    for (size_t j = i + 2; j < spans; ++j) {
      if (closed && i == 0 && j == spans - 1) continue;
      if (crosses(points[i], points[(i + 1) % points.size()], points[j], points[(j + 1) % points.size()])) {
        invalid("the drawn curve crosses itself near " + point(points[j]));
      }
    }
}

// Splits the sharp edge of the junction in the mesh and in the chain (feature or creases) that
// holds it; returns the new vertex, a corner where the new curve meets the old one.
int insert_junction(Editable& e, const Junction& j) {
  ControlMesh& m = e.mesh();
  // The edge may have been split by an earlier junction: the piece of it that holds the point.
  int a = -1, b = -1;
  double best = std::numeric_limits<double>::infinity();
  for (const EdgeVerts& edge : sharp_edges(m)) {
    const double d = detail::segment_distance(j.at, m.positions[edge[0]], m.positions[edge[1]]);
    if (d < best) best = d, a = edge[0], b = edge[1];
  }
  const Vec2 pa = m.positions[a], pb = m.positions[b];
  for (const int v : {a, b})
    if (std::hypot(m.positions[v].x - j.at.x, m.positions[v].y - j.at.y) < 1e-3) return v;  // on a vertex
  const double len2 = (pb.x - pa.x) * (pb.x - pa.x) + (pb.y - pa.y) * (pb.y - pa.y);
  const double t = std::clamp(((j.at.x - pa.x) * (pb.x - pa.x) + (j.at.y - pa.y) * (pb.y - pa.y)) / len2, 1e-3, 1 - 1e-3);
  const int nv = e.split_edge(a, b, t);
  for (Feature& f : m.features)
    for (size_t i = 0; i + 1 < f.vertices.size(); ++i)
      if ((f.vertices[i] == a && f.vertices[i + 1] == b) || (f.vertices[i] == b && f.vertices[i + 1] == a)) {
        f.vertices.insert(f.vertices.begin() + long(i) + 1, nv);
        return nv;
      }
  for (size_t i = 0; i < m.creases.size(); ++i) {
    const EdgeVerts c = m.creases[i];
    if ((c[0] == a && c[1] == b) || (c[0] == b && c[1] == a)) {
      m.creases[i] = {c[0], nv};
      m.creases.push_back({nv, c[1]});
      return nv;
    }
  }
  return nv;
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

  // The pieces between junctions with existing features: each its own fit, ending on them.
  std::vector<Vec2> poly;
  for (const Vec2& q : polyline)
    if (poly.empty() || std::hypot(q.x - poly.back().x, q.y - poly.back().y) > 1e-9) poly.push_back(q);
  if (result.curve.closed) poly.back() = poly.front();
  std::vector<Junction> junctions = find_junctions(mesh_in, poly, result.curve.closed);
  // A closed drawing that meets features starts and ends at its first junction.
  const bool loop = result.curve.closed && !junctions.empty();
  if (loop) {
    const Junction start = junctions.front();
    double total = 0;
    for (size_t i = 1; i < poly.size(); ++i) total += std::hypot(poly[i].x - poly[i - 1].x, poly[i].y - poly[i - 1].y);
    std::vector<Vec2> turned = sub_polyline(poly, start.s, total);
    const std::vector<Vec2> rest = sub_polyline(poly, 0, start.s);
    turned.insert(turned.end(), rest.begin() + 1, rest.end());
    turned.front() = turned.back() = start.at;
    poly = std::move(turned);
    junctions = find_junctions(mesh_in, poly, true);
    double length = 0;
    for (size_t i = 1; i < poly.size(); ++i) length += std::hypot(poly[i].x - poly[i - 1].x, poly[i].y - poly[i - 1].y);
    std::erase_if(junctions, [&](const Junction& j) { return j.s < kJoinDistance || j.s > length - kJoinDistance; });
    junctions.insert(junctions.begin(), Junction{0.0, start.at, start.a, start.b});
  }
  struct Piece {
    CurveFit fit;
    int first = -1, last = -1;  // junction indices at its ends, -1: free
  };
  std::vector<Piece> pieces;
  if (junctions.empty()) {
    pieces.push_back({result.curve, -1, -1});
  } else {
    double length = 0;
    for (size_t i = 1; i < poly.size(); ++i) length += std::hypot(poly[i].x - poly[i - 1].x, poly[i].y - poly[i - 1].y);
    std::vector<double> cuts{0};
    for (size_t k = loop ? 1 : 0; k < junctions.size(); ++k) cuts.push_back(junctions[k].s);
    cuts.push_back(length);
    for (size_t k = 0; k + 1 < cuts.size(); ++k) {
      const double s0 = cuts[k], s1 = cuts[k + 1];
      if (s1 - s0 < kMinLength) continue;
      // Piece k runs from cut k to cut k + 1: junction k - 1 to junction k (an end of the
      // polyline at either end of the list; a junction at an end leaves an empty piece there).
      std::vector<Vec2> part = sub_polyline(poly, s0, s1);
      // (A loop's junction 0 is both ends: piece k then runs from junction k to k + 1, or 0.)
      const int n = static_cast<int>(junctions.size());
      const int first = loop ? int(k) : k == 0 ? -1 : int(k) - 1;
      const int last = loop ? (int(k) + 1) % n : int(k) < n ? int(k) : -1;
      if (first >= 0) part.front() = junctions[first].at;
      if (last >= 0) part.back() = junctions[last].at;
      Piece piece;
      piece.fit = fit_curve(part, spacing, 0.5, false);
      piece.first = first, piece.last = last;
      pieces.push_back(std::move(piece));
    }
    if (pieces.empty()) invalid("the drawn curve is too short between the features it meets");
    result.curve = pieces.front().fit;
  }

  ControlMesh mesh = mesh_in;
  mesh.parent_vertices.clear(), mesh.collapses.clear();
  const int old_vertices = mesh.num_vertices();
  Editable e(mesh, width, height);
  std::vector<int> junction_vertex(junctions.size(), -1);
  auto junction_at = [&](int j) {
    if (junction_vertex[j] < 0) junction_vertex[j] = insert_junction(e, junctions[j]);
    return junction_vertex[j];
  };
  std::vector<std::vector<int32_t>> chains;
  for (Piece& piece : pieces) {
    std::vector<Vec2>& points = piece.fit.points;
    frame_points(points, piece.fit.closed, piece.first >= 0, piece.last >= 0, width, height);
    std::vector<int32_t> chain;
    for (size_t i = 0; i < points.size(); ++i) {
      int v;
      if (i == 0 && piece.first >= 0) {
        v = junction_at(piece.first);
      } else if (i + 1 == points.size() && piece.last >= 0) {
        v = junction_at(piece.last);
      } else {
        // A control point on an existing vertex (to 1e-6 px) takes it, unless a feature or a
        // crease holds it already (the drawing would touch that one without a junction).
        v = insert_point(e, points[i]);
        if (v < old_vertices && e.sharp_at(v) >= 0) {
          invalid("the curve's control point " + point(points[i]) + " falls on control vertex " + std::to_string(v) +
                  " of " + sharp_name(mesh, e.sharp_at(v)));
        }
      }
      const bool closes = i + 1 == points.size() && i > 1 && v == chain.front();  // a loop on one junction
      if (!closes && std::find(chain.begin(), chain.end(), v) != chain.end()) {
        invalid("the curve's control points " + point(points[i]) + " repeat a vertex");
      }
      chain.push_back(v);
    }
    if (piece.fit.closed) chain.push_back(chain.front());
    chains.push_back(std::move(chain));
  }
  for (const std::vector<int32_t>& chain : chains) {
    for (size_t i = 0; i + 1 < chain.size(); ++i) {
      recover_edge(e, chain[i], chain[i + 1]);
      if (e.triangle_of(chain[i + 1], chain[i]) < 0 || e.triangle_of(chain[i], chain[i + 1]) < 0) {
        invalid("the curve runs along the image border near " + point(mesh.positions[chain[i]]));
      }
      e.mark(chain[i], chain[i + 1], kDrawn);  // kept by the flips that follow
    }
  }
  make_delaunay(e);
  result.flips = e.flips;
  result.vertices_added = mesh.num_vertices() - old_vertices;
  result.pieces = static_cast<int>(chains.size());
  result.junctions = static_cast<int>(std::count_if(junction_vertex.begin(), junction_vertex.end(), [](int v) { return v >= 0; }));

  int32_t id = 0;
  for (const Feature& f : mesh.features) id = std::max(id, f.id + 1);
  for (const std::vector<int32_t>& chain : chains) {
    if (kind == FeatureKind::kTear) {
      Feature f;
      f.id = id++;
      f.vertices = chain;
      mesh.features.push_back(std::move(f));
      if (result.feature < 0) result.feature = static_cast<int>(mesh.features.size()) - 1;
    } else {
      for (size_t i = 0; i + 1 < chain.size(); ++i) mesh.creases.push_back({chain[i], chain[i + 1]});
    }
  }
  if (kind == FeatureKind::kTear) result.id = mesh.features[result.feature].id;
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

namespace {

// The pixels within 2 px of a tear or crease of `system`'s limit mesh.
std::vector<uint8_t> near_sharp_pixels(const fit_detail::FitSystem& system, int width, int height) {
  std::vector<uint8_t> near(size_t(width) * height, 0);
  for (const auto* edges : {&system.refined.tear_edges, &system.refined.crease_edges})
    for (const EdgeVerts& e : *edges) {
      const float* p = &system.limit[2 * size_t(e[0])];
      const float* q = &system.limit[2 * size_t(e[1])];
      detail::for_pixels_near_segment(p[0], p[1], q[0], q[1], 2.0, width, height,
                                      [&](int x, int y) { near[size_t(y) * width + x] = 1; });
    }
  return near;
}

// Which spans of `curve` (`per_span` samples each) the surface of `mesh` (`system`: its fit's
// system, pixels located) crosses by a step of more than `max_step` levels (any channel, 8-bit):
// the two pixels on either side of each sample segment's midpoint, both on `faces` and not
// `by_sharp` (near_sharp_pixels: a tear or crease that stays makes a step of its own).
std::vector<uint8_t> steep_spans(const ControlMesh& mesh, const fit_detail::FitSystem& system, int width, int height,
                                 std::span<const Vec2> curve, int per_span, const std::vector<uint8_t>& faces,
                                 const std::vector<uint8_t>& by_sharp, int max_step) {
  const Eigen::MatrixX3d limit = refined_colors(mesh, system);
  auto at = [&](int x, int y, std::array<double, 3>& out) {
    const fit_detail::Location& loc = system.located[size_t(y) * width + x];
    if (loc.triangle < 0 || by_sharp[size_t(y) * width + x] || !faces[system.refined.triangle_parent[loc.triangle]])
      return false;
    const Tri& rc = system.refined.triangle_colors[loc.triangle];
    for (int k = 0; k < 3; ++k) out[k] = std::round(std::clamp(fit_detail::predict(loc, rc, limit, k), 0.0, 255.0));
    return true;
  };
  std::vector<uint8_t> steep((curve.size() - 1 + per_span - 1) / per_span, 0);
  for (size_t i = 0; i + 1 < curve.size(); ++i) {
    const Vec2 a = curve[i], b = curve[i + 1];
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    if (len == 0) continue;
    const Vec2 m{(a.x + b.x) / 2, (a.y + b.y) / 2};
    const Vec2 normal{-(b.y - a.y) / len, (b.x - a.x) / len};
    const int x = int(std::floor(m.x)), y = int(std::floor(m.y));
    for (const auto& [dx, dy] : {std::pair{1, 0}, std::pair{0, 1}, std::pair{-1, 0}, std::pair{0, -1}}) {
      const int x1 = x + dx, y1 = y + dy;
      if (std::min({x, y, x1, y1}) < 0 || std::max(x, x1) >= width || std::max(y, y1) >= height) continue;
      const double s0 = (x + 0.5 - m.x) * normal.x + (y + 0.5 - m.y) * normal.y;
      const double s1 = (x1 + 0.5 - m.x) * normal.x + (y1 + 0.5 - m.y) * normal.y;
      std::array<double, 3> c0, c1;
      if (s0 * s1 >= 0 || !at(x, y, c0) || !at(x1, y1, c1)) continue;
      for (int k = 0; k < 3; ++k)
        if (std::abs(c0[k] - c1[k]) > max_step) steep[i / per_span] = 1;
    }
  }
  return steep;
}

// Deletes the chain `gone` (a tear feature, or a chain of creases when `crease`): see
// delete_feature.
FeatureEditResult delete_chain(ControlMesh& mesh_in, int width, int height, const MeshTopology& before,
                               int feature, const Feature& gone, bool crease) {
  FeatureEditResult result;
  result.feature = feature;
  result.id = gone.id;
  ControlMesh mesh = mesh_in;
  mesh.parent_vertices.clear(), mesh.collapses.clear();
  if (crease) {
    std::set<uint64_t> edges;
    for (size_t i = 0; i + 1 < gone.vertices.size(); ++i) edges.insert(undirected(gone.vertices[i], gone.vertices[i + 1]));
    std::erase_if(mesh.creases, [&](const EdgeVerts& e) { return edges.count(undirected(e[0], e[1])) > 0; });
  } else {
    mesh.features.erase(mesh.features.begin() + feature);
  }
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
  // The band where the membrane alone sets the colors: J / (2 kRampSlope) pixels on each side of
  // a jump J, so the ramp across it climbs about kRampSlope levels a pixel, and at least
  // kBandEdges control edges (wider than the stencils' two rings, or the data at its edge would
  // rebuild the step; short features need the width most, the ramp being steepest at a curve's
  // ends). Where that is not enough the band widens (below).
  constexpr double kRampSlope = 3.0;
  constexpr double kBandEdges = 4;
  // The membrane's weight against one pixel's: light, so that outside the band the data holds the
  // colors; inside it, where there is no data, the membrane alone sets them.
  constexpr double kMembrane = 1e-3;
  const double edge = mean_edge_near(mesh_in, polygon);
  // The band leaves data to hold the colors: it is at most a third of the image's smaller side
  // wide, and inside a closed curve at most a third of the curve's extent, so that a core of what
  // the curve bounds keeps its colors (outside, the ramp takes the width it needs). Unbounded,
  // deleting the outline of examples/01-disk, a jump of 200 on a coarse 96-pixel image, made the
  // band the whole image, and the membrane alone set every color: the picture went flat.
  const double image_cap = std::min(width, height) / 3.0;
  double inside_cap = image_cap;
  if (gone.closed()) {
    double x0 = polygon[0].x, x1 = x0, y0 = polygon[0].y, y1 = y0;
    for (const Vec2& p : polygon) x0 = std::min(x0, p.x), x1 = std::max(x1, p.x), y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
    inside_cap = std::max(2.0, std::max(x1 - x0, y1 - y0) / 3);
  }
  auto band_for = [&](double j, double widen) {
    return std::max(2.0, std::min(image_cap, widen * std::max(kBandEdges * edge, j / (2 * kRampSlope))));
  };
  // The pixels within the band of the curve as it was drawn (its limit, 8 samples a span, each
  // with the jump interpolated between the span's vertices).
  const bool closed = gone.closed();
  if (closed) polygon.pop_back(), jump.pop_back();
  constexpr int kPerSpan = 8;
  const std::vector<Vec2> curve = sample_bspline(polygon, closed, kPerSpan);
  const size_t n = polygon.size();
  const size_t spans = (curve.size() - 1 + kPerSpan - 1) / kPerSpan;
  // Where the ramp still climbs more than kMaxStep levels a pixel across the curve (the band
  // pinched by a tear that stays, a curve's end), that span's band widens and the colors are
  // refitted: at most kWidenings times, by kWiden each time.
  constexpr int kMaxStep = 4;
  constexpr int kWidenings = 3;
  constexpr double kWiden = 1.3;
  std::vector<double> widen(spans, 1.0);
  const std::vector<std::array<float, 3>> targets =
      surface_at_pixels(mesh_in, before, width, height, default_fit_depth(mesh_in));
  const std::vector<Color> merged = mesh.colors;
  // One system for every refit and check: the positions and the topology stay.
  fit_detail::FitSystem system(mesh, topology, width, height, default_fit_depth(mesh));
  fit_detail::locate_pixels(system);
  const std::vector<uint8_t> by_sharp = near_sharp_pixels(system, width, height);
  std::vector<uint8_t> seeds(mesh.num_vertices(), 0);
  for (const int v : gone.vertices) seeds[v] = 1;
  for (int attempt = 0;; ++attempt) {
    double widest = 0;
    for (size_t i = 0; i + 1 < curve.size(); ++i) {
      const size_t span = i / kPerSpan;
      widest = std::max(widest, band_for(std::max(jump[span % n], jump[(span + 1) % n]), widen[span]));
    }
    const int rings = std::min(16, 2 + static_cast<int>(std::ceil(widest / std::max(edge, 1.0))));
    const std::vector<uint8_t> free_vertex = grow(topology, seeds, rings);
    std::vector<uint8_t> band(size_t(width) * height, 0);
    for (size_t i = 0; i + 1 < curve.size(); ++i) {
      const size_t span = i / kPerSpan;
      const double t = double(i % kPerSpan) / kPerSpan;
      const double j = (1 - t) * jump[span % n] + t * jump[(span + 1) % n];
      const double w = band_for(j, widen[span]);
      detail::for_pixels_near_segment(curve[i].x, curve[i].y, curve[i + 1].x, curve[i + 1].y, w, width, height,
                                      [&](int x, int y) {
                                        const size_t k = size_t(y) * width + x;
                                        if (band[k]) return;
                                        if (closed && w > inside_cap) {
                                          const Vec2 c{x + 0.5, y + 0.5};
                                          if (detail::inside_polygon(curve, c.x, c.y) &&
                                              detail::segment_distance(c, curve[i], curve[i + 1]) > inside_cap)
                                            return;
                                        }
                                        band[k] = 1;
                                      });
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
    mesh.colors = merged;
    result.colors_refit = refit_colors(mesh, system, width, height, free_vertex, targets, band, band_faces, kMembrane);
    if (attempt == kWidenings) break;
    const std::vector<uint8_t> steep = steep_spans(mesh, system, width, height, curve, kPerSpan, band_faces, by_sharp, kMaxStep);
    if (std::find(steep.begin(), steep.end(), 1) == steep.end()) break;
    for (size_t span = 0; span < spans; ++span)
      if (steep[span]) widen[span] *= kWiden;
  }
  validate_level(mesh, width, height);
  mesh_in = std::move(mesh);
  return result;
}

}  // namespace

FeatureEditResult delete_feature(ControlMesh& mesh, int width, int height, int feature) {
  const MeshTopology before = validate_level(mesh, width, height);
  if (feature < 0 || feature >= static_cast<int>(mesh.features.size())) {
    invalid("feature " + std::to_string(feature) + " is out of range (the level has " +
            std::to_string(mesh.features.size()) + " features)");
  }
  const Feature gone = mesh.features[feature];
  return delete_chain(mesh, width, height, before, feature, gone, false);
}

FeatureEditResult delete_crease(ControlMesh& mesh, int width, int height, const Feature& chain) {
  const MeshTopology before = validate_level(mesh, width, height);
  std::set<uint64_t> creases;
  for (const EdgeVerts& e : mesh.creases) creases.insert(undirected(e[0], e[1]));
  for (size_t i = 0; i + 1 < chain.vertices.size(); ++i) {
    const int32_t a = chain.vertices[i], b = chain.vertices[i + 1];
    if (a < 0 || b < 0 || a >= mesh.num_vertices() || b >= mesh.num_vertices() || !creases.count(undirected(a, b))) {
      invalid("the chain's edge " + std::to_string(i) + " is not a crease of the level");
    }
  }
  if (chain.vertices.size() < 2) invalid("the chain has fewer than 2 vertices");
  return delete_chain(mesh, width, height, before, -1, chain, true);
}

}  // namespace subvec
