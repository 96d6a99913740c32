// Data-dependent refinement of the simplified mesh: edge flips and vertex moves (refine.h).
//
// Both work on one measure, the squared error of a triangle's linear color interpolation over the
// pixel centres inside it (a centre on an edge counts in both triangles; every comparison counts
// it the same way before and after, so the total over all faces falls with every accepted step),
// summed from the moments of the triangle's pixels (pixel_moments_p.h).
//
// A flip pass evaluates every candidate edge against the pass's starting mesh (in parallel: the
// evaluations only read), then applies the flips in order of gain, skipping any whose triangles an
// earlier flip of the pass replaced. Vertex moves run one color class of the vertex graph at a
// time: vertices of one class share no edge, so no move changes another's one-ring, and the class
// can move in parallel with the same outcome as in any order.
#include "subvec/vectorize/refine.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <unordered_set>

#include <Eigen/Dense>

#include "core/cancel_p.h"
#include "core/messages_p.h"
#include "core/parallel_p.h"
#include "mesh/collapse_p.h"
#include "vectorize/pixel_moments_p.h"
#include "subvec/core/error.h"
#include "subvec/mesh/topology.h"

namespace subvec {
namespace {

using detail::signed_area;

// The interpolation error of one triangle with corner colors c0, c1, c2 over the pixel centres
// inside it (pixel_moments_p.h); a negative value when it is thinner than `min_area`.
double triangle_error(const Image8& image, Vec2 p0, Vec2 p1, Vec2 p2, Color c0, Color c1, Color c2,
                      double min_area) {
  detail::PixelMoments m;
  if (!detail::pixel_moments(image, p0, p1, p2, p0, min_area, m)) return -1;
  if (m.n == 0) return 0;
  // The interpolated color is affine: c0 + (c1 - c0) w1 + (c2 - c0) w2; the error is
  // Σ f² - 2 Σ f t + Σ t² per channel, and no less than zero whatever the rounding.
  const auto w = detail::barycentric(p0, p1, p2, p0);
  const std::array<double, 3> k0{c0.r, c0.g, c0.b}, k1{c1.r, c1.g, c1.b}, k2{c2.r, c2.g, c2.b};
  double sum = m.tt;
  for (int ch = 0; ch < 3; ++ch) {
    const detail::Affine f = detail::Affine{k0[ch], 0, 0} + w[1] * (k1[ch] - k0[ch]) + w[2] * (k2[ch] - k0[ch]);
    sum += m.sum(f, f) - 2 * m.sum_t(f, ch);
  }
  return std::max(0.0, sum);
}

// 4 sqrt(3) area / (sum of squared edge lengths): 1 for an equilateral triangle, 0 for a flat one.
double shape_quality(Vec2 p, Vec2 q, Vec2 r) {
  const double sum = (q.x - p.x) * (q.x - p.x) + (q.y - p.y) * (q.y - p.y) + (r.x - q.x) * (r.x - q.x) +
                     (r.y - q.y) * (r.y - q.y) + (p.x - r.x) * (p.x - r.x) + (p.y - r.y) * (p.y - r.y);
  return sum > 0 ? 4 * std::sqrt(3.0) * std::abs(signed_area(p, q, r)) / sum : 0;
}

int corner_of(const Tri& t, int32_t v) { return t[0] == v ? 0 : t[1] == v ? 1 : 2; }

Color corner_color(const ControlMesh& mesh, int f, int32_t v) {
  return mesh.colors[mesh.triangle_colors[f][corner_of(mesh.triangles[f], v)]];
}

int32_t opposite(const Tri& t, int32_t a, int32_t b) {
  for (int32_t v : t)
    if (v != a && v != b) return v;
  return -1;
}

// Runs job(i) for i in [0, count) in chunks over the worker threads.
template <class Job>
void parallel_range(int count, int threads, const Job& job) {
  const int chunks = std::min(count, 16 * threads);
  detail::parallel_for(chunks, threads, [&](int chunk) {
    const int end = static_cast<int>(int64_t(count) * (chunk + 1) / chunks);
    for (int i = static_cast<int>(int64_t(count) * chunk / chunks); i < end; ++i) job(i);
  });
}

double face_error(const ControlMesh& mesh, const Image8& image, int f) {
  const Tri& t = mesh.triangles[f];
  const auto& p = mesh.positions;
  return std::max(0.0, triangle_error(image, p[t[0]], p[t[1]], p[t[2]], corner_color(mesh, f, t[0]),
                                      corner_color(mesh, f, t[1]), corner_color(mesh, f, t[2]), 0));
}

// What a refinement carries from step to step, so that each step looks only at what changed:
// every face's error; which faces changed since the flip candidates were last evaluated (a
// candidate depends only on its edge's two faces, so an edge between unchanged faces has none);
// when each face last changed and when each vertex's move was last refused (the step depends
// only on the vertex's one-ring, so a ring that has not changed since refuses it again). Skipping
// those evaluations gives the same mesh as doing them.
struct Tracker {
  std::vector<double> error;        // per face
  std::vector<char> flip_dirty;     // per face
  std::vector<int64_t> changed_at;  // per face: the epoch of its last change
  std::vector<int64_t> refused_at;  // per vertex: the epoch of its last refused move, or -1
  int64_t epoch = 1;

