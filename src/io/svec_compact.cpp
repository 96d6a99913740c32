// Compact levels of `.svec` versions 2 and 3 (docs/format.md, "Payload, version 2" and
// "Payload, version 3").
//
// Design note. A level is six kinds of symbols, which version 2 writes as six sections of varints
// (the larger ones each in their own zstd block, so that they get their own entropy tables) and
// version 3 as one stream of the same symbols, binarized and range-coded with adaptive contexts
// (svec_range_p.h):
//  1. connectivity: the mesh, closed into a sphere by one virtual vertex joined to every border
//     edge, is visited by region growing from triangle 0. A frontier (cyclic lists of boundary
//     edges) separates visited from unvisited triangles; each step takes the triangle across the
//     frontier's gate edge (u, w) and names its third vertex x with one of five operations, as in
//     Rossignac's Edgebreaker: C (x is new), R (x follows w on the frontier), L (x precedes u),
//     E (the loop closes) and S (x is elsewhere on the loop, which splits in two; the position is
//     stored as an offset). On a sphere a vertex appears at most once per loop, so these cover
//     every case. Three operations share a byte: about 2 bits per triangle before zstd.
//  2. split offsets: the virtual vertex's number, then one varint per S.
//  3. positions: integers on the 2^-p pixel grid, in the order vertices were met, each predicted
//     by the mean of the parallelograms a + b - c over the already decoded triangles around it
//     (multi-parallelogram prediction), or from the gate it was met across.
//  4-5. creases and features: a feature is its start vertex and, per step, the rank of the next
//     vertex among the current vertex's neighbors sorted by how straight they continue the chain
//     (mostly rank 0); the ranks have their own section.
//  6. colors: integers on the 2^-c level grid, in canonical face-varying order (first use by the
//     triangles in traversal order; tears are known by then), each predicted by the mean of the
//     decoded values it shares a triangle with, the residual written as green, red - green and
//     blue - green.
// Decoding mirrors each step with the same frontier code, so both sides stay in lock step; every
// count, offset and index read is checked before use. The traversal, prediction and
// quantization are shared by both versions: only the symbol sinks (encoder) and sources (decoder)
// differ, so version 3 holds exactly version 2's content.
//
// Why a hand-written range coder. The symbols are a few thousand small numbers per level; zstd
// models the varint bytes order-0 and pays for per-block tables, which on 8 to 16 KB files is a
// noticeable share. Binarized numbers (adaptive Exp-Golomb) in adaptive binary contexts (12-bit
// probabilities adapted by a shift, fast while a context is new) save about 10 % with no change
// of content. No packaged library exposes such a coder as a documented, stable bitstream, and a
// file format must not depend on a library's internals; the coder is ~200 lines of integer
// arithmetic, fully specified in docs/format.md and pinned by a known-answer test. Contexts were
// kept only where they measured better: the fans of the gate vertices for the operations, the
// neighbours' residual sizes for colors; positions use one model per coordinate (finer contexts
// learned too slowly on a few thousand vertices and cost more than they saved).
#include "io/svec_compact_p.h"

#include "io/svec_range_p.h"

#include <algorithm>
#include <bit>
#include <climits>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <tuple>
#include <unordered_map>

#include "subvec/mesh/topology.h"

namespace subvec::svec_detail {
namespace {

constexpr uint8_t kOpC = 0, kOpL = 1, kOpR = 2, kOpE = 3, kOpS = 4;
constexpr int kOpsPerByte = 3;  // base 5: op0 + 5 op1 + 25 op2 < 125

// ---------------------------------------------------------------------------------------------
// The frontier, shared by the encoder and the decoder.

class Frontier {
 public:
  // A loop entry stands for the frontier edge v -> v(next), oriented as in the unvisited triangle
  // across it; `apex` is the third vertex of the visited triangle on the other side.
  struct Node {
    int32_t v, next, prev, apex;
  };

  // Starts from the visited seed triangle (a, b, c): the loop b -> a -> c.
  Frontier(int32_t a, int32_t b, int32_t c) {
    nodes_.push_back({b, 1, 2, c});
    nodes_.push_back({a, 2, 0, b});
    nodes_.push_back({c, 0, 1, a});
    gate_ = 0;
    size_ = 3;
  }

  int32_t u() const { return nodes_[gate_].v; }
  int32_t w() const { return nodes_[next(gate_)].v; }
  int32_t after_w() const { return nodes_[next(next(gate_))].v; }
  int32_t before_u() const { return nodes_[prev(gate_)].v; }
  int32_t gate_apex() const { return nodes_[gate_].apex; }
  int64_t size() const { return size_; }

  // C: the new triangle (u, w, x) with a new vertex x.
  void add_vertex(int32_t x) {
    const int32_t g = gate_, n = next(g);
    const int32_t u0 = nodes_[g].v, w0 = nodes_[n].v;
    const auto nx = static_cast<int32_t>(nodes_.size());
    nodes_.push_back({x, n, g, u0});
    nodes_[n].prev = nx;
    nodes_[g].next = nx;
    nodes_[g].apex = w0;
    ++size_;
    gate_ = nx;
  }
  // R: x follows w; w leaves the loop.
  void close_right() {
    const int32_t g = gate_, n = next(g);
    nodes_[g].apex = nodes_[n].v;
    unlink(n);
    --size_;
  }
  // L: x precedes u; u leaves the loop.
  void close_left() {
    const int32_t g = gate_, p = prev(g);
    nodes_[p].apex = nodes_[g].v;
    unlink(g);
    --size_;
    gate_ = p;
  }
  // E: the loop was one triangle; continues with the last loop put aside. False when none is left.
  bool close_loop() {
    if (stack_.empty()) return false;
    std::tie(gate_, size_) = stack_.back();
    stack_.pop_back();
    return true;
  }
  // The vertex `pos` steps forward from the gate (walking the shorter way round).
  int32_t vertex_at(int64_t pos) const { return nodes_[node_at(pos)].v; }
  // Forward steps from the gate to the entry of x, or -1.
  int64_t find(int32_t x) const {
    int32_t n = gate_;
    for (int64_t pos = 0; pos < size_; ++pos, n = next(n))
      if (nodes_[n].v == x) return pos;
    return -1;
  }
  // S: x is the vertex `pos` (3 .. size - 2) steps forward. The loop splits into
  // x -> w -> ... -> (before x), continued now, and u -> x -> ... -> (before u), put aside.
  void split(int64_t pos) {
    const int32_t g = gate_, n = next(g), at = node_at(pos), before = prev(at);
    const int32_t u0 = nodes_[g].v, w0 = nodes_[n].v;
    const auto nx = static_cast<int32_t>(nodes_.size());
    nodes_.push_back({nodes_[at].v, n, before, u0});
    nodes_[n].prev = nx;
    nodes_[before].next = nx;
    nodes_[g].next = at;
    nodes_[at].prev = g;
    nodes_[g].apex = w0;
    stack_.emplace_back(g, size_ - pos + 1);
    size_ = pos;
    gate_ = nx;
  }

 private:
  int32_t next(int32_t n) const { return nodes_[n].next; }
  int32_t prev(int32_t n) const { return nodes_[n].prev; }
  int32_t node_at(int64_t pos) const {
    int32_t n = gate_;
    if (pos <= size_ / 2) {
      for (int64_t i = 0; i < pos; ++i) n = next(n);
    } else {
      for (int64_t i = pos; i < size_; ++i) n = prev(n);
    }
    return n;
  }
  void unlink(int32_t n) {
    nodes_[prev(n)].next = next(n);
    nodes_[next(n)].prev = prev(n);
  }

