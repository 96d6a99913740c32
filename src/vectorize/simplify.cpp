// Constrained 5D QEM simplification with feature refitting (paper §4).
//
// Design note. The mesh is index-based: positions, triangles, per-corner color indices, and a
// per-vertex list of incident faces that collapses keep current. Quadrics live on color indices,
// not vertices: a vertex on a tear has one color per side, so each side accumulates its own 5D
// quadric and a collapse along a tear merges the quadrics side by side. Colors are eliminated from
// every quadric in closed form (Schur complement), leaving a 2D quadric in the position, so the
// cost of a placement is cheap to evaluate and the best point on the edge has a closed form.
//
// Constraints (paper §4, and the model's invariants): corners never move; a border vertex
// collapses only into a neighbour along the same border side; a tear vertex only into its
// neighbour along the same feature, after which the feature's nearby control vertices are refitted
// by least squares to the detected polyline (eq. 1) and the collapse is rolled back if the limit
// curve (a uniform cubic B-spline of the chain, corners interpolated) leaves it by more than
// max_feature_error. No collapse may break the link condition or flip or flatten a triangle.
//
// Speed. Collapses are cheapest first from a lazy queue whose front alone is a heap (binned by
// cost, mesh/collapse_engine_p.h). Faces and color values are renumbered in vertex order for locality.
// Most collapses run in parallel: the image is cut into 2 x 2 regions with frozen seams, each
// simplified on its own (a Worker per region, writing only what it owns) down to the target plus its
// frozen vertices, then one global pass finishes. The region phase is exactly one global pass with
// the seams frozen (see run(); tests/unit/vectorize/simplify_test.cpp compares the two bit for
// bit); the final mesh is close to, not the same as, one global pass from the start. The output
// does not depend on the thread count.
//
// The 5D quadric, the collapse of faces and colors, the queue and the incidence lists are the
// levels' too (mesh/quadric_p.h, mesh/collapse_p.h, mesh/collapse_engine_p.h), and so is the greedy
// loop (run_collapses).
#include "subvec/vectorize/simplify.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <memory>
#include <numeric>
#include <span>
#include <string>

#include <Eigen/Dense>

#include "core/cancel_p.h"
#include "core/parallel_p.h"
#include "mesh/chains_p.h"
#include "mesh/collapse_p.h"
#include "mesh/collapse_engine_p.h"
#include "mesh/quadric_p.h"
#include "subvec/core/error.h"
#include "subvec/mesh/topology.h"
#include "vectorize/simplify_p.h"

namespace subvec {
namespace {

using detail::Arena;
using detail::best_color;
using detail::CollapseQueue;
using detail::Entry;
using detail::IncidenceLists;
using detail::Point5;
using detail::Quadric2;
using detail::reduce;
using Quadric = detail::Quadric5;

using Kind = detail::VertexKind;  // kTear: a vertex of a feature chain

// Uniform cubic B-spline basis on a segment, s in [0, 1].
std::array<double, 4> bspline(double s) {
  const double t = 1 - s;
  return {t * t * t / 6, (3 * s * s * s - 6 * s * s + 4) / 6, (-3 * s * s * s + 3 * s * s + 3 * s + 1) / 6,
          s * s * s / 6};
}


class Simplifier {
 public:
  Simplifier(ControlMesh& mesh, int width, int height, const SimplifyOptions& options,
             detail::SimplifySchedule schedule)
      : mesh_(mesh), w_(width), h_(height), options_(options), schedule_(schedule) {}

  SimplifyStats run();

 private:
  struct Plan {
    double cost = std::numeric_limits<double>::infinity();
    int32_t remove = -1, keep = -1;
    Vec2 position;
  };
  // Who simplifies what: one worker per region in the parallel phase, one for the whole mesh
  // after. A worker collapses and moves only vertices it owns and reads its neighbourhood, which
  // nobody else writes meanwhile; it has its own queue, statistics and scratch space.
  static constexpr int32_t kEveryVertex = -1, kUnfrozen = -2;
  struct Worker {
    int32_t region = kEveryVertex;  // a region, every vertex, or every unfrozen vertex
    int64_t alive = 0;    // live vertices of the region
    int64_t stop = 0;     // simplify down to this many
    CollapseQueue queue;
    SimplifyStats stats;
    bool cancelled = false;  // stopped early by options.cancel
    Arena arena;
    detail::VertexMarks marks;  // neighbourhood queries
    std::vector<int32_t> ring, faces;
  };

  void setup();
  void renumber_for_locality(std::vector<int32_t>& face_of, std::vector<int32_t>& color_of);
  void build_incidence(const std::vector<int32_t>& face_of);
  void classify_vertices();
  void initial_quadrics(const std::vector<int32_t>& color_of);
  void split_regions(int num_regions_x, int num_regions_y);
  bool owns(const Worker& w, int32_t v) const {
    if (w.region < 0) return w.region == kEveryVertex || !frozen_[v];
    return region_[v] == w.region && !frozen_[v];
  }
  bool live(const Entry& e) const { return detail::entry_live(e, vertex_alive_, version_); }
  bool owns_window(const Worker& w, int32_t removed_node) const;
  void simplify_with(Worker& w);
  void simplify_regions_serially(std::vector<Worker>& regions);
  Plan plan(int32_t a, int32_t b) const;
  Plan plan_direction(int32_t u, int32_t v) const;
  void push_edges(Worker& w, int32_t v);
  bool try_collapse(Worker& w, const Plan& e);
  void push(Worker& w, const Plan& p);
  void rebuild_queue(Worker& w);
  void neighbours(Worker& w, int32_t v, std::vector<int32_t>& out) const;
  bool image_corner(Vec2 p) const { return (p.x == 0 || p.x == w_) && (p.y == 0 || p.y == h_); }
  bool sharp(int32_t v) const { return kind_[v] == Kind::kTear || kind_[v] == Kind::kCorner; }
  int faces_with_edge(int32_t u, int32_t v, int32_t* out) const;
  void write_back();