  Tracker(const ControlMesh& mesh, const Image8& image, int threads)
      : error(mesh.num_triangles()), flip_dirty(mesh.num_triangles(), 1), changed_at(mesh.num_triangles(), 0),
        refused_at(mesh.num_vertices(), -1) {
    std::vector<int> all(mesh.num_triangles());
    for (int f = 0; f < mesh.num_triangles(); ++f) all[f] = f;
    update(mesh, image, all, threads);
  }
  // Faces `changed` have new corners, positions or colors.
  void update(const ControlMesh& mesh, const Image8& image, const std::vector<int>& changed, int threads) {
    std::vector<double> errors(changed.size());
    parallel_range(static_cast<int>(changed.size()), threads,
                   [&](int i) { errors[i] = face_error(mesh, image, changed[i]); });
    for (size_t i = 0; i < changed.size(); ++i) set(changed[i], errors[i]);
  }
  // Face f changed and has this error.
  void set(int f, double face_error) { error[f] = face_error, flip_dirty[f] = 1, changed_at[f] = epoch; }
  double total() const {
    double sum = 0;
    for (double e : error) sum += e;
    return sum;
  }
};

// One flip pass; returns the number of flips.
int flip_pass(ControlMesh& mesh, const Image8& image, const RefineOptions& options, Tracker& track, int threads) {
  const MeshTopology topo = MeshTopology::build(mesh, image.width, image.height);
  const auto& pos = mesh.positions;
  struct Candidate {
    int32_t edge = -1;
    double gain = 0;
  };
  std::vector<Candidate> found(topo.num_edges());
  parallel_range(topo.num_edges(), threads, [&](int e) {
    if (topo.edge_tags[e] != EdgeTag::kSmooth) return;
    const int f0 = topo.edge_faces[e][0], f1 = topo.edge_faces[e][1];
    if (f1 < 0 || !(track.flip_dirty[f0] || track.flip_dirty[f1])) return;
    const int32_t a = topo.edges[e][0], b = topo.edges[e][1];
    const int32_t c = opposite(mesh.triangles[f0], a, b), d = opposite(mesh.triangles[f1], a, b);
    if (c == d || topo.find_edge(c, d) >= 0) return;
    // The quadrilateral a c b d must be strictly convex: a and b on either side of c d (c and d
    // are on either side of a b already, the two faces being positive).
    const double s0 = signed_area(pos[c], pos[d], pos[a]), s1 = signed_area(pos[c], pos[d], pos[b]);
    if ((s0 > 0) == (s1 > 0)) return;
    // No new sliver: both new triangles keep min_quality, or the pair's worst quality.
    const double old_quality = std::min(shape_quality(pos[a], pos[b], pos[c]), shape_quality(pos[a], pos[b], pos[d]));
    const double new_quality = std::min(shape_quality(pos[c], pos[d], pos[a]), shape_quality(pos[c], pos[d], pos[b]));
    if (new_quality < std::min(old_quality, options.min_quality)) return;
    const Color ca = corner_color(mesh, f0, a), cb = corner_color(mesh, f0, b);
    const Color cc = corner_color(mesh, f0, c), cd = corner_color(mesh, f1, d);
    const double e0 = triangle_error(image, pos[c], pos[d], pos[a], cc, cd, ca, options.min_area);
    const double e1 = triangle_error(image, pos[c], pos[d], pos[b], cc, cd, cb, options.min_area);
    if (e0 < 0 || e1 < 0) return;
    const double before = track.error[f0] + track.error[f1], after = e0 + e1;
    if (after < (1 - options.min_gain) * before) found[e] = {e, before - after};
  });
  std::vector<Candidate> order;
  for (const Candidate& k : found)
    if (k.edge >= 0) order.push_back(k);
  std::sort(order.begin(), order.end(), [](const Candidate& x, const Candidate& y) {
    return x.gain != y.gain ? x.gain > y.gain : x.edge < y.edge;
  });
  // Every edge has been evaluated against the faces as they are; a candidate not applied below
  // lost to a flip that replaced one of its faces, which makes that face dirty again.
  std::fill(track.flip_dirty.begin(), track.flip_dirty.end(), 0);
  std::vector<char> replaced(mesh.num_triangles(), 0);
  std::vector<int> changed;
  std::unordered_set<int64_t> created;  // (min << 32) | max of the edges this pass made
  for (const Candidate& k : order) {
    const int f0 = topo.edge_faces[k.edge][0], f1 = topo.edge_faces[k.edge][1];
    if (replaced[f0] || replaced[f1]) continue;
    const int32_t a = topo.edges[k.edge][0], b = topo.edges[k.edge][1];
    const int32_t c = opposite(mesh.triangles[f0], a, b), d = opposite(mesh.triangles[f1], a, b);
    // In a valid planar mesh no two quadrilaterals share a diagonal; checked all the same.
    if (!created.insert(int64_t(std::min(c, d)) << 32 | std::max(c, d)).second) {
      track.flip_dirty[f0] = track.flip_dirty[f1] = 1;  // evaluated again next pass
      continue;
    }
    const Tri& t0 = mesh.triangles[f0];
    const Tri& k0 = mesh.triangle_colors[f0];
    const int32_t ka = k0[corner_of(t0, a)], kb = k0[corner_of(t0, b)], kc = k0[corner_of(t0, c)];
    const int32_t kd = mesh.triangle_colors[f1][corner_of(mesh.triangles[f1], d)];
    // The new faces (c, d, a) and (d, c, b), each turned to positive area like every face.
    Tri n0{c, d, a}, m0{kc, kd, ka}, n1{d, c, b}, m1{kd, kc, kb};
    if (signed_area(pos[c], pos[d], pos[a]) < 0) std::swap(n0[0], n0[1]), std::swap(m0[0], m0[1]);
    if (signed_area(pos[d], pos[c], pos[b]) < 0) std::swap(n1[0], n1[1]), std::swap(m1[0], m1[1]);
    mesh.triangles[f0] = n0, mesh.triangle_colors[f0] = m0;
    mesh.triangles[f1] = n1, mesh.triangle_colors[f1] = m1;
    replaced[f0] = replaced[f1] = 1;
    changed.push_back(f0), changed.push_back(f1);
  }
  track.update(mesh, image, changed, threads);
  ++track.epoch;
  return static_cast<int>(changed.size() / 2);
}

int flip_passes(ControlMesh& mesh, const Image8& image, const RefineOptions& options, Tracker& track, int threads) {
  int flips = 0;
  for (int pass = 0; pass < options.flip_passes; ++pass) {
    detail::check_cancel(options.cancel);
    const int n = flip_pass(mesh, image, options, track, threads);
    flips += n;
    if (n == 0) break;
  }
  return flips;
}

// Greedy coloring of the vertices in index order: no two vertices of one class share an edge.
// Returns the classes.
std::vector<std::vector<int32_t>> vertex_classes(const ControlMesh& mesh, const MeshTopology& topo) {
  const int nv = mesh.num_vertices();
  std::vector<int32_t> offsets(nv + 1, 0), neighbors(2 * topo.edges.size());
  for (const EdgeVerts& e : topo.edges) ++offsets[e[0] + 1], ++offsets[e[1] + 1];
  for (int v = 0; v < nv; ++v) offsets[v + 1] += offsets[v];
  std::vector<int32_t> fill(offsets.begin(), offsets.end() - 1);
  for (const EdgeVerts& e : topo.edges) neighbors[fill[e[0]]++] = e[1], neighbors[fill[e[1]]++] = e[0];
  std::vector<int32_t> color(nv, -1);
  std::vector<std::vector<int32_t>> classes;
  std::vector<char> used;
  for (int v = 0; v < nv; ++v) {
    used.assign(classes.size() + 1, 0);
    for (int i = offsets[v]; i < offsets[v + 1]; ++i)
      if (color[neighbors[i]] >= 0) used[color[neighbors[i]]] = 1;
    const int c = static_cast<int>(std::find(used.begin(), used.end(), 0) - used.begin());
    if (c == static_cast<int>(classes.size())) classes.emplace_back();
    color[v] = c;
    classes[c].push_back(v);
  }
  return classes;
}

// How vertex v may move: both coordinates (smooth), along the image border (a border vertex
// that is no corner), or not at all (tears, creases, corners: their colors still adapt).
struct Freedom {
  bool x = false, y = false;
};
Freedom freedom_of(const ControlMesh& mesh, const MeshTopology& topo, const Image8& image, int32_t v) {
  switch (topo.vertex_tags[v]) {
    case VertexTag::kSmooth:
      return {true, true};
    case VertexTag::kCrease: {
      const Vec2 p = mesh.positions[v];
      if (p.x == 0 || p.x == image.width) return {false, true};
      if (p.y == 0 || p.y == image.height) return {true, false};
      return {};
    }
    default:
      return {};
  }
}

// One Gauss-Newton step for vertex v on its free coordinates and the colors of its corners (one
// per side of a tear), kept only when the one-ring's error, `before` now, falls; returns whether it
// was kept, and then the new error of each face of the ring (in topo.faces_of(v) order, measured
// as face_error() measures it) in `face_errors`.
bool move_vertex(ControlMesh& mesh, const MeshTopology& topo, const Image8& image, int32_t v, double before,
                 const RefineOptions& options, std::vector<double>& face_errors) {
  constexpr int kMaxSides = 4;
  // The one-ring as (p1, p2) with v first in each face's order, those corners' colors, which of
  // v's color values (sides) the face uses, and v's corner in the face.
  struct Wedge {
    Vec2 p1, p2;
    Color c1, c2;
    int side, corner;
  };
  std::vector<Wedge> ring;
  std::array<int32_t, kMaxSides> side_color{};
  int sides = 0;
  for (auto [it, end] = topo.faces_of(v); it != end; ++it) {
    const Tri& t = mesh.triangles[*it];
    const Tri& k = mesh.triangle_colors[*it];
    const int i = corner_of(t, v), i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    int side = static_cast<int>(std::find(side_color.begin(), side_color.begin() + sides, k[i]) - side_color.begin());
    if (side == sides) {
      if (sides == kMaxSides) return false;
      side_color[sides++] = k[i];
    }
    ring.push_back({mesh.positions[t[i1]], mesh.positions[t[i2]], mesh.colors[k[i1]], mesh.colors[k[i2]], side, i});
  }
  const Freedom free = freedom_of(mesh, topo, image, v);
  const Vec2 x = mesh.positions[v];
  std::array<Color, kMaxSides> color{};
  for (int k = 0; k < sides; ++k) color[k] = mesh.colors[side_color[k]];
  // The ring's worst shape quality with v at x; a move may not take it under min_move_quality
  // unless it already was.
  auto ring_quality = [&](Vec2 at) {
    double worst = 1;
    for (const Wedge& w : ring) worst = std::min(worst, shape_quality(at, w.p1, w.p2));
    return worst;
  };
  const double quality_floor =
      options.min_move_quality > 0 ? std::min(ring_quality(mesh.positions[v]), options.min_move_quality) : 0;
  // The ring's error with v at x and colors c; negative when a face gets too thin.
  face_errors.resize(ring.size());
  auto ring_error = [&](Vec2 at, const std::array<Color, kMaxSides>& c) {
    if (quality_floor > 0 && !(at == mesh.positions[v]) && ring_quality(at) < quality_floor) return -1.0;
    double sum = 0;
    for (size_t j = 0; j < ring.size(); ++j) {
      const Wedge& w = ring[j];
      // Positive like every face (the error alone would accept a face turned over).
      if (!(signed_area(at, w.p1, w.p2) > options.min_area)) return -1.0;
      // In the face's own corner order, so that a pixel centre on an edge counts as face_error()
      // counts it.
      const int i = w.corner, i1 = (i + 1) % 3, i2 = (i + 2) % 3;
      std::array<Vec2, 3> p;
      std::array<Color, 3> k;
      p[i] = at, p[i1] = w.p1, p[i2] = w.p2;
      k[i] = c[w.side], k[i1] = w.c1, k[i2] = w.c2;
      const double e = triangle_error(image, p[0], p[1], p[2], k[0], k[1], k[2], options.min_area);
      if (e < 0) return -1.0;
      face_errors[j] = e;
      sum += e;
    }
    return sum;
  };
  // Residuals f - I per pixel and channel, where f = (c a0 + c1 a1(x) + c2 a2(x)) / A(x) with
  // a0 = area(s, p1, p2), a1 = area(x, s, p2), a2 = area(x, p1, s), A = area(x, p1, p2). The
  // gradient of area(x, q, r) in x is (q.y - r.y, r.x - q.x) / 2. Unknowns: x, y, then r, g, b of
  // each side.
  const int n = 2 + 3 * sides;
  Eigen::MatrixXd jtj = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd jtr = Eigen::VectorXd::Zero(n);
  for (const Wedge& w : ring) {
    const Vec2 p1 = w.p1, p2 = w.p2;
    // Every term below is affine in the pixel centre s (about x) or the pixel's color times one,
    // so the wedge's sums come from its pixels' moments.
    detail::PixelMoments m;
    detail::pixel_moments(image, x, p1, p2, x, 0, m);
    if (m.n == 0) continue;
    const double inv = 1 / signed_area(x, p1, p2);
    const double ax = 0.5 * (p1.y - p2.y), ay = 0.5 * (p2.x - p1.x);
    const auto [w0, w1, w2] = detail::barycentric(x, p1, p2, x);
    // The gradients of a1 = area(x, s, p2) and a2 = area(x, p1, s) in x.
    const detail::Affine g1x{0.5 * (x.y - p2.y), 0, 0.5}, g1y{0.5 * (p2.x - x.x), -0.5, 0};
    const detail::Affine g2x{0.5 * (p1.y - x.y), 0, -0.5}, g2y{0.5 * (x.x - p1.x), 0.5, 0};
    const double cv[3] = {color[w.side].r, color[w.side].g, color[w.side].b};
    const double c1[3] = {w.c1.r, w.c1.g, w.c1.b}, c2[3] = {w.c2.r, w.c2.g, w.c2.b};
    const int col = 2 + 3 * w.side;
    const double ww = m.sum(w0, w0);
    for (int ch = 0; ch < 3; ++ch) {
      // Jacobian row (jx, jy, and w0 in this side's and channel's color column); residual f - t.
      const detail::Affine f = w0 * cv[ch] + w1 * c1[ch] + w2 * c2[ch];
      const detail::Affine jx = (g1x * c1[ch] + g2x * c2[ch] - f * ax) * inv;
      const detail::Affine jy = (g1y * c1[ch] + g2y * c2[ch] - f * ay) * inv;
      jtj(0, 0) += m.sum(jx, jx), jtj(0, 1) += m.sum(jx, jy), jtj(1, 1) += m.sum(jy, jy);
      jtr(0) += m.sum(jx, f) - m.sum_t(jx, ch), jtr(1) += m.sum(jy, f) - m.sum_t(jy, ch);
      jtj(0, col + ch) += m.sum(jx, w0), jtj(1, col + ch) += m.sum(jy, w0), jtj(col + ch, col + ch) += ww;
      jtr(col + ch) += m.sum(w0, f) - m.sum_t(w0, ch);
    }
  }
  if (!(before > 0)) return false;
  jtj.triangularView<Eigen::StrictlyLower>() = jtj.transpose().triangularView<Eigen::StrictlyLower>();
  // A fixed coordinate: its row and column say "no step".
  for (int axis = 0; axis < 2; ++axis) {
    if (axis == 0 ? free.x : free.y) continue;
    jtj.row(axis).setZero(), jtj.col(axis).setZero(), jtj(axis, axis) = 1, jtr(axis) = 0;
  }
  // Levenberg-Marquardt damping, scale-free, and a floor for a color no pixel sees.
  jtj.diagonal() = jtj.diagonal() * 1.001 + Eigen::VectorXd::Constant(n, 1e-9);
  Eigen::VectorXd step = -jtj.ldlt().solve(jtr);
  if (!step.allFinite()) return false;
  const double length = std::hypot(step(0), step(1));
  if (length > options.max_step) step.head<2>() *= options.max_step / length;
  // Tried over-relaxed first (the sweeps converge faster), then halved until the error falls.
  step *= options.over_relaxation;
  for (int halving = 0; halving < 4; ++halving, step *= 0.5) {
    Vec2 at{x.x + step(0), x.y + step(1)};
    if (!free.x) at.x = x.x;
    if (!free.y) at.y = x.y;
    std::array<Color, kMaxSides> c = color;
    for (int k = 0; k < sides; ++k) {
      c[k] = {static_cast<float>(color[k].r + step(2 + 3 * k)), static_cast<float>(color[k].g + step(3 + 3 * k)),
              static_cast<float>(color[k].b + step(4 + 3 * k))};
    }
    const double after = ring_error(at, c);
    if (after >= 0 && after < before) {
      mesh.positions[v] = at;
      for (int k = 0; k < sides; ++k) mesh.colors[side_color[k]] = c[k];
      return true;
    }
  }
  return false;
}

int move_vertices(ControlMesh& mesh, const Image8& image, const RefineOptions& options, Tracker& track,
                  int threads) {
  const MeshTopology topo = MeshTopology::build(mesh, image.width, image.height);
  int moves = 0;
  for (const std::vector<int32_t>& members : vertex_classes(mesh, topo)) {
    detail::check_cancel(options.cancel);
    // 0: not tried (its ring is as it was when its move was last refused), 1: refused, 2: moved;
    // and a moved vertex's ring errors.
    std::vector<char> outcome(members.size(), 0);
    std::vector<std::vector<double>> ring_errors(members.size());
    parallel_range(static_cast<int>(members.size()), threads, [&](int i) {
      const int32_t v = members[i];
      bool ring_changed = track.refused_at[v] < 0;
      double before = 0;
      for (auto [it, end] = topo.faces_of(v); it != end; ++it) {
        ring_changed |= track.changed_at[*it] > track.refused_at[v];
        before += track.error[*it];
      }
      if (ring_changed) outcome[i] = move_vertex(mesh, topo, image, v, before, options, ring_errors[i]) ? 2 : 1;
    });
    for (size_t i = 0; i < members.size(); ++i) {
      if (outcome[i] == 1) track.refused_at[members[i]] = track.epoch;
      if (outcome[i] != 2) continue;
      ++moves;
      int k = 0;
      for (auto [it, end] = topo.faces_of(members[i]); it != end; ++it) track.set(*it, ring_errors[i][k++]);
    }
    ++track.epoch;
  }
  return moves;
}

}  // namespace

void validate(const RefineOptions& r, const std::string& prefix) {
  using detail::check_in;
  check_in(prefix + "rounds", r.rounds, 0, 50);
  check_in(prefix + "flip_passes", r.flip_passes, 0, 100);
  if (!(r.min_gain >= 0 && r.min_gain < 1)) detail::out_of_range(prefix + "min_gain", "in [0, 1)", r.min_gain);
  check_in(prefix + "min_area", r.min_area, 0, 1e6);
  check_in(prefix + "min_quality", r.min_quality, 0, 1);
  check_in(prefix + "min_move_quality", r.min_move_quality, 0, 1);
  detail::check_positive(prefix + "max_step", r.max_step);
  check_in(prefix + "over_relaxation", r.over_relaxation, 1, 2);
}

RefineStats refine_mesh(ControlMesh& mesh, const Image8& image, const RefineOptions& options) {
  validate(options);
  RefineStats stats;
  if (options.rounds == 0) return stats;
  const int threads = detail::resolve_threads(options.threads);
  Tracker track(mesh, image, threads);
  stats.error_before = track.total();
  stats.flips += flip_passes(mesh, image, options, track, threads);
  for (int round = 0; round < options.rounds; ++round) {
    stats.moves += move_vertices(mesh, image, options, track, threads);
    stats.flips += flip_passes(mesh, image, options, track, threads);
  }
  stats.error_after = track.total();
  return stats;
}

}  // namespace subvec