  std::vector<Node> nodes_;
  int32_t gate_ = 0;
  int64_t size_ = 0;
  std::vector<std::pair<int32_t, int64_t>> stack_;  // gate and size of loops put aside
};

// S offsets: the shorter way round, forward (even codes) or backward (odd codes).
uint64_t split_code(int64_t pos, int64_t size) {
  const int64_t forward = pos - 3, backward = size - pos - 2;
  return backward < forward ? 2 * uint64_t(backward) + 1 : 2 * uint64_t(forward);
}
int64_t split_position(uint64_t code, int64_t size) {
  const auto half = static_cast<int64_t>(std::min<uint64_t>(code / 2, uint64_t{1} << 62));
  return code % 2 ? size - 2 - half : half + 3;
}

// ---------------------------------------------------------------------------------------------
// What the traversal yields, in the decoder's numbering (vertices 0..V, one of them virtual).

struct Traversal {
  int32_t virtual_vertex = -1;
  std::vector<Tri> faces;               // visit order, (u, w, x) with (u, w) the gate edge
  std::vector<std::array<int32_t, 3>> vertex_basis;  // per vertex: (u, w, apex) when it was met
};

// The level in traversal order plus what prediction needs.
struct Canonical {
  ControlMesh mesh;                  // vertices, triangles in visit order; colors filled later
  std::vector<int32_t> final_index;  // decode number -> vertex of `mesh` (-1: virtual)
  std::vector<int32_t> decode_index;  // vertex of `mesh` -> decode number
};

Canonical make_canonical(const Traversal& tr, int num_vertices) {
  Canonical c;
  c.final_index.assign(tr.vertex_basis.size(), -1);
  c.decode_index.reserve(num_vertices);
  for (int32_t d = 0; d < static_cast<int32_t>(tr.vertex_basis.size()); ++d) {
    if (d == tr.virtual_vertex) continue;
    c.final_index[d] = static_cast<int32_t>(c.decode_index.size());
    c.decode_index.push_back(d);
  }
  std::vector<int32_t> real(tr.faces.size(), -1);
  for (size_t f = 0; f < tr.faces.size(); ++f) {
    const Tri& t = tr.faces[f];
    if (t[0] == tr.virtual_vertex || t[1] == tr.virtual_vertex || t[2] == tr.virtual_vertex)
      continue;
    real[f] = c.mesh.num_triangles();
    c.mesh.triangles.push_back({c.final_index[t[0]], c.final_index[t[1]], c.final_index[t[2]]});
  }
  return c;
}

// ---------------------------------------------------------------------------------------------
// Prediction.

uint64_t key(int32_t a, int32_t b) {
  return (uint64_t{static_cast<uint32_t>(a)} << 32) | static_cast<uint32_t>(b);
}

using Point = std::array<int64_t, 2>;
using Rgb = std::array<int64_t, 3>;

int64_t floor_div(int64_t a, int64_t b) {
  const int64_t q = a / b;
  return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}

// Positions in decode order, each predicted from the vertices decoded before it: the mean of
// every parallelogram a + b - c over an edge (a, b) with triangles (x, a, b) and (b, a, c), all
// three known (multi-parallelogram prediction); for the few vertices with none, from the gate
// they were met across.
class PositionPredictor {
 public:
  explicit PositionPredictor(const Traversal& tr) : tr_(tr) {
    const size_t n = tr.vertex_basis.size();
    offsets_.assign(n + 1, 0);
    for (const Tri& t : tr.faces)
      if (real(t))
        for (int32_t v : t) ++offsets_[v + 1];
    for (size_t v = 0; v < n; ++v) offsets_[v + 1] += offsets_[v];
    faces_.resize(offsets_[n]);
    std::vector<int32_t> fill(offsets_.begin(), offsets_.end() - 1);
    for (int32_t f = 0; f < static_cast<int32_t>(tr.faces.size()); ++f) {
      const Tri& t = tr.faces[f];
      if (!real(t)) continue;
      for (int k = 0; k < 3; ++k) {
        faces_[fill[t[k]]++] = f;
        half_edges_.emplace_back(key(t[k], t[(k + 1) % 3]), f);
      }
    }
    std::sort(half_edges_.begin(), half_edges_.end());
  }

  Point predict(int32_t x, const std::vector<Point>& p, const Point& previous,
                const Point& max) const {
    Point sum{0, 0};
    int64_t n = 0;
    for (int32_t i = offsets_[x]; i < offsets_[x + 1]; ++i) {
      const Tri& t = tr_.faces[faces_[i]];
      const int k = t[0] == x ? 0 : t[1] == x ? 1 : 2;
      const int32_t a = t[(k + 1) % 3], b = t[(k + 2) % 3];
      if (a > x || b > x) continue;
      const auto it = std::lower_bound(half_edges_.begin(), half_edges_.end(),
                                       std::pair<uint64_t, int32_t>(key(b, a), -1));
      if (it == half_edges_.end() || it->first != key(b, a)) continue;
      const Tri& o = tr_.faces[it->second];
      const int32_t c = o[0] != a && o[0] != b ? o[0] : o[1] != a && o[1] != b ? o[1] : o[2];
      if (c > x) continue;
      for (int j = 0; j < 2; ++j) sum[j] += p[a][j] + p[b][j] - p[c][j];
      ++n;
    }
    Point q;
    if (n > 0) {
      q = {floor_div(2 * sum[0] + n, 2 * n), floor_div(2 * sum[1] + n, 2 * n)};
    } else {
      q = from_gate(tr_.vertex_basis[x], p, previous);
    }
    return {std::clamp<int64_t>(q[0], 0, max[0]), std::clamp<int64_t>(q[1], 0, max[1])};
  }

 private:
  bool real(const Tri& t) const {
    return t[0] != tr_.virtual_vertex && t[1] != tr_.virtual_vertex && t[2] != tr_.virtual_vertex;
  }
  // From the gate (u, w) with apex a that the vertex was met across.
  Point from_gate(const std::array<int32_t, 3>& basis, const std::vector<Point>& p,
                  const Point& previous) const {
    const auto [u, w, a] = basis;
    const int32_t virt = tr_.virtual_vertex;
    if (u < 0) return previous;  // the seed
    if (u == virt) return p[w];  // a border vertex next to w
    if (w == virt) return p[u];
    if (a == virt) {
      // Across a border edge: the apex of an equilateral triangle on its inner side.
      const int64_t dx = p[w][0] - p[u][0], dy = p[w][1] - p[u][1];
      return {floor_div(p[u][0] + p[w][0], 2) - floor_div(dy * 7, 8),
              floor_div(p[u][1] + p[w][1], 2) + floor_div(dx * 7, 8)};
    }
    return {p[u][0] + p[w][0] - p[a][0], p[u][1] + p[w][1] - p[a][1]};
  }