  // Feature refit (eq. 1), in three steps: the window of chain nodes it reads and moves, the rows
  // of the least-squares problem, the solve and the largest parametric error.
  static constexpr int kRefitReach = 5;  // nodes on each side of a removal
  struct RefitWindow {
    std::array<int32_t, 2 * kRefitReach + 2> win{};  // nodes w_0..w_K in chain order
    int count = 0, centre = 0;                        // K + 1; the slot after the removal
    bool periodic = false, hard_start = false, hard_end = false;
    std::array<int, 4> free_slots{};                  // slots that move
    int nfree = 0;
    int seg_lo = 0, seg_hi = -1;                      // segments (w_k, w_k+1) checked
    int K() const { return count - 1; }
    int wrap(int k) const { return periodic ? ((k % count) + count) % count : k; }
  };
  struct FitRow {  // a target point, and the limit curve there as (slot, weight) pairs
    std::array<std::pair<int, double>, 6> w;
    int nw = 0;
    Vec2 target;
  };
  bool refit_window(int32_t removed, RefitWindow& out) const;
  void fit_rows(const RefitWindow& win, const detail::Chain& f, std::vector<FitRow>& rows) const;
  double refit(int32_t removed, std::array<std::pair<int32_t, Vec2>, 8>& moved, int& num_moved) const;

  ControlMesh& mesh_;
  int w_, h_;
  SimplifyOptions options_;
  detail::SimplifySchedule schedule_;

  std::vector<Vec2> pos_;
  std::vector<Tri> tri_, tcol_;
  std::vector<int32_t> face_order_;  // input face of each face
  std::vector<uint8_t> face_alive_, vertex_alive_;
  IncidenceLists vfaces_;
  std::vector<Kind> kind_;
  std::vector<uint8_t> sides_;     // bit mask: 1 x=0, 2 y=0, 4 x=W, 8 y=H
  std::vector<int32_t> only_color_;  // the color of a vertex with one color value, else -1
  std::vector<uint32_t> version_;
  std::vector<Quadric> quadric_;   // per color index
  detail::FeatureChains chains_;   // the features, as linked nodes
  std::vector<Arena> arenas_;     // where incidence lists grew
  std::vector<int16_t> region_;   // region of each vertex in the parallel phase
  std::vector<uint8_t> frozen_;   // left alone in the parallel phase (seams, shared closed features)
};

// Stage 3 starts from the dense mesh (paper §4, "Mesh simplification"): its faces and colors in a
// cache-friendly order, the incidence lists, the vertex types, the feature chains, the quadrics.
void Simplifier::setup() {
  pos_ = mesh_.positions;
  std::vector<int32_t> face_of, color_of;
  renumber_for_locality(face_of, color_of);
  build_incidence(face_of);
  classify_vertices();
  chains_.build(mesh_.features, pos_, kind_);  // the refit's targets (eq. 1)
  initial_quadrics(color_of);
}

void Simplifier::renumber_for_locality(std::vector<int32_t>& face_of, std::vector<int32_t>& color_of) {
  const int nv = mesh_.num_vertices(), nf = mesh_.num_triangles();
  // Faces and color values are renumbered to follow the vertex order, which is spatially coherent,
  // so that a vertex's neighbourhood and its quadrics share cache lines: faces by their smallest
  // vertex, color values by their vertex. Everything that depends on an order (incidence lists,
  // quadric sums, the output) still follows the input order.
  // (Stable counting sorts by vertex.)
  auto stable_order = [nv](const std::vector<int32_t>& key) {
    std::vector<int32_t> start(size_t(nv) + 1, 0), order(key.size());
    for (int32_t k : key) ++start[k + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    for (size_t i = 0; i < key.size(); ++i) order[start[key[i]]++] = static_cast<int32_t>(i);
    return order;
  };
  std::vector<int32_t> min_vertex(nf);
  for (int f = 0; f < nf; ++f) min_vertex[f] = std::min({mesh_.triangles[f][0], mesh_.triangles[f][1], mesh_.triangles[f][2]});
  face_order_ = stable_order(min_vertex);
  face_of.assign(nf, 0);
  for (int i = 0; i < nf; ++i) face_of[face_order_[i]] = i;
  std::vector<int32_t> color_vertex(mesh_.num_colors(), 0);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) color_vertex[mesh_.triangle_colors[f][k]] = mesh_.triangles[f][k];
  const std::vector<int32_t> color_order = stable_order(color_vertex);
  color_of.assign(mesh_.num_colors(), 0);
  for (int i = 0; i < mesh_.num_colors(); ++i) color_of[color_order[i]] = i;
  tri_.resize(nf);
  tcol_.resize(nf);
  for (int i = 0; i < nf; ++i) {
    tri_[i] = mesh_.triangles[face_order_[i]];
    for (int k = 0; k < 3; ++k) tcol_[i][k] = color_of[mesh_.triangle_colors[face_order_[i]][k]];
  }
}

// Per vertex: its incident faces (in input face order), a version for the lazy queue, and its
// color when it has only one.
void Simplifier::build_incidence(const std::vector<int32_t>& face_of) {
  const int nv = mesh_.num_vertices(), nf = mesh_.num_triangles();
  face_alive_.assign(nf, 1);
  vertex_alive_.assign(nv, 1);
  {
    std::vector<int32_t> counts(nv, 0);
    for (const Tri& t : mesh_.triangles)
      for (int32_t v : t) ++counts[v];
    vfaces_.reserve(counts);
  }
  Arena& arena = arenas_.emplace_back();  // (unused: the lists have room)
  for (int f = 0; f < nf; ++f)
    for (int v : mesh_.triangles[f]) vfaces_.push_back(v, face_of[f], arena);
  version_.assign(nv, 0);
  only_color_.assign(nv, -1);
  std::vector<uint8_t> seen(nv, 0);
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const int32_t v = tri_[f][k], c = tcol_[f][k];
      if (!seen[v]) only_color_[v] = c, seen[v] = 1;
      else if (only_color_[v] != c) only_color_[v] = -1;
    }
  }

}