  const Traversal& tr_;
  std::vector<int32_t> offsets_, faces_;
  std::vector<std::pair<uint64_t, int32_t>> half_edges_;
};

// Neighbors of each vertex, sorted by index (CSR).
struct Neighbors {
  std::vector<int32_t> offsets, list;
  std::span<const int32_t> of(int v) const {
    return {list.data() + offsets[v], list.data() + offsets[v + 1]};
  }
};

// Color value `ci` from the known values it shares a triangle with (their rounded mean).
Rgb predict_color(std::span<const int32_t> adjacent, const std::vector<char>& known,
                        const std::vector<Rgb>& colors, const Rgb& previous) {
  Rgb sum{0, 0, 0};
  int64_t n = 0;
  for (const int32_t j : adjacent) {
    if (!known[j]) continue;
    for (int ch = 0; ch < 3; ++ch) sum[ch] += colors[j][ch];
    ++n;
  }
  if (n == 0) return previous;
  for (int ch = 0; ch < 3; ++ch) sum[ch] = floor_div(2 * sum[ch] + n, 2 * n);
  return sum;
}

Neighbors neighbors(const std::vector<Tri>& triangles, size_t n_vertices) {
  std::vector<std::pair<int32_t, int32_t>> pairs;
  pairs.reserve(triangles.size() * 6);
  for (const Tri& t : triangles) {
    for (int k = 0; k < 3; ++k) {
      pairs.emplace_back(t[k], t[(k + 1) % 3]);
      pairs.emplace_back(t[(k + 1) % 3], t[k]);
    }
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  Neighbors n;
  n.offsets.assign(n_vertices + 1, 0);
  for (const auto& [a, b] : pairs) ++n.offsets[a + 1];
  for (size_t v = 0; v < n_vertices; ++v) n.offsets[v + 1] += n.offsets[v];
  n.list.reserve(pairs.size());
  for (const auto& [a, b] : pairs) n.list.push_back(b);
  return n;
}

// Candidates for the step after `from` -> `at` of a chain, best first: by the cosine of the turn
// (straightest first), then by index. Positions are integers, so the cosine is computed from
// exact integer dot products and correctly rounded operations: the same order on every machine.
std::vector<int32_t> ranked_steps(const Neighbors& nb, const std::vector<Point>& p, int32_t from,
                                  int32_t at) {
  const std::span<const int32_t> cand = nb.of(at);
  std::vector<int32_t> out(cand.begin(), cand.end());
  if (from < 0) return out;
  const int64_t dx = p[at][0] - p[from][0], dy = p[at][1] - p[from][1];
  std::vector<std::pair<double, int32_t>> keyed;
  keyed.reserve(out.size());
  for (const int32_t q : out) {
    const int64_t ex = p[q][0] - p[at][0], ey = p[q][1] - p[at][1];
    const double dot = static_cast<double>(dx * ex + dy * ey);
    const double len = std::sqrt(static_cast<double>(ex * ex + ey * ey));
    keyed.emplace_back(len > 0 ? -dot / len : 0.0, q);
  }
  std::sort(keyed.begin(), keyed.end());
  for (size_t i = 0; i < keyed.size(); ++i) out[i] = keyed[i].second;
  return out;
}

int32_t rank_of(const std::vector<int32_t>& ranked, int32_t v) {
  const auto it = std::find(ranked.begin(), ranked.end(), v);
  return it == ranked.end() ? -1 : static_cast<int32_t>(it - ranked.begin());
}

int64_t to_grid(double v, int bits) { return std::llround(std::ldexp(v, bits)); }
double from_grid(int64_t v, int bits) { return std::ldexp(static_cast<double>(v), -bits); }


// Section framing: u32 byte length, then the bytes.
void put_section(ByteWriter& out, const std::vector<uint8_t>& bytes, const char* what,
                 std::vector<size_t>& block_ends) {
  out.count(bytes.size(), what);
  out.bytes.insert(out.bytes.end(), bytes.begin(), bytes.end());
  block_ends.push_back(out.bytes.size());
}

// ---------------------------------------------------------------------------------------------
// Contexts of version 3: what the coder knows, identically on both sides, before each symbol.

// The state of the traversal before an operation.
struct OpContext {
  bool triangle = false;     // the current loop has 3 entries: only C and E are possible
  int fan_u = 0, fan_w = 0;  // visited triangles at the gate vertices u and w (7: virtual)
};

int fan_bucket(int32_t v, int32_t virt, const std::vector<int32_t>& visits) {
  return v == virt ? 7 : std::min(visits[v], 6);
}

// Activity bucket of a mean magnitude sum / n: 0 without neighbors (n = 0), else
// min((bit length of floor(sum / n) + 1) / 2, 4).
inline constexpr int kActivityBuckets = 5;
int activity_bucket(int64_t sum, int64_t n) {
  if (n == 0) return 0;
  const uint64_t mean = uint64_t(sum / n);
  return std::min((int(std::bit_width(mean)) + 1) / 2, kActivityBuckets - 1);
}
// Residual magnitudes enter the contexts capped, so that sums stay small.
inline constexpr int64_t kActivityCap = 65535;
int64_t capped(int64_t a) { return std::min(std::abs(a), kActivityCap); }


// Residual contexts of a color value: per coded channel (d_G, d_R - d_G, d_B - d_G) the mean
// magnitude of that channel's residuals over the known values it shares a triangle with.
struct ColorContext {
  std::array<int, 3> activity{};
};

ColorContext color_context(std::span<const int32_t> adjacent, const std::vector<char>& known,
                           const std::vector<Rgb>& activity) {
  Rgb sum{0, 0, 0};
  int64_t n = 0;
  for (const int32_t j : adjacent) {
    if (!known[j]) continue;
    for (int ch = 0; ch < 3; ++ch) sum[ch] += activity[j][ch];
    ++n;
  }
  return {{activity_bucket(sum[0], n), activity_bucket(sum[1], n), activity_bucket(sum[2], n)}};
}

// ---------------------------------------------------------------------------------------------
// Symbol sinks: version 2 writes varint sections, version 3 one range-coded stream.

enum Section { kConnectivity, kSplits, kPositions, kFeatures, kSteps, kColors, kSections };
const char* const kSectionNames[kSections] = {"connectivity", "split offsets", "positions",
                                              "features",     "feature steps", "colors"};

class SymbolSink {
 public:
  virtual ~SymbolSink() = default;
  virtual void virtual_vertex(uint64_t v) = 0;
  virtual void op(int op, const OpContext& c) = 0;
  virtual void split(uint64_t code) = 0;
  virtual void position(int64_t rx, int64_t ry) = 0;
  virtual void vertex(uint64_t v) = 0;  // first vertex of a crease or feature
  virtual void step(uint64_t rank, bool first) = 0;
  virtual void feature(int64_t id_delta, double saliency, uint64_t n_minus_2) = 0;
  // d_G, d_R - d_G, d_B - d_G
  virtual void color(const Rgb& d, const ColorContext& c) = 0;
  virtual void finish(ByteWriter& out, std::vector<size_t>& block_ends) = 0;
};

class VarintSink final : public SymbolSink {
 public:
  void virtual_vertex(uint64_t v) override { put_varint(s_[kSplits], v); }
  void op(int op, const OpContext&) override { ops_.push_back(uint8_t(op)); }
  void split(uint64_t code) override { put_varint(s_[kSplits], code); }
  void position(int64_t rx, int64_t ry) override {
    put_varint(s_[kPositions], zigzag(rx));
    put_varint(s_[kPositions], zigzag(ry));
  }
  void vertex(uint64_t v) override { put_varint(s_[kFeatures], v); }
  void step(uint64_t rank, bool) override { put_varint(s_[kSteps], rank); }
  void feature(int64_t id_delta, double saliency, uint64_t n_minus_2) override {
    std::vector<uint8_t>& bytes = s_[kFeatures];
    put_varint(bytes, zigzag(id_delta));
    if (saliency == 0 && !std::signbit(saliency)) {
      bytes.push_back(0);
    } else if (static_cast<double>(static_cast<float>(saliency)) == saliency) {
      bytes.push_back(1);
      const auto bits = std::bit_cast<uint32_t>(static_cast<float>(saliency));
      for (int k = 0; k < 4; ++k) bytes.push_back(static_cast<uint8_t>(bits >> (8 * k)));
    } else {
      bytes.push_back(2);
      const auto bits = std::bit_cast<uint64_t>(saliency);
      for (int k = 0; k < 8; ++k) bytes.push_back(static_cast<uint8_t>(bits >> (8 * k)));
    }
    put_varint(bytes, n_minus_2);
  }
  void color(const Rgb& d, const ColorContext&) override {
    for (int ch = 0; ch < 3; ++ch) put_varint(s_[kColors], zigzag(d[ch]));
  }
  void finish(ByteWriter& out, std::vector<size_t>& block_ends) override {
    // 1. Connectivity (the seed is implicit; 2V - 3 operations), three per byte.
    std::vector<uint8_t>& bytes = s_[kConnectivity];
    for (size_t i = 0; i < ops_.size(); i += kOpsPerByte) {
      int b = 0, scale = 1;
      for (size_t j = i; j < i + kOpsPerByte; ++j, scale *= 5)
        if (j < ops_.size()) b += ops_[j] * scale;
      bytes.push_back(static_cast<uint8_t>(b));
    }
    // The two small sections share the block of the section after them.
    std::vector<size_t> no_blocks;
    put_section(out, s_[kConnectivity], "connectivity bytes", block_ends);
    put_section(out, s_[kSplits], "split offset bytes", no_blocks);
    put_section(out, s_[kPositions], "position bytes", block_ends);
    put_section(out, s_[kFeatures], "feature bytes", no_blocks);
    put_section(out, s_[kSteps], "feature step bytes", block_ends);
    put_section(out, s_[kColors], "color bytes", block_ends);
  }

 private:
  std::vector<uint8_t> ops_;
  std::vector<uint8_t> s_[kSections];
};

// Saliency bits coded with contexts: f32 (sign and 8 exponent bits), f64 (sign and 11).
inline constexpr int kSaliencyTopBits[2] = {9, 12};
inline constexpr int kSaliencyBits[2] = {32, 64};
inline constexpr int kSaliencyModeledMantissa = 4;

// The adaptive models of version 3 (docs/format.md, "Payload, version 3").
struct Models {
  BitModel op_triangle;  // loop of 3: C (0) or E (1)
  BitModel op_c[8];      // C (0) or not, by the fan of w
  BitModel op_r[8];      // R (0) or L / S, by the fan of w
  BitModel op_l[8];      // L (0) or S, by the fan of u
  NumberModel virtual_vertex, split;
  NumberModel position[2];  // x, y
  NumberModel step_first, step_next, id, length;
  BitModel saliency_nonzero, saliency_wide;
  // Sign and exponent bits of a saliency as a bit tree (node 1 the root, node 2k + b after k),
  // then the top mantissa bits, one context per position.
  BitModel saliency_top[2][1 << kSaliencyTopBits[1]];
  BitModel saliency_mantissa[2][kSaliencyModeledMantissa];
  NumberModel color[3][kActivityBuckets];  // d_G, d_R - d_G, d_B - d_G by their activity
};

class RangeSink final : public SymbolSink {
 public:
  RangeSink(Models& m, int32_t nv) : m_(m), vertex_bits_(std::bit_width(uint32_t(nv - 1))) {}
  void virtual_vertex(uint64_t v) override { put_unsigned(e_, m_.virtual_vertex, v); }
  void op(int op, const OpContext& c) override {
    if (c.triangle) {
      e_.bit(m_.op_triangle, op == kOpE);
      return;
    }
    e_.bit(m_.op_c[c.fan_w], op != kOpC);
    if (op == kOpC) return;
    e_.bit(m_.op_r[c.fan_w], op != kOpR);
    if (op == kOpR) return;
    e_.bit(m_.op_l[c.fan_u], op != kOpL);
  }
  void split(uint64_t code) override { put_unsigned(e_, m_.split, code); }
  void position(int64_t rx, int64_t ry) override {
    put_signed(e_, m_.position[0], rx);
    put_signed(e_, m_.position[1], ry);
  }
  void vertex(uint64_t v) override { e_.direct(v, vertex_bits_); }
  void step(uint64_t rank, bool first) override {
    put_unsigned(e_, first ? m_.step_first : m_.step_next, rank);
  }
  void feature(int64_t id_delta, double saliency, uint64_t n_minus_2) override {
    put_signed(e_, m_.id, id_delta);
    // The compact form keeps a saliency in single precision (docs/format.md, "Choosing the
    // grids"): it only orders features, and the 29 low bits of a double are noise that cost
    // about 4 bytes a feature. Values beyond the float range stay as they are.
    if (std::isfinite(saliency) && std::abs(saliency) <= double(std::numeric_limits<float>::max()))
      saliency = static_cast<double>(static_cast<float>(saliency));
    const bool zero = saliency == 0 && !std::signbit(saliency);
    e_.bit(m_.saliency_nonzero, !zero);
    if (!zero) {
      const bool wide = static_cast<double>(static_cast<float>(saliency)) != saliency;
      e_.bit(m_.saliency_wide, wide);
      const uint64_t bits = wide ? std::bit_cast<uint64_t>(saliency)
                                 : std::bit_cast<uint32_t>(static_cast<float>(saliency));
      const int w = wide, total = kSaliencyBits[w], top = kSaliencyTopBits[w];
      uint32_t node = 1;
      for (int i = total - 1; i >= total - top; --i) {
        const int b = int((bits >> i) & 1);
        e_.bit(m_.saliency_top[w][node], b);
        node = 2 * node + uint32_t(b);
      }
      for (int k = 0; k < kSaliencyModeledMantissa; ++k)
        e_.bit(m_.saliency_mantissa[w][k], int((bits >> (total - top - 1 - k)) & 1));
      const int rest = total - top - kSaliencyModeledMantissa;
      if (rest > 32) e_.direct((bits >> 32) & ((uint64_t{1} << (rest - 32)) - 1), rest - 32);
      e_.direct(bits & ((uint64_t{1} << std::min(rest, 32)) - 1), std::min(rest, 32));
    }
    put_unsigned(e_, m_.length, n_minus_2);
  }
  void color(const Rgb& d, const ColorContext& c) override {
    for (int ch = 0; ch < 3; ++ch) put_signed(e_, m_.color[ch][c.activity[ch]], d[ch]);
  }
  void finish(ByteWriter& out, std::vector<size_t>& block_ends) override {
    const std::vector<uint8_t> bytes = e_.finish();
    put_section(out, bytes, "coded level bytes", block_ends);
  }

 private:
  Models& m_;
  int vertex_bits_;
  RangeEncoder e_;
};

// Symbol sources, the decoder's side.
class SymbolSource {
 public:
  virtual ~SymbolSource() = default;
  virtual void begin(Section s) = 0;
  virtual void end(Section s) = 0;
  virtual uint64_t virtual_vertex() = 0;
  virtual int op(const OpContext& c) = 0;
  virtual uint64_t split() = 0;
  virtual std::array<int64_t, 2> position() = 0;
  virtual uint64_t vertex() = 0;
  virtual uint64_t step(bool first) = 0;
  virtual int64_t feature_id(const std::string& what) = 0;
  virtual double saliency(const std::string& what) = 0;
  // n - 2 for a chain of n vertices; `what` names the feature.
  virtual uint64_t feature_length(const std::string& what) = 0;
  virtual Rgb color(const ColorContext& c) = 0;
  virtual void finish() = 0;
};

class VarintSource final : public SymbolSource {
 public:
  VarintSource(Cursor& in, std::string name, size_t nv) : in_(in), name_(std::move(name)), nv_(nv) {}
  void begin(Section s) override {
    const std::string label = name_ + kSectionNames[s];
    const size_t n = in_.count(label, 1, Limits::kMaxElements * 64);
    in_.set_context(label);
    c_[s] = Cursor(std::span<const uint8_t>(in_.take(n), n));
    c_[s].set_context(label);
    if (s == kConnectivity) {
      const size_t num_ops = 2 * nv_ - 3;
      if (c_[s].remaining() != (num_ops + kOpsPerByte - 1) / kOpsPerByte) {
        fail(name_ + "connectivity: " + str(c_[s].remaining()) + " bytes for " + str(nv_) +
             " vertices (expected " + str((num_ops + kOpsPerByte - 1) / kOpsPerByte) + ")");
      }
    }
  }
  void end(Section s) override {
    if (c_[s].remaining() != 0)
      fail(str(c_[s].remaining()) + " unexpected bytes at the end of " + name_ + kSectionNames[s]);
  }
  uint64_t virtual_vertex() override { return c_[kSplits].varint(); }
  int op(const OpContext&) override {
    if (ops_read_ % kOpsPerByte == 0) {
      packed_ = c_[kConnectivity].u8();
      if (packed_ >= 125)
        fail(name_ + "connectivity: byte " + str(ops_read_ / kOpsPerByte) +
             " is not three operations");
    }
    ++ops_read_;
    const int op = packed_ % 5;
    packed_ = static_cast<uint8_t>(packed_ / 5);
    return op;
  }
  uint64_t split() override { return c_[kSplits].varint(); }
  std::array<int64_t, 2> position() override {
    const int64_t x = c_[kPositions].svarint();
    return {x, c_[kPositions].svarint()};
  }
  uint64_t vertex() override { return c_[kFeatures].varint(); }
  uint64_t step(bool) override { return c_[kSteps].varint(); }
  int64_t feature_id(const std::string& what) override {
    c_[kFeatures].set_context(name_ + what);
    return c_[kFeatures].svarint();
  }
  double saliency(const std::string& what) override {
    Cursor& fs = c_[kFeatures];
    const uint8_t tag = fs.u8();
    if (tag == 1) return std::bit_cast<float>(fs.u32());
    if (tag == 2) return fs.f64();
    if (tag != 0) fail(name_ + what + ": unknown saliency tag " + str(tag));
    return 0;
  }
  uint64_t feature_length(const std::string& what) override {
    const uint64_t n = c_[kFeatures].varint();
    if (n > c_[kSteps].remaining())
      fail(name_ + what + ": " + str(n + 2) + " vertices, too few bytes");
    return n;
  }
  Rgb color(const ColorContext&) override {
    Rgb d;
    for (int64_t& r : d) r = c_[kColors].svarint();
    return d;
  }
  void finish() override {}

 private:
  Cursor& in_;
  std::string name_;
  size_t nv_;
  Cursor c_[kSections] = {Cursor({}), Cursor({}), Cursor({}), Cursor({}), Cursor({}), Cursor({})};
  size_t ops_read_ = 0;
  uint8_t packed_ = 0;
};

class RangeSource final : public SymbolSource {
 public:
  RangeSource(std::span<const uint8_t> bytes, const std::string& name, Models& m, size_t nv)
      : d_(bytes, name + "stream"), m_(m), vertex_bits_(std::bit_width(uint32_t(nv - 1))) {}
  void begin(Section s) override { d_.set_context(kSectionNames[s]); }
  void end(Section) override {}
  uint64_t virtual_vertex() override { return get_unsigned(d_, m_.virtual_vertex); }
  int op(const OpContext& c) override {
    if (c.triangle) return d_.bit(m_.op_triangle) ? kOpE : kOpC;
    if (!d_.bit(m_.op_c[c.fan_w])) return kOpC;
    if (!d_.bit(m_.op_r[c.fan_w])) return kOpR;
    return d_.bit(m_.op_l[c.fan_u]) ? kOpS : kOpL;
  }
  uint64_t split() override { return get_unsigned(d_, m_.split); }
  std::array<int64_t, 2> position() override {
    const int64_t x = get_signed(d_, m_.position[0]);
    return {x, get_signed(d_, m_.position[1])};
  }
  uint64_t vertex() override { return d_.direct(vertex_bits_); }
  uint64_t step(bool first) override {
    return get_unsigned(d_, first ? m_.step_first : m_.step_next);
  }
  int64_t feature_id(const std::string&) override { return get_signed(d_, m_.id); }
  double saliency(const std::string&) override {
    if (!d_.bit(m_.saliency_nonzero)) return 0;
    const int w = d_.bit(m_.saliency_wide), total = kSaliencyBits[w], top = kSaliencyTopBits[w];
    uint32_t node = 1;
    for (int i = 0; i < top; ++i) node = 2 * node + uint32_t(d_.bit(m_.saliency_top[w][node]));
    uint64_t bits = node - (uint32_t{1} << top);
    for (int k = 0; k < kSaliencyModeledMantissa; ++k)
      bits = (bits << 1) | uint64_t(d_.bit(m_.saliency_mantissa[w][k]));
    const int rest = total - top - kSaliencyModeledMantissa;
    if (rest > 32) bits = (bits << (rest - 32)) | d_.direct(rest - 32);
    bits = (bits << std::min(rest, 32)) | d_.direct(std::min(rest, 32));
    return w ? std::bit_cast<double>(bits) : double(std::bit_cast<float>(uint32_t(bits)));
  }
  uint64_t feature_length(const std::string&) override { return get_unsigned(d_, m_.length); }
  Rgb color(const ColorContext& c) override {
    Rgb d;
    for (int ch = 0; ch < 3; ++ch) d[ch] = get_signed(d_, m_.color[ch][c.activity[ch]]);
    return d;
  }
  void finish() override { d_.finish(); }

 private:
  RangeDecoder d_;
  Models& m_;
  int vertex_bits_;
};

}  // namespace


ControlMesh quantize_positions(const ControlMesh& mesh, int width, int height,
                               int position_bits) {
  ControlMesh q = mesh;
  const int32_t nv = mesh.num_vertices();
  const Point max = {int64_t{width} << position_bits, int64_t{height} << position_bits};

  // Positions: the nearest grid point, interior vertices kept off the border lines.
  std::vector<Point> g(nv);
  std::vector<std::array<bool, 2>> fixed(nv);
  for (int32_t v = 0; v < nv; ++v) {
    const double xy[2] = {mesh.positions[v].x, mesh.positions[v].y};
    for (int k = 0; k < 2; ++k) {
      fixed[v][k] = xy[k] == 0 || xy[k] == (k == 0 ? width : height);
      g[v][k] = to_grid(xy[k], position_bits);
      if (!fixed[v][k]) g[v][k] = std::clamp<int64_t>(g[v][k], 1, max[k] - 1);
    }
  }
  // Triangles that rounding flipped or collapsed: move their vertices, one at a time, to the
  // nearest grid point within two cells that leaves fewer of their triangles non-positive.
  std::vector<int32_t> offsets(size_t(nv) + 1, 0), faces;
  for (const Tri& t : mesh.triangles)
    for (int32_t v : t) ++offsets[v + 1];
  for (int32_t v = 0; v < nv; ++v) offsets[v + 1] += offsets[v];
  faces.resize(offsets[nv]);
  {
    std::vector<int32_t> fill(offsets.begin(), offsets.end() - 1);
    for (int32_t f = 0; f < mesh.num_triangles(); ++f)
      for (int32_t v : mesh.triangles[f]) faces[fill[v]++] = f;
  }
  auto positive = [&](int32_t f) {
    const Tri& t = mesh.triangles[f];
    const Point &a = g[t[0]], &b = g[t[1]], &c = g[t[2]];
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) > 0;
  };
  auto bad_around = [&](int32_t v) {
    return std::count_if(faces.begin() + offsets[v], faces.begin() + offsets[v + 1],
                         [&](int32_t f) { return !positive(f); });
  };
  std::vector<std::array<int64_t, 2>> moves;
  for (int64_t dy = -2; dy <= 2; ++dy)
    for (int64_t dx = -2; dx <= 2; ++dx) moves.push_back({dx, dy});
  for (int round = 0; round < 8; ++round) {
    std::vector<int32_t> bad;
    for (int32_t f = 0; f < mesh.num_triangles(); ++f)
      if (!positive(f)) bad.insert(bad.end(), mesh.triangles[f].begin(), mesh.triangles[f].end());
    if (bad.empty()) break;
    std::sort(bad.begin(), bad.end());
    bad.erase(std::unique(bad.begin(), bad.end()), bad.end());
    for (const int32_t v : bad) {
      const double exact[2] = {std::ldexp(mesh.positions[v].x, position_bits),
                               std::ldexp(mesh.positions[v].y, position_bits)};
      const Point base = {to_grid(mesh.positions[v].x, position_bits),
                          to_grid(mesh.positions[v].y, position_bits)};
      std::vector<std::pair<double, Point>> candidates;
      for (const auto& m : moves) {
        if ((fixed[v][0] && m[0] != 0) || (fixed[v][1] && m[1] != 0)) continue;
        const Point c = {base[0] + m[0], base[1] + m[1]};
        if ((!fixed[v][0] && (c[0] < 1 || c[0] > max[0] - 1)) ||
            (!fixed[v][1] && (c[1] < 1 || c[1] > max[1] - 1)))
          continue;
        const double ex = double(c[0]) - exact[0], ey = double(c[1]) - exact[1];
        candidates.emplace_back(ex * ex + ey * ey, c);
      }
      std::stable_sort(candidates.begin(), candidates.end(),
                       [](const auto& a, const auto& b) { return a.first < b.first; });
      Point best = g[v];
      auto best_bad = bad_around(v);
      for (const auto& [d, c] : candidates) {
        g[v] = c;
        const auto n = bad_around(v);
        if (n < best_bad) {
          best = c;
          best_bad = n;
          if (n == 0) break;
        }
      }
      g[v] = best;
    }
  }
  for (int32_t v = 0; v < nv; ++v) {
    q.positions[v] = {from_grid(g[v][0], position_bits), from_grid(g[v][1], position_bits)};
  }

  return q;
}

// ---------------------------------------------------------------------------------------------
// ---------------------------------------------------------------------------------------------
// Encoder.

namespace {

// The closed mesh: real triangles, then one virtual triangle (b, a, virtual) per border edge
// a -> b; and each half-edge's triangle.
struct ClosedMesh {
  std::vector<Tri> triangles;
  std::unordered_map<uint64_t, int32_t> half_edges;
};

ClosedMesh close_mesh(const ControlMesh& mesh, int32_t virt) {
  ClosedMesh closed{mesh.triangles, {}};
  closed.half_edges.reserve(closed.triangles.size() * 4);
  for (int32_t f = 0; f < static_cast<int32_t>(mesh.triangles.size()); ++f)
    for (int k = 0; k < 3; ++k) closed.half_edges[key(closed.triangles[f][k], closed.triangles[f][(k + 1) % 3])] = f;
  for (int32_t f = 0; f < static_cast<int32_t>(mesh.triangles.size()); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int32_t a = mesh.triangles[f][k], b = mesh.triangles[f][(k + 1) % 3];
      if (closed.half_edges.count(key(b, a))) continue;
      const auto g = static_cast<int32_t>(closed.triangles.size());
      closed.triangles.push_back({b, a, virt});
      closed.half_edges[key(b, a)] = g;
      closed.half_edges[key(a, virt)] = g;
      closed.half_edges[key(virt, b)] = g;
    }
  }
  return closed;
}

// The encoder's traversal in the original numbering: each vertex's decode number (`code`), the
// operations with their contexts and split codes, the visited faces (u, w, x) and each vertex's
// basis (u, w, apex) when it was met.
struct EncoderTraversal {
  std::vector<int32_t> code;
  std::vector<uint8_t> ops;
  std::vector<OpContext> op_contexts;
  std::vector<uint64_t> splits;
  std::vector<Tri> faces;
  std::vector<std::array<int32_t, 3>> basis;
};

// Traverses the closed mesh from its triangle 0, numbering vertices as they are met.
EncoderTraversal traverse(const ClosedMesh& closed, int32_t nv) {
  const int32_t virt = nv;
  EncoderTraversal e;
  e.code.assign(size_t(nv) + 1, -1);
  std::vector<char> visited(closed.triangles.size(), 0);
  std::vector<int32_t> visits(size_t(nv) + 1, 0);  // visited triangles per (original) vertex
  const Tri seed = closed.triangles[0];
  for (int k = 0; k < 3; ++k) {
    e.code[seed[k]] = k;
    e.basis.push_back({-1, -1, -1});
    visits[seed[k]] = 1;
  }
  visited[0] = 1;
  e.faces = {seed};
  Frontier front(seed[0], seed[1], seed[2]);
  for (;;) {
    const int32_t u = front.u(), w = front.w();
    const auto it = closed.half_edges.find(key(u, w));
    if (it == closed.half_edges.end() || visited[it->second])
      fail("internal error: the compact encoder lost its way", ErrorCode::kInvalidMesh);
    const int32_t f = it->second;
    visited[f] = 1;
    const Tri& t = closed.triangles[f];
    const int32_t x = t[0] != u && t[0] != w ? t[0] : t[1] != u && t[1] != w ? t[1] : t[2];
    e.faces.push_back({u, w, x});
    e.op_contexts.push_back(
        {front.size() == 3, fan_bucket(u, virt, visits), fan_bucket(w, virt, visits)});
    for (const int32_t v : {u, w, x}) ++visits[v];
    bool last = false;
    if (e.code[x] < 0) {
      e.code[x] = static_cast<int32_t>(e.basis.size());
      e.basis.push_back({u, w, front.gate_apex()});
      e.ops.push_back(kOpC);
      front.add_vertex(x);
    } else if (front.size() == 3) {
      e.ops.push_back(kOpE);
      last = !front.close_loop();
    } else if (front.after_w() == x) {
      e.ops.push_back(kOpR);
      front.close_right();
    } else if (front.before_u() == x) {
      e.ops.push_back(kOpL);
      front.close_left();
    } else {
      const int64_t pos = front.find(x);
      if (pos < 3 || pos > front.size() - 2)
        fail("internal error: the compact encoder lost its way", ErrorCode::kInvalidMesh);
      e.ops.push_back(kOpS);
      e.splits.push_back(split_code(pos, front.size()));
      front.split(pos);
    }
    if (last) break;
  }
  if (e.faces.size() != closed.triangles.size() || e.basis.size() != size_t(nv) + 1)
    fail("internal error: the mesh is not a disk", ErrorCode::kInvalidMesh);
  return e;
}

// The traversal in decode numbering.
Traversal decode_numbering(const EncoderTraversal& e, int32_t virt) {
  Traversal tr;
  tr.virtual_vertex = e.code[virt];
  auto dc = [&](int32_t v) { return v < 0 ? -1 : e.code[v]; };
  for (size_t f = 0; f < e.faces.size(); ++f) {
    tr.faces.push_back({dc(e.faces[f][0]), dc(e.faces[f][1]), dc(e.faces[f][2])});
  }
  for (const auto& b : e.basis) tr.vertex_basis.push_back({dc(b[0]), dc(b[1]), dc(b[2])});
  return tr;
}

// 1-2. Connectivity (the seed is implicit; 2V - 3 operations), the virtual vertex first and each
// S's offset after it.
void encode_connectivity(const EncoderTraversal& e, const Traversal& tr, SymbolSink& sink) {
  sink.virtual_vertex(uint64_t(tr.virtual_vertex));
  size_t s = 0;
  for (size_t i = 0; i < e.ops.size(); ++i) {
    sink.op(e.ops[i], e.op_contexts[i]);
    if (e.ops[i] == kOpS) sink.split(e.splits[s++]);
  }
}

// 3. Positions on the grid, in decode order (returned, indexed by decode number).
std::vector<Point> encode_positions(const ControlMesh& mesh, const EncoderTraversal& e, const Traversal& tr,
                                    int width, int height, int position_bits, SymbolSink& sink) {
  const size_t n_decode = tr.vertex_basis.size();
  std::vector<Point> p(n_decode, Point{0, 0});
  for (int32_t v = 0; v < mesh.num_vertices(); ++v) {
    p[e.code[v]] = {to_grid(mesh.positions[v].x, position_bits),
                    to_grid(mesh.positions[v].y, position_bits)};
  }
  const Point max = {int64_t{width} << position_bits, int64_t{height} << position_bits};
  Point previous{0, 0};
  const PositionPredictor predictor(tr);
  for (size_t d = 0; d < n_decode; ++d) {
    if (int32_t(d) == tr.virtual_vertex) continue;
    const Point q = predictor.predict(int32_t(d), p, previous, max);
    sink.position(p[d][0] - q[0], p[d][1] - q[1]);
    previous = p[d];
  }
  return p;
}

// 4. Creases and features of the canonical mesh m, steps ranked on its grid positions fp.
void encode_features(const ControlMesh& m, const std::vector<Point>& fp, SymbolSink& sink) {
  const Neighbors nb = neighbors(m.triangles, m.positions.size());
  for (const EdgeVerts& e : m.creases) {
    sink.vertex(uint64_t(e[0]));
    sink.step(uint64_t(rank_of(ranked_steps(nb, fp, -1, e[0]), e[1])), true);
  }
  int64_t previous_id = -1;
  for (const Feature& f : m.features) {
    sink.feature(int64_t{f.id} - previous_id - 1, f.saliency, f.vertices.size() - 2);
    previous_id = f.id;
    sink.vertex(uint64_t(f.vertices[0]));
    for (size_t i = 1; i < f.vertices.size(); ++i) {
      const int32_t from = i >= 2 ? f.vertices[i - 2] : -1;
      sink.step(uint64_t(rank_of(ranked_steps(nb, fp, from, f.vertices[i - 1]), f.vertices[i])),
                i == 1);
    }
  }
}

// Colors are floats: a grid value survives the read (k * 2^-c as a float) only while |k| <= 2^24.
// Colors up to 2^23 grid steps leave room for the error diffusion, so every value read back lies
// exactly on the grid and a second write gives the same bytes. (At 2^44 steps, a color of 2^27 at
// quarter steps came back rounded, and its neighbors moved; the fuzzer found it.) Larger colors
// (a filter's 1e6, a hand-written 3e38, valid in the model) are refused; the lossless form keeps
// them.
void check_color_range(const ControlMesh& mesh, int color_bits) {
  const double max_color = std::ldexp(1.0, 23 - color_bits);
  for (const Color& color : mesh.colors) {
    for (const float v : {color.r, color.g, color.b}) {
      if (!(std::abs(double(v)) <= max_color)) {
        char text[96];
        std::snprintf(text, sizeof text, "color value %g is too large for the compact .svec form",
                      double(v));
        throw Error(ErrorCode::kInvalidArgument,
                    std::string(text) + " (at most " + str(uint64_t(max_color)) +
                        " in magnitude; .svec.json or convert --lossless keep it)");
      }
    }
  }
}

// Color targets on the grid scale, in the canonical face-varying order fv of m.
std::vector<std::array<double, 3>> color_targets(const ControlMesh& mesh, const ControlMesh& m,
                                                 const ClosedMesh& closed, const EncoderTraversal& e,
                                                 const std::vector<Tri>& fv, int num_colors, int color_bits) {
  const int32_t virt = mesh.num_vertices();
  std::vector<std::array<double, 3>> target(num_colors);
  std::vector<int32_t> origin(mesh.triangles.size());  // canonical triangle -> visited face
  int32_t t = 0;
  for (size_t f = 0; f < e.faces.size(); ++f)
    if (e.faces[f][0] != virt && e.faces[f][1] != virt && e.faces[f][2] != virt) origin[t++] = int32_t(f);
  for (t = 0; t < m.num_triangles(); ++t) {
    const Tri& orig_face = e.faces[origin[t]];  // (u, w, x) in original vertex numbers
    const int32_t of = closed.half_edges.at(key(orig_face[0], orig_face[1]));
    for (int k = 0; k < 3; ++k) {
      int j = 0;
      while (mesh.triangles[of][j] != orig_face[k]) ++j;
      const Color& col = mesh.colors[mesh.triangle_colors[of][j]];
      target[fv[t][k]] = {std::ldexp(double(col.r), color_bits),
                          std::ldexp(double(col.g), color_bits),
                          std::ldexp(double(col.b), color_bits)};
    }
  }
  return target;
}

// 5. Colors, in index order (the order of first use). Each one's rounding error is taken off the
// targets of its neighbors still to come (error diffusion), so that nearby errors cancel: the
// rendered color is a local average of control colors, and moves less than the values themselves.
void encode_colors(const std::vector<Tri>& fv, int num_colors, std::vector<std::array<double, 3>> target,
                   int color_bits, SymbolSink& sink) {
  const Neighbors cadj = neighbors(fv, size_t(num_colors));
  std::vector<Rgb> colors(num_colors), color_activity(num_colors);
  std::vector<char> known(num_colors, 0);
  const int64_t mid = to_grid(128.0, color_bits);
  Rgb last{mid, mid, mid};
  for (int32_t ci = 0; ci < num_colors; ++ci) {
    const Rgb q = predict_color(cadj.of(ci), known, colors, last);
    Rgb d;
    for (int ch = 0; ch < 3; ++ch) {
      colors[ci][ch] = std::llround(target[ci][ch]);
      d[ch] = colors[ci][ch] - q[ch];
    }
    int later = 0;
    for (const int32_t j : cadj.of(ci)) later += j > ci;
    if (later > 0) {
      for (int ch = 0; ch < 3; ++ch) {
        const double error = double(colors[ci][ch]) - target[ci][ch];
        for (const int32_t j : cadj.of(ci))
          if (j > ci) target[j][ch] -= error / later;
      }
    }
    // The residual as green, red - green, blue - green: in photographs most of a local change is
    // in luminance, common to the three channels.
    const Rgb coded_d = {d[1], d[0] - d[1], d[2] - d[1]};
    sink.color(coded_d, color_context(cadj.of(ci), known, color_activity));
    for (int ch = 0; ch < 3; ++ch) color_activity[ci][ch] = capped(coded_d[ch]);
    known[ci] = 1;
    last = colors[ci];
  }
}

}  // namespace