void Simplifier::classify_vertices() {
  const int nv = mesh_.num_vertices();
  kind_.resize(nv);
  // Vertex types as in MeshTopology (paper §3.2), counted directly: border edges join two vertices on
  // one side of the image (in a valid mesh no other edge does), creases are listed, tears are the
  // features' edges; feature ends and the image corners are corners.
  sides_.assign(nv, 0);
  for (int v = 0; v < nv; ++v) sides_[v] = detail::image_sides(pos_[v], w_, h_);
  std::vector<uint8_t> creases(nv, 0), tears(nv, 0), corner(nv, 0);
  for (int v = 0; v < nv; ++v) {
    if (!sides_[v]) continue;
    std::array<int32_t, 8> along{};
    int count = 0;
    for (int32_t f : vfaces_[v]) {
      for (int32_t w : tri_[f]) {
        if (w == v || !(sides_[v] & sides_[w]) || std::find(along.begin(), along.begin() + count, w) != along.begin() + count) continue;
        if (count < 8) along[count++] = w;
      }
    }
    creases[v] = static_cast<uint8_t>(count);
    corner[v] = (image_corner(pos_[v]) ? 1 : 0);
  }
  for (const EdgeVerts& e : mesh_.creases)
    for (int32_t v : e) creases[v] = static_cast<uint8_t>(std::min(creases[v] + 1, 255));
  for (const Feature& f : mesh_.features) {
    for (size_t i = 0; i + 1 < f.vertices.size(); ++i)
      for (int32_t v : {f.vertices[i], f.vertices[i + 1]}) tears[v] = static_cast<uint8_t>(std::min(tears[v] + 1, 255));
    if (!f.closed()) corner[f.vertices.front()] = corner[f.vertices.back()] = 1;
  }
  for (int v = 0; v < nv; ++v) {
    if (corner[v]) kind_[v] = Kind::kCorner;
    else if (creases[v] == 0 && tears[v] == 0) kind_[v] = Kind::kSmooth;
    else if (creases[v] == 2 && tears[v] == 0) kind_[v] = sides_[v] ? Kind::kBorder : Kind::kCorner;  // interior creases stay
    else if (tears[v] == 2 && creases[v] == 0) kind_[v] = Kind::kTear;
    else kind_[v] = Kind::kCorner;
  }

}

void Simplifier::initial_quadrics(const std::vector<int32_t>& color_of) {
  // Summed in the input's face order, onto the renumbered color values.
  const double cs = options_.color_scale;
  quadric_ = detail::color_quadrics(mesh_.num_triangles(), mesh_.num_colors(), options_.threads,
                                    [&](int f, int k, Point5& p) {
    const Vec2 x = pos_[mesh_.triangles[f][k]];
    const int32_t c = mesh_.triangle_colors[f][k];
    const Color rgb = mesh_.colors[c];
    p = {x.x, x.y, cs * rgb.r, cs * rgb.g, cs * rgb.b};
    return color_of[c];
  });
}

// The distinct neighbours of v, in no particular order.
void Simplifier::neighbours(Worker& worker, int32_t v, std::vector<int32_t>& out) const {
  out.clear();
  const uint32_t stamp = worker.marks.next_stamp();
  for (int32_t f : vfaces_[v]) {
    for (int32_t w : tri_[f]) {
      if (w == v || worker.marks.mark[w] == stamp) continue;
      worker.marks.mark[w] = stamp;
      out.push_back(w);
    }
  }
}

int Simplifier::faces_with_edge(int32_t u, int32_t v, int32_t* out) const {
  return detail::faces_with_edge(vfaces_[u], tri_, v, out);
}

Simplifier::Plan Simplifier::plan_direction(int32_t u, int32_t v) const {
  Plan p;
  const Kind ku = kind_[u], kv = kind_[v];
  if (ku == Kind::kCorner) return p;
  // A smooth vertex into a vertex with one color: the edge (which exists: u and v are neighbours)
  // merges one pair of quadrics whatever its faces.
  int32_t faces[2];
  std::array<std::array<int32_t, 2>, 2> pairs;
  int npairs = 0;
  if (ku == Kind::kSmooth && only_color_[u] >= 0 && only_color_[v] >= 0) {
    pairs[0] = {only_color_[u], only_color_[v]};
    npairs = 1;
  } else {
    const int nfaces = faces_with_edge(u, v, faces);
    if (nfaces < 1 || nfaces > 2) return p;
    const auto along_chain = [&] {
      const detail::Chain& f = chains_.chains[chains_.chain_of[u]];
      return (kv == Kind::kTear || kv == Kind::kCorner) && chains_.chain_neighbour(u, v) && !(f.closed && f.size <= 4);
    };
    if (!detail::kinds_allow_collapse(ku, kv, nfaces, (sides_[u] & sides_[v]) != 0, along_chain)) return p;

    // The merged quadric, side by side: pairs (color of u, color of v) over the faces on the edge.
    npairs = detail::edge_color_pairs(faces, nfaces, tri_, tcol_, u, v, pairs);
  }
  Quadric2 r;
  for (int i = 0; i < npairs; ++i) {
    Quadric q = quadric_[pairs[i][0]];
    q += quadric_[pairs[i][1]];
    r += reduce(q);
  }
  const Vec2 pu = pos_[u], pv = pos_[v];
  Vec2 best = pv;
  if (ku == Kind::kSmooth && kv == Kind::kSmooth) {
    // Best point on the segment: R(pu + t (pv - pu)) is quadratic in t.
    const double dx = pv.x - pu.x, dy = pv.y - pu.y;
    const double mdx = r.m00 * dx + r.m01 * dy, mdy = r.m01 * dx + r.m11 * dy;
    const double a = dx * mdx + dy * mdy, b = 2 * (pu.x * mdx + pu.y * mdy + r.g0 * dx + r.g1 * dy);
    const double t = a > 1e-12 ? std::clamp(-b / (2 * a), 0.0, 1.0) : 0.5;
    best = {pu.x + t * dx, pu.y + t * dy};
  }
  p.cost = std::max(0.0, r(best.x, best.y));
  p.remove = u, p.keep = v;
  p.position = best;
  return p;
}

Simplifier::Plan Simplifier::plan(int32_t a, int32_t b) const {
  // Between two smooth vertices both directions give the same optimum on the segment.
  if (kind_[a] == Kind::kSmooth && kind_[b] == Kind::kSmooth) return plan_direction(std::max(a, b), std::min(a, b));
  Plan p = plan_direction(a, b), q = plan_direction(b, a);
  return q.cost < p.cost ? q : p;
}

// Plans the edges from v to the neighbours the worker owns (v is one of its own).
void Simplifier::push_edges(Worker& worker, int32_t v) {
  std::vector<int32_t>& ring = worker.ring;
  neighbours(worker, v, ring);
  std::erase_if(ring, [&](int32_t w) { return !owns(worker, w); });
  // Planning is bound by fetching the neighbours' quadrics: request them all first.
  for (int32_t w : ring) {
    const int32_t c = only_color_[w];
    if (c < 0) continue;
    const char* q = reinterpret_cast<const char*>(&quadric_[c]);
    __builtin_prefetch(q), __builtin_prefetch(q + 64), __builtin_prefetch(q + 128);
  }
  for (int32_t w : ring) {
    push(worker, plan(v, w));
  }
}

void Simplifier::push(Worker& worker, const Plan& p) {
  if (p.remove < 0 || !std::isfinite(p.cost)) return;
  worker.queue.push(detail::make_entry(p.cost, p.remove, p.keep, version_[p.remove], version_[p.keep]));
}

// Re-plans every live edge of the worker into a fresh queue, dropping the stale entries that pile up.
void Simplifier::rebuild_queue(Worker& worker) {
  worker.queue.clear();
  std::vector<int32_t>& ring = worker.ring;
  for (int32_t v = 0; v < static_cast<int32_t>(pos_.size()); ++v) {
    if (!vertex_alive_[v] || !owns(worker, v)) continue;
    neighbours(worker, v, ring);
    for (int32_t w : ring)
      if (w > v && owns(worker, w)) push(worker, plan(v, w));
  }
}