void encode_compact_level(const ControlMesh& mesh, int width, int height, int position_bits,
                          int color_bits, int version, ByteWriter& out,
                          std::vector<size_t>& block_ends, std::vector<int32_t>* vertex_order) {
  const int32_t nv = mesh.num_vertices(), virt = nv;
  const ClosedMesh closed = close_mesh(mesh, virt);
  const EncoderTraversal e = traverse(closed, nv);
  const Traversal tr = decode_numbering(e, virt);
  Canonical c = make_canonical(tr, nv);
  std::vector<int32_t> final_of(nv);
  for (int32_t v = 0; v < nv; ++v) final_of[v] = c.final_index[e.code[v]];
  if (vertex_order) *vertex_order = final_of;
  ControlMesh& m = c.mesh;
  m.positions.resize(nv);
  for (int32_t v = 0; v < nv; ++v) m.positions[final_of[v]] = mesh.positions[v];
  for (const EdgeVerts& edge : mesh.creases) m.creases.push_back({final_of[edge[0]], final_of[edge[1]]});
  for (const Feature& f : mesh.features) {
    Feature g = f;
    for (int32_t& v : g.vertices) v = final_of[v];
    m.features.push_back(g);
  }

  Models models;
  VarintSink varints;
  RangeSink coded(models, nv);
  SymbolSink& sink = version == 2 ? static_cast<SymbolSink&>(varints) : coded;
  encode_connectivity(e, tr, sink);
  const std::vector<Point> p = encode_positions(mesh, e, tr, width, height, position_bits, sink);
  // Prediction works on final vertex numbers with positions on the grid.
  std::vector<Point> fp(nv);
  for (int32_t v = 0; v < nv; ++v) fp[v] = p[c.decode_index[v]];
  encode_features(m, fp, sink);

  const MeshTopology topo = MeshTopology::build(m, width, height);
  int num_colors = 0;
  const std::vector<Tri> fv = face_varying_indices(m, topo, num_colors);
  check_color_range(mesh, color_bits);
  encode_colors(fv, num_colors, color_targets(mesh, m, closed, e, fv, num_colors, color_bits), color_bits, sink);
  sink.finish(out, block_ends);
}