// The piece of chain that the refit after removing node `removed` reads and changes, and the
// segments it checks; false when there is nothing to refit or check. The limit curve of a chain is
// the uniform cubic B-spline of its control vertices; at a corner (feature end or junction) it
// ends with the phantom point 2 Q0 - Q1, which is what the crease masks with a fixed corner
// produce. The B-spline is local, so only a window of five nodes on each side of the removal
// matters: up to two free nodes per side, the segments they touch, and fixed context beyond.
// Windows stop early at corners ("hard" ends).
bool Simplifier::refit_window(int32_t removed, RefitWindow& out) const {
  out = RefitWindow{};
  const detail::ChainNode& r = chains_.nodes[removed];
  const detail::Chain& f = chains_.chains[chains_.chain_of[r.vertex]];
  std::array<int32_t, 2 * kRefitReach + 1> back{}, fwd{};
  int nb = 0, nf = 0;
  bool& hard_start = out.hard_start;
  bool& hard_end = out.hard_end;
  for (int32_t n = r.prev;; n = chains_.nodes[n].prev) {
    if (n < 0 || n == removed) { hard_start = true; break; }
    back[nb++] = n;
    if (kind_[chains_.nodes[n].vertex] == Kind::kCorner) { hard_start = true; break; }
    if (nb == kRefitReach) break;
  }
  for (int32_t n = r.next;; n = chains_.nodes[n].next) {
    if (n < 0 || n == removed) { hard_end = true; break; }
    if (nb > 0 && n == back[nb - 1] && !hard_start) break;  // a short loop met itself
    fwd[nf++] = n;
    if (kind_[chains_.nodes[n].vertex] == Kind::kCorner) { hard_end = true; break; }
    if (nf == kRefitReach) break;
  }
  // Window w_0..w_K in chain order; `centre` is the index of the node after the removal.
  auto& win = out.win;
  int& count = out.count;
  for (int i = nb - 1; i >= 0; --i) win[count++] = back[i];
  const int centre = out.centre = count;
  for (int i = 0; i < nf; ++i) win[count++] = fwd[i];
  // A short closed loop: the window wraps onto itself; treat the whole loop as periodic.
  bool& periodic = out.periodic;
  if (f.closed && !hard_start && !hard_end && f.size - 1 <= 2 * kRefitReach) {
    std::vector<int32_t> loop;
    for (int32_t n = r.next; n != removed && static_cast<int>(loop.size()) < f.size; n = chains_.nodes[n].next) loop.push_back(n);
    count = 0;
    for (int32_t n : loop) win[count++] = n;
    periodic = true;
  }
  const int K = count - 1;
  if (K < 1) return false;
  auto slot_ok = [&](int k) { return periodic || (k >= 0 && k <= K); };
  auto wrap = [&](int k) { return out.wrap(k); };
  // Free nodes: tear vertices among the two before and two after the removal.
  auto& free_slots = out.free_slots;
  int& nfree = out.nfree;
  for (int k = periodic ? 0 : centre - 2; k <= (periodic ? K : centre + 1); ++k) {
    if (!slot_ok(k)) continue;
    if (periodic && nfree == 4) break;
    if (kind_[chains_.nodes[win[wrap(k)]].vertex] == Kind::kTear) free_slots[nfree++] = wrap(k);
  }
  // Segments k (between w_k and w_{k+1}) that the removal or a free node can change, and that the
  // window can evaluate (soft ends need one more node of context).
  const int nseg = periodic ? count : K;
  int& seg_lo = out.seg_lo;
  int& seg_hi = out.seg_hi;
  seg_lo = periodic ? 0 : centre - 4, seg_hi = periodic ? nseg - 1 : centre + 2;
  if (!periodic) {
    seg_lo = std::max(seg_lo, hard_start ? 0 : 1);
    seg_hi = std::min(seg_hi, hard_end ? K - 1 : K - 2);
  }
  return seg_lo <= seg_hi;

}

// The rows of eq. 1 over the window's segments: each target point of the detected polyline
// between two nodes, and the limit curve at its parameter as weights on the window's slots.
void Simplifier::fit_rows(const RefitWindow& win, const detail::Chain& f, std::vector<FitRow>& rows) const {
  const int K = win.K(), total = static_cast<int>(f.target.size());
  const bool periodic = win.periodic;
  auto wrap = [&](int k) { return win.wrap(k); };
  rows.clear();
  for (int k = win.seg_lo; k <= win.seg_hi; ++k) {
    const double p0 = chains_.nodes[win.win[wrap(k)]].param;
    double p1 = chains_.nodes[win.win[wrap(k + 1)]].param;
    if (p1 <= p0) p1 += total;  // wraps around a closed target
    const int j_begin = static_cast<int>(std::ceil(p0));
    const int j_end = static_cast<int>(std::floor(p1)) - (k < win.seg_hi && p1 == std::floor(p1) ? 1 : 0);
    for (int j = j_begin; j <= j_end; ++j) {
      const double s = (j - p0) / (p1 - p0);
      const auto b = bspline(s);
      FitRow row;
      row.target = f.target[((j % total) + total) % total];
      auto add = [&](int slot, double weight) {
        for (int i = 0; i < row.nw; ++i) {
          if (row.w[i].first == slot) {
            row.w[i].second += weight;
            return;
          }
        }
        row.w[row.nw++] = {slot, weight};
      };
      for (int i = 0; i < 4; ++i) {
        const int kk = k - 1 + i;
        if (periodic || (kk >= 0 && kk <= K)) {
          add(wrap(kk), b[i]);
        } else if (kk < 0) {  // phantom 2 w0 - w1 at a hard start
          add(0, 2 * b[i]), add(1, -b[i]);
        } else {  // phantom 2 wK - w(K-1) at a hard end
          add(K, 2 * b[i]), add(K - 1, -b[i]);
        }
      }
      rows.push_back(row);
    }
  }
}