// ---------------------------------------------------------------------------------------------
// Decoder.

namespace {

// What a level declares before its symbols.
struct LevelCounts {
  size_t vertices = 0, colors = 0, triangles = 0, creases = 0, features = 0;
  int position_bits = 0, color_bits = 0;
};

LevelCounts read_counts(Cursor& in, const std::string& name) {
  LevelCounts n;
  in.set_context(name + "counts");
  n.vertices = in.count(name + "vertices", 0);
  n.colors = in.count(name + "colors", 0);
  n.triangles = in.count(name + "triangles", 0);
  n.creases = in.count(name + "creases", 0);
  n.features = in.count(name + "features", 0);
  in.set_context(name + "precision");
  n.position_bits = in.u8(), n.color_bits = static_cast<int8_t>(in.u8());
  if (n.position_bits > kMaxPositionBits || n.color_bits < kMinColorBits ||
      n.color_bits > kMaxColorBits) {
    fail(name + "precision: position bits " + std::to_string(n.position_bits) + ", color bits " +
         std::to_string(n.color_bits) + " (expected 0 to " + std::to_string(kMaxPositionBits) +
         " and " + std::to_string(kMinColorBits) + " to " + std::to_string(kMaxColorBits) + ")");
  }
  if (n.vertices < 3) fail(name + "vertices: " + str(n.vertices) + " (a level has at least 3)");
  return n;
}

// 1-2. Connectivity: 2V - 3 operations after the seed.
Traversal decode_connectivity(SymbolSource& src, size_t nv, const std::string& name) {
  auto corrupt = [&](const std::string& what) { fail(name + "connectivity: " + what); };
  const size_t num_ops = 2 * nv - 3;
  src.begin(kConnectivity);
  src.begin(kSplits);
  const uint64_t virt64 = src.virtual_vertex();
  if (virt64 < 3 || virt64 > nv) corrupt("virtual vertex " + str(virt64) + " out of range");
  Traversal tr;
  tr.virtual_vertex = static_cast<int32_t>(virt64);
  const int32_t virt = tr.virtual_vertex;
  for (int k = 0; k < 3; ++k) tr.vertex_basis.push_back({-1, -1, -1});
  tr.faces.push_back({0, 1, 2});
  std::vector<int32_t> visits = {1, 1, 1};  // visited triangles per decode number
  Frontier front(0, 1, 2);
  bool done = false;
  for (size_t i = 0; i < num_ops; ++i) {
    if (done) corrupt("the traversal ends before the last operation");
    const int32_t u = front.u(), w = front.w();
    const int op =
        src.op({front.size() == 3, fan_bucket(u, virt, visits), fan_bucket(w, virt, visits)});
    int32_t x = -1;
    if (op == kOpC) {
      if (tr.vertex_basis.size() > nv) corrupt("more vertices than the " + str(nv) + " declared");
      x = static_cast<int32_t>(tr.vertex_basis.size());
      tr.vertex_basis.push_back({u, w, front.gate_apex()});
      visits.push_back(0);
      front.add_vertex(x);
    } else if (op == kOpE) {
      if (front.size() != 3) corrupt("operation " + str(i) + " closes a loop of " +
                                     str(uint64_t(front.size())) + " edges");
      x = front.after_w();
      done = !front.close_loop();
    } else if (op == kOpR || op == kOpL) {
      if (front.size() <= 3) corrupt("operation " + str(i) + " on a loop of 3 edges");
      x = op == kOpR ? front.after_w() : front.before_u();
      op == kOpR ? front.close_right() : front.close_left();
    } else {
      const int64_t pos = split_position(src.split(), front.size());
      if (pos < 3 || pos > front.size() - 2) corrupt("split offset out of range");
      x = front.vertex_at(pos);
      front.split(pos);
    }
    if (x == u || x == w) corrupt("operation " + str(i) + " makes a degenerate triangle");
    for (const int32_t v : {u, w, x}) ++visits[v];
    tr.faces.push_back({u, w, x});
  }
  if (!done) corrupt("the traversal leaves triangles unvisited");
  if (tr.vertex_basis.size() != nv + 1) {
    corrupt(str(tr.vertex_basis.size() - 1) + " vertices, but " + str(nv) + " are declared");
  }
  src.end(kConnectivity);
  src.end(kSplits);
  return tr;
}

// 3. Positions on the grid, indexed by decode number.
std::vector<Point> decode_positions(SymbolSource& src, const Traversal& tr, size_t nv, int width, int height,
                                    int position_bits, const std::string& name) {
  src.begin(kPositions);
  std::vector<Point> p(nv + 1, Point{0, 0});
  const Point max = {int64_t{width} << position_bits, int64_t{height} << position_bits};
  constexpr int64_t kLimit = int64_t{1} << 40;
  Point previous{0, 0};
  const PositionPredictor predictor(tr);
  for (size_t d = 0; d < nv + 1; ++d) {
    if (int32_t(d) == tr.virtual_vertex) continue;
    const Point q = predictor.predict(int32_t(d), p, previous, max);
    const std::array<int64_t, 2> r = src.position();
    for (int k = 0; k < 2; ++k) {
      if (r[k] < -kLimit || r[k] > kLimit) fail(name + "positions: residual out of range");
      p[d][k] = q[k] + r[k];
    }
    previous = p[d];
  }
  src.end(kPositions);
  return p;
}

// 4. Creases and features of m, steps ranked on its grid positions fp.
void decode_features(SymbolSource& src, const LevelCounts& counts, const std::vector<Point>& fp,
                     const std::string& name, ControlMesh& m) {
  const size_t nv = counts.vertices;
  src.begin(kFeatures);
  src.begin(kSteps);
  const Neighbors nb = neighbors(m.triangles, m.positions.size());
  auto vertex = [&](uint64_t v, const std::string& what) {
    if (v >= nv) fail(name + what + ": vertex " + str(v) + " out of range");
    return static_cast<int32_t>(v);
  };
  auto step = [&](int32_t from, int32_t at, bool first, const std::string& what) {
    const std::vector<int32_t> ranked = ranked_steps(nb, fp, from, at);
    const uint64_t r = src.step(first);
    if (r >= ranked.size()) fail(name + what + ": step " + str(r) + " out of range");
    return ranked[r];
  };
  for (size_t i = 0; i < counts.creases; ++i) {
    const std::string what = "crease " + str(i);
    const int32_t a = vertex(src.vertex(), what);
    m.creases.push_back({a, step(-1, a, true, what)});
  }
  int64_t previous_id = -1;
  for (size_t i = 0; i < counts.features; ++i) {
    const std::string what = "feature " + str(i);
    Feature f;
    const int64_t id = previous_id + 1 + src.feature_id(what);
    if (id < INT32_MIN || id > INT32_MAX) fail(name + what + ": id out of range");
    f.id = static_cast<int32_t>(id);
    previous_id = id;
    f.saliency = src.saliency(what);
    const uint64_t n = src.feature_length(what);
    if (n > nv) fail(name + what + ": " + str(n + 2) + " vertices, more than the level has");
    f.vertices.push_back(vertex(src.vertex(), what));
    for (uint64_t k = 0; k <= n; ++k) {
      const int32_t from = f.vertices.size() >= 2 ? f.vertices[f.vertices.size() - 2] : -1;
      f.vertices.push_back(step(from, f.vertices.back(), k == 0, what));
    }
    m.features.push_back(std::move(f));
  }
  src.end(kFeatures);
  src.end(kSteps);
}

// 5. Colors: the face-varying indices from the tears, then the values in index order.
void decode_colors(SymbolSource& src, const LevelCounts& counts, int width, int height, const std::string& name,
                   ControlMesh& m) {
  const int color_bits = counts.color_bits;
  src.begin(kColors);
  const MeshTopology topo = MeshTopology::build(m, width, height);
  int nc = 0;
  m.triangle_colors = face_varying_indices(m, topo, nc);
  if (size_t(nc) != counts.colors) {
    fail(name + "colors: the tears give " + str(uint64_t(nc)) + " color values, but " +
         str(counts.colors) + " are declared");
  }
  std::vector<Rgb> colors(nc), color_activity(nc);
  const Neighbors cadj = neighbors(m.triangle_colors, size_t(nc));
  std::vector<char> known(nc, 0);
  const int64_t mid = to_grid(128.0, color_bits);
  Rgb last{mid, mid, mid};
  constexpr int64_t kColorLimit = int64_t{1} << 48;
  constexpr int64_t kColorValueLimit = int64_t{1} << 24;
  for (int32_t ci = 0; ci < nc; ++ci) {
    const Rgb q = predict_color(cadj.of(ci), known, colors, last);
    Rgb d = src.color(color_context(cadj.of(ci), known, color_activity));
    for (int ch = 0; ch < 3; ++ch) {
      if (d[ch] < -kColorLimit || d[ch] > kColorLimit) fail(name + "colors: residual out of range");
      color_activity[ci][ch] = capped(d[ch]);
    }
    d = {d[1] + d[0], d[0], d[2] + d[0]};
    for (int ch = 0; ch < 3; ++ch) {
      colors[ci][ch] = q[ch] + d[ch];
      // A float holds grid values up to 2^24 exactly; the writer stays below 2^23 plus its error
      // diffusion (check_color_range).
      if (std::abs(colors[ci][ch]) > kColorValueLimit) fail(name + "colors: value out of range");
    }
    known[ci] = 1;
    last = colors[ci];
  }
  src.end(kColors);
  src.finish();
  m.colors.resize(nc);
  for (int32_t i = 0; i < nc; ++i) {
    m.colors[i] = {static_cast<float>(from_grid(colors[i][0], color_bits)),
                   static_cast<float>(from_grid(colors[i][1], color_bits)),
                   static_cast<float>(from_grid(colors[i][2], color_bits))};
  }
}

}  // namespace