// Feature refit after the removal of node `removed` (paper §4, eq. 1): the free nodes of the
// window move to the least-squares fit of the limit curve to the detected polyline. Fills the
// moved vertices and returns the largest parametric error of the affected piece of curve.
double Simplifier::refit(int32_t removed, std::array<std::pair<int32_t, Vec2>, 8>& moved,
                         int& num_moved) const {
  RefitWindow window;
  if (!refit_window(removed, window)) return 0;
  thread_local std::vector<FitRow> rows;
  fit_rows(window, chains_.chains[chains_.chain_of[chains_.nodes[removed].vertex]], rows);
  const auto& win = window.win;
  const int count = window.count, nfree = window.nfree;
  const auto& free_slots = window.free_slots;
  std::array<Vec2, 2 * kRefitReach + 2> q;
  for (int i = 0; i < count; ++i) q[i] = pos_[chains_.nodes[win[i]].vertex];
  if (nfree > 0 && !rows.empty()) {
    // Normal equations of the small least-squares problem (eq. 1), x and y at once, with a light
    // pull toward the current positions for free nodes that no target point constrains.
    Eigen::Matrix4d ata = Eigen::Matrix4d::Zero();
    Eigen::Matrix<double, 4, 2> atb = Eigen::Matrix<double, 4, 2>::Zero();
    for (const FitRow& row : rows) {
      double coef[4] = {0, 0, 0, 0};
      double bx = row.target.x, by = row.target.y;
      for (int i = 0; i < row.nw; ++i) {
        const auto [slot, weight] = row.w[i];
        int fi = -1;
        for (int j = 0; j < nfree; ++j)
          if (free_slots[j] == slot) fi = j;
        if (fi >= 0) {
          coef[fi] += weight;
        } else {
          bx -= weight * q[slot].x, by -= weight * q[slot].y;
        }
      }
      for (int a = 0; a < nfree; ++a) {
        for (int b = 0; b < nfree; ++b) ata(a, b) += coef[a] * coef[b];
        atb(a, 0) += coef[a] * bx, atb(a, 1) += coef[a] * by;
      }
    }
    for (int i = 0; i < 4; ++i) {
      const double reg = i < nfree ? 1e-3 : 1.0;
      ata(i, i) += reg;
      if (i < nfree) atb(i, 0) += reg * q[free_slots[i]].x, atb(i, 1) += reg * q[free_slots[i]].y;
    }
    const Eigen::Matrix<double, 4, 2> x = ata.ldlt().solve(atb);
    for (int i = 0; i < nfree && num_moved < 8; ++i) {
      q[free_slots[i]] = {x(i, 0), x(i, 1)};
      moved[num_moved++] = {chains_.nodes[win[free_slots[i]]].vertex, q[free_slots[i]]};
    }
  }
  double worst = 0;
  for (const FitRow& row : rows) {
    double x = 0, y = 0;
    for (int i = 0; i < row.nw; ++i) x += row.w[i].second * q[row.w[i].first].x, y += row.w[i].second * q[row.w[i].first].y;
    worst = std::max(worst, std::hypot(x - row.target.x, y - row.target.y));
  }
  return worst;
}

bool Simplifier::try_collapse(Worker& worker, const Plan& e) {
  const int32_t u = e.remove, v = e.keep;
  SimplifyStats& stats = worker.stats;
  // A collapse along a feature refits nodes up to five away: they must all be the worker's.
  const int32_t removed_node = kind_[u] == Kind::kTear ? chains_.node_of[u] : -1;
  if (removed_node >= 0 && !owns_window(worker, removed_node)) return false;
  {
    int32_t faces[2];
    const int nfaces = faces_with_edge(u, v, faces);
    if (!detail::link_condition(vfaces_[u], vfaces_[v], tri_, u, v, nfaces, worker.marks)) {
      ++stats.rejected_topology;
      return false;
    }
    // Two tear edges of a dying triangle (u, v, w) would merge into one edge claimed twice.
    const auto sharp_tear_edge = [&](int32_t a, int32_t b) { return sharp(a) && sharp(b) && chains_.tear_edge(a, b); };
    if (detail::folds_sharp_edges(faces, std::min(nfaces, 2), tri_, u, v, sharp_tear_edge)) {
      ++stats.rejected_topology;
      return false;
    }
  }
  std::array<std::pair<int32_t, Vec2>, 8> moved;
  int num_moved = 0;
  moved[num_moved++] = {u, e.position};  // u takes v's place (its faces get v)
  moved[num_moved++] = {v, e.position};

  // A collapse along a feature: the chain loses u, then its neighbourhood is refitted.
  if (removed_node >= 0) {
    const double error = refit(removed_node, moved, num_moved);
    if (error > options_.max_feature_error) {
      ++stats.rejected_feature;
      return false;
    }
    stats.max_feature_error = std::max(stats.max_feature_error, error);
  }

  // No flipped or degenerate triangle among everything that moves.
  constexpr double kMinArea = 1e-4;
  const auto position = [&](int32_t w) {
    Vec2 p = pos_[w];
    for (int i = 0; i < num_moved; ++i)
      if (moved[i].first == w) p = moved[i].second;
    return p;
  };
  for (int i = 0; i < num_moved; ++i) {
    if (!detail::faces_keep_area(vfaces_[moved[i].first], tri_, u, v, position, kMinArea)) {
      ++stats.rejected_topology;
      return false;
    }
  }

  // Apply: quadrics merged side by side, u's faces handed to v with v's colors, chain updated.
  int32_t faces[2];
  const int nfaces = std::min(faces_with_edge(u, v, faces), 2);
  std::array<std::array<int32_t, 2>, 2> pairs;
  const int npairs = detail::edge_color_pairs(faces, nfaces, tri_, tcol_, u, v, pairs);
  detail::merge_side_by_side(quadric_, pairs, npairs);
  detail::collapse_incidence(u, v, pairs, npairs, tri_, tcol_, vfaces_, face_alive_, vertex_alive_, worker.arena,
                             worker.faces);  // v's list may move
  --worker.alive;
  for (int i = 0; i < num_moved; ++i) pos_[moved[i].first] = moved[i].second;
  if (removed_node >= 0) chains_.unlink(u);  // its two chain edges become one
  ++stats.collapses;

  // Costs change around v and every moved vertex.
  ++version_[v];
  push_edges(worker, v);
  for (int i = 2; i < num_moved; ++i) {
    ++version_[moved[i].first];
    push_edges(worker, moved[i].first);
  }
  return true;
}

// Greedy collapses, cheapest first, of the worker's edges until it is down to w.stop vertices.
void Simplifier::simplify_with(Worker& worker) {
  worker.marks.mark.assign(pos_.size(), 0);
  rebuild_queue(worker);
  size_t rebuild_at = 4 * worker.queue.size();
  // A worker that sees the cancel flag stops, and run() throws on the calling thread.
  worker.cancelled = !detail::run_collapses(
      worker.queue, options_.cancel, [&] { return worker.alive > worker.stop; },
      [&](const Entry& e) { return live(e); },
      [&](const Entry& e) {
        const Plan p = plan_direction(e.remove(), e.keep);
        if (p.remove < 0) return;
        try_collapse(worker, p);
        if (worker.queue.size() > rebuild_at) {
          rebuild_queue(worker);
          rebuild_at = std::max<size_t>(4 * worker.queue.size(), 1024);
        }
      });
  worker.marks.mark = {};
}

SimplifyStats Simplifier::run() {
  using detail::SimplifySchedule;
  setup();
  const int64_t target = options_.target_vertices;
  SimplifyStats stats;
  auto merge = [&](const SimplifyStats& s) {
    stats.collapses += s.collapses;
    stats.rejected_topology += s.rejected_topology;
    stats.rejected_feature += s.rejected_feature;
    stats.max_feature_error = std::max(stats.max_feature_error, s.max_feature_error);
  };

  // Parallel phase (deterministic whatever the thread count): the image is cut into a fixed grid of
  // regions, and each region is simplified on its own, its seams frozen, down to `target`
  // vertices plus its frozen ones. The collapses of a region do not depend on the other regions:
  // the phase is one global pass with the seams frozen in which each region stops at its own count
  // (kRegionsSerial; the tests compare the two bit for bit). However the final vertices are shared
  // among regions, none ends with more than `target`, so the phase stops before a global pass
  // would. It is not how one global pass from the start would go, though: that pass also
  // collapses the seams meanwhile, and the costs it changes there change the order farther out.
  // On a synthetic 512 x 512 image, 20 000 vertices down to 600, 63 % of the final vertices more
  // than 48 px from a seam are also in the global pass's mesh (95 % if the seams were not frozen).
  constexpr int kRegionsX = 2, kRegionsY = 2;
  const int64_t nv = static_cast<int64_t>(pos_.size());
  if (schedule_ != SimplifySchedule::kGlobal && nv > 4 * kRegionsX * kRegionsY * target) {
    split_regions(kRegionsX, kRegionsY);
    std::vector<Worker> workers(kRegionsX * kRegionsY);
    for (int64_t v = 0; v < nv; ++v) {
      Worker& w = workers[region_[v]];
      ++w.alive;
      w.stop += frozen_[v];
    }
    for (size_t r = 0; r < workers.size(); ++r) {
      workers[r].region = static_cast<int32_t>(r);
      workers[r].stop += target;
    }
    if (schedule_ == SimplifySchedule::kRegionsSerial) {
      simplify_regions_serially(workers);
    } else {
      detail::parallel_for(static_cast<int>(workers.size()), options_.threads, [&](int r) { simplify_with(workers[r]); });
    }
    for (Worker& w : workers) {
      if (w.cancelled) throw Error(ErrorCode::kCancelled, "cancelled");
      merge(w.stats);
      arenas_.push_back(std::move(w.arena));
    }
  }

  // Then everything, one collapse at a time.
  if (schedule_ == SimplifySchedule::kRegionsThenGlobal || schedule_ == SimplifySchedule::kGlobal) {
    Worker all;
    for (int64_t v = 0; v < nv; ++v) all.alive += vertex_alive_[v];
    all.stop = target;
    simplify_with(all);
    if (all.cancelled) throw Error(ErrorCode::kCancelled, "cancelled");
    merge(all.stats);
  }
  write_back();
  return stats;
}