ControlMesh decode_compact_level(Cursor& in, int level, int width, int height, int version) {
  const std::string name = "level " + str(uint64_t(level)) + " ";
  const LevelCounts counts = read_counts(in, name);
  const size_t nv = counts.vertices;

  Models models;
  std::unique_ptr<SymbolSource> source;
  if (version == 2) {
    source = std::make_unique<VarintSource>(in, name, nv);
  } else {
    const std::string label = name + "stream";
    const size_t n = in.count(label, 1, Limits::kMaxElements * 64);
    in.set_context(label);
    source = std::make_unique<RangeSource>(std::span<const uint8_t>(in.take(n), n), name, models, nv);
  }
  SymbolSource& src = *source;

  const Traversal tr = decode_connectivity(src, nv, name);
  Canonical c = make_canonical(tr, static_cast<int>(nv));
  ControlMesh& m = c.mesh;
  if (size_t(m.num_triangles()) != counts.triangles) {
    fail(name + "connectivity: " + str(uint64_t(m.num_triangles())) + " triangles, but " +
         str(counts.triangles) + " are declared");
  }
  const std::vector<Point> p = decode_positions(src, tr, nv, width, height, counts.position_bits, name);
  m.positions.resize(nv);
  std::vector<Point> fp(nv);
  for (size_t v = 0; v < nv; ++v) {
    fp[v] = p[c.decode_index[v]];
    m.positions[v] = {from_grid(fp[v][0], counts.position_bits), from_grid(fp[v][1], counts.position_bits)};
  }
  decode_features(src, counts, fp, name, m);
  decode_colors(src, counts, width, height, name, m);
  return std::move(c.mesh);
}

}  // namespace subvec::svec_detail