// The reference for the parallel phase: the same regions' collapses from one queue, cheapest first
// over all of them, on one thread; an entry of a region that is down to its count is dropped.
// Statistics go to the region of each collapse.
void Simplifier::simplify_regions_serially(std::vector<Worker>& regions) {
  Worker all;
  all.region = kUnfrozen;
  all.marks.mark.assign(pos_.size(), 0);
  rebuild_queue(all);
  size_t rebuild_at = 4 * all.queue.size();
  auto open = [&] {
    return std::any_of(regions.begin(), regions.end(), [](const Worker& w) { return w.alive > w.stop; });
  };
  const bool finished = detail::run_collapses(all.queue, options_.cancel, open, [&](const Entry& e) { return live(e); },
                                              [&](const Entry& e) {
    Worker& region = regions[region_[e.remove()]];
    if (region.alive <= region.stop) return;
    const Plan p = plan_direction(e.remove(), e.keep);
    if (p.remove < 0) return;
    all.stats = {};
    if (try_collapse(all, p)) --region.alive;
    region.stats.collapses += all.stats.collapses;
    region.stats.rejected_topology += all.stats.rejected_topology;
    region.stats.rejected_feature += all.stats.rejected_feature;
    region.stats.max_feature_error = std::max(region.stats.max_feature_error, all.stats.max_feature_error);
    if (all.queue.size() > rebuild_at) {
      rebuild_queue(all);
      rebuild_at = std::max<size_t>(4 * all.queue.size(), 1024);
    }
  });
  if (!finished) regions[0].cancelled = true;
  regions[0].arena = std::move(all.arena);
}

// Regions: a grid of nx x ny rectangles of the image by initial position. Frozen: every vertex with
// a neighbour in another region (the seams), and every vertex of a closed feature that is not all
// within one region's unfrozen vertices (its length is shared state).
void Simplifier::split_regions(int nx, int ny) {
  const int32_t nv = static_cast<int32_t>(pos_.size());
  region_.resize(nv);
  for (int32_t v = 0; v < nv; ++v) {
    const int rx = std::clamp(static_cast<int>(pos_[v].x * nx / w_), 0, nx - 1);
    const int ry = std::clamp(static_cast<int>(pos_[v].y * ny / h_), 0, ny - 1);
    region_[v] = static_cast<int16_t>(ry * nx + rx);
  }
  frozen_.assign(nv, 0);
  for (const Tri& t : tri_) {
    if (region_[t[0]] == region_[t[1]] && region_[t[1]] == region_[t[2]]) continue;
    for (int32_t v : t) frozen_[v] = 1;
  }
  for (const detail::Chain& f : chains_.chains) {
    if (!f.closed) continue;
    bool shared = false;
    int32_t n = f.head;
    for (int32_t i = 0; i < f.size; ++i, n = chains_.nodes[n].next) {
      const int32_t v = chains_.nodes[n].vertex;
      shared |= frozen_[v] || region_[v] != region_[chains_.nodes[f.head].vertex];
    }
    if (!shared) continue;
    for (int32_t i = 0; i < f.size; ++i, n = chains_.nodes[n].next) frozen_[chains_.nodes[n].vertex] = 1;
  }
}

// Whether every node that the refit after removing `removed_node` reads or moves is the worker's
// (the same walk as refit(): five nodes each way, stopping at corners).
bool Simplifier::owns_window(const Worker& worker, int32_t removed_node) const {
  if (worker.region == kEveryVertex) return true;
  constexpr int kReach = kRefitReach;
  for (int direction = 0; direction < 2; ++direction) {
    int count = 0;
    for (int32_t n = direction ? chains_.nodes[removed_node].next : chains_.nodes[removed_node].prev; n >= 0 && n != removed_node;
         n = direction ? chains_.nodes[n].next : chains_.nodes[n].prev) {
      if (!owns(worker, chains_.nodes[n].vertex)) return false;
      if (kind_[chains_.nodes[n].vertex] == Kind::kCorner || ++count == kReach) break;
    }
  }
  return true;
}

void Simplifier::write_back() {
  // Faces in the input's order; each color at its quadric's best value where its vertex ended.
  std::vector<int32_t> face_of(tri_.size()), vmap, used;
  for (size_t i = 0; i < tri_.size(); ++i) face_of[face_order_[i]] = static_cast<int32_t>(i);
  const double scale = 1 / options_.color_scale;
  mesh_ = detail::live_mesh(pos_, vertex_alive_, tri_, tcol_, face_alive_, face_of, static_cast<int>(quadric_.size()),
                            mesh_.creases, chains_, [&](int32_t c, int32_t v) {
    const auto rgb = best_color(quadric_[c], pos_[v].x, pos_[v].y);
    return Color{static_cast<float>(rgb[0] * scale), static_cast<float>(rgb[1] * scale),
                 static_cast<float>(rgb[2] * scale)};
  }, vmap, used);
}

}  // namespace

SimplifyStats simplify(ControlMesh& mesh, int width, int height, const SimplifyOptions& options) {
  return detail::simplify_scheduled(mesh, width, height, options, detail::SimplifySchedule::kRegionsThenGlobal);
}

SimplifyStats detail::simplify_scheduled(ControlMesh& mesh, int width, int height, const SimplifyOptions& options,
                                         SimplifySchedule schedule) {
  if (options.target_vertices < 4) {
    throw Error(ErrorCode::kInvalidArgument, "simplify: target of " + std::to_string(options.target_vertices) +
                                                 " vertices is below the 4 image corners");
  }
  if (!(options.max_feature_error > 0) || !(options.color_scale > 0)) {
    throw Error(ErrorCode::kInvalidArgument, "simplify: max_feature_error and color_scale must be positive");
  }
  Simplifier s(mesh, width, height, options, schedule);
  return s.run();
}

}  // namespace subvec
