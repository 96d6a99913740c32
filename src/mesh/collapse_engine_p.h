// The one collapse engine of the library (paper §4 and §5), shared by the simplification of
// vectorization (vectorize/simplify.cpp) and the coarsening between levels (mesh/coarsen.cpp,
// vectorize/levels.cpp, replayed by pyramid/): the lazy queue that orders collapses cheapest first,
// the per-vertex lists of incident faces, the feature chains (chains_p.h), the collapse applied to
// them (collapse_incidence), the greedy loop (run_collapses) and the renumbered mesh it leaves
// (live_mesh). What a collapse may do and how it changes the faces and colors is collapse_p.h;
// what it costs is the 5D quadric of quadric_p.h (color_quadrics).
//
// Design note. The two users differ only in their policies: the simplification places the kept
// vertex at the best point of the edge and refits the chain around a removed tear vertex (eq. 1),
// region by region in parallel; the levels make half-edge collapses (the kept vertex stays, so
// the pyramid can predict the removed one from its neighbours) and keep chains within a distance
// of where the step began.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cstdint>
#include <cstring>
#include <memory>
#include <span>
#include <vector>

#include "core/cancel_p.h"
#include "mesh/chains_p.h"
#include "mesh/collapse_p.h"
#include "subvec/mesh/vector_image.h"

namespace subvec::detail {
// A 4-ary min-heap: the four children of a node share one cache line (16-byte entries, the
// array offset by three slots so that every group of four siblings starts on a 64-byte boundary),
// which halves the depth and the cache misses of a binary heap; the lazy collapse queue is
// dominated by them.
template <class T>
class QuadHeap {
  static_assert(sizeof(T) == 16);
  static constexpr size_t kPad = 3;

 public:
  bool empty() const { return size_ == 0; }
  size_t size() const { return size_; }
  const T& top() const { return at(0); }
  void clear() { size_ = 0; }
  void push(const T& x) {
    if (size_ == capacity_) grow();
    size_t i = size_++;
    while (i > 0) {
      const size_t parent = (i - 1) / 4;
      if (!(x < at(parent))) break;
      at(i) = at(parent);
      i = parent;
    }
    at(i) = x;
  }
  void pop() {
    const T x = at(--size_);
    if (size_ == 0) return;
    const size_t n = size_;
    size_t i = 0;
    while (true) {
      const size_t first = 4 * i + 1;
      if (first >= n) break;
      size_t best = first;
      const size_t last = std::min(first + 4, n);
      for (size_t c = first + 1; c < last; ++c)
        if (at(c) < at(best)) best = c;
      if (!(at(best) < x)) break;
      at(i) = at(best);
      i = best;
    }
    at(i) = x;
  }

 private:
  struct alignas(64) Line {
    unsigned char bytes[64];
  };
  T& at(size_t i) { return reinterpret_cast<T*>(storage_.get())[i + kPad]; }
  const T& at(size_t i) const { return reinterpret_cast<const T*>(storage_.get())[i + kPad]; }
  void grow() {
    const size_t capacity = std::max<size_t>(1024, 2 * capacity_);
    std::unique_ptr<Line[]> storage(new Line[(capacity + kPad) * sizeof(T) / sizeof(Line) + 1]);
    if (size_) std::memcpy(reinterpret_cast<T*>(storage.get()) + kPad, &at(0), size_ * sizeof(T));
    storage_ = std::move(storage);
    capacity_ = capacity;
  }
  std::unique_ptr<Line[]> storage_;
  size_t size_ = 0, capacity_ = 0;
};

// A queue entry: the collapse of `remove` into `keep`, planned when the two vertices had these
// versions. 16 bytes. Ordered by cost, then the removed and the kept vertex (determinism); the cost
// is a non-negative float, so its bits order like the value and cost and removed vertex compare as
// one 64-bit key. Versions are truncated: an entry that survives a wrap-around is still fully
// re-planned and checked before it collapses anything.
struct Entry {
  uint64_t key;  // cost bits << 32 | remove
  int32_t keep;
  uint16_t version_remove, version_keep;
  int32_t remove() const { return static_cast<int32_t>(key & 0xffffffffu); }
  bool operator<(const Entry& o) const { return key != o.key ? key < o.key : keep < o.keep; }
};

// The entry for removing `remove` into `keep` at `cost` (>= 0, finite), planned at these versions.
inline Entry make_entry(double cost, int32_t remove, int32_t keep, uint32_t version_remove, uint32_t version_keep) {
  const uint64_t cost_bits = std::bit_cast<uint32_t>(static_cast<float>(cost));
  return {cost_bits << 32 | static_cast<uint32_t>(remove), keep, static_cast<uint16_t>(version_remove),
          static_cast<uint16_t>(version_keep)};
}

// Whether an entry is current: both vertices alive, neither changed since it was planned.
template <class Alive, class Versions>
bool entry_live(const Entry& e, const Alive& alive, const Versions& version) {
  const int32_t remove = e.remove();
  return alive[remove] && alive[e.keep] && static_cast<uint16_t>(version[remove]) == e.version_remove &&
         static_cast<uint16_t>(version[e.keep]) == e.version_keep;
}

// The lazy collapse queue: entries are never updated in place; a re-planned edge gets a new entry
// and the old one goes stale, to be skipped when it comes out. Most entries go stale long before
// they would reach the front, so only the front lives in a heap: entries are binned by the high
// bits of their cost (1/16 of an octave per bin), the heap holds every entry of the bins up to
// `front_`, and the bins above wait unsorted until the heap runs dry, when the next non-empty bin
// is moved into the heap with its stale entries dropped. Entries come out in exactly the order of
// one big heap, at the cost of a heap that stays small enough for the cache.
class CollapseQueue {
 public:
  size_t size() const { return size_; }
  void clear() {
    heap_.clear();
    for (auto& bin : bins_) std::vector<Entry>().swap(bin);
    front_ = 0;
    size_ = 0;
  }
  void push(const Entry& e) {
    const uint32_t b = bin(e);
    if (b <= front_) {
      heap_.push(e);
    } else {
      bins_[b].push_back(e);
    }
    ++size_;
  }
  // Takes the smallest entry into `out`; false when the queue is empty. `live(e)` says whether an
  // entry is still current; entries that are not may be dropped unseen.
  template <class Live>
  bool pop(Entry& out, const Live& live) {
    while (heap_.empty()) {
      uint32_t b = front_ + 1;
      while (b < kBins && bins_[b].empty()) ++b;
      if (b == kBins) return false;
      front_ = b;
      std::vector<Entry> entries;
      entries.swap(bins_[b]);
      for (const Entry& e : entries) {
        if (live(e)) heap_.push(e);
        else --size_;
      }
    }
    out = heap_.top();
    heap_.pop();
    --size_;
    return true;
  }

 private:
  static constexpr int kShift = 32 + 19;  // float bits above the 4 leading mantissa bits
  static constexpr uint32_t kBins = uint32_t{1} << (63 - kShift);
  static uint32_t bin(const Entry& e) { return static_cast<uint32_t>(e.key >> kShift); }
  QuadHeap<Entry> heap_;
  std::vector<std::vector<Entry>> bins_ = std::vector<std::vector<Entry>>(kBins);
  uint32_t front_ = 0;
  size_t size_ = 0;
};

// Blocks of int32 that never move, handed out in order: one per worker, so that lists can grow
// on several threads at once.
class Arena {
 public:
  int32_t* take(size_t n) {
    if (n > left_) {
      const size_t size = std::max<size_t>(n, 1 << 16);
      chunks_.push_back(std::make_unique<int32_t[]>(size));
      next_ = chunks_.back().get();
      left_ = size;
    }
    int32_t* out = next_;
    next_ += n, left_ -= n;
    return out;
  }

 private:
  std::vector<std::unique_ptr<int32_t[]>> chunks_;
  int32_t* next_ = nullptr;
  size_t left_ = 0;
};

// The faces incident to each vertex: lists laid out in vertex order in one block, each with room to
// grow; a full list moves to a block twice as large from the caller's arena. Lists keep their
// order; growing a list invalidates views of it.
class IncidenceLists {
 public:
  // `counts[v]` entries will be pushed for each vertex v first.
  void reserve(const std::vector<int32_t>& counts) {
    data_.resize(counts.size());
    size_.assign(counts.size(), 0);
    capacity_.resize(counts.size());
    size_t total = 0;
    for (size_t v = 0; v < counts.size(); ++v) {
      capacity_[v] = std::max(8, counts[v] + 2);
      total += capacity_[v];
    }
    pool_ = std::make_unique<int32_t[]>(total);
    total = 0;
    for (size_t v = 0; v < counts.size(); ++v) data_[v] = pool_.get() + total, total += capacity_[v];
  }
  std::span<const int32_t> operator[](int32_t v) const { return {data_[v], size_t(size_[v])}; }
  void push_back(int32_t v, int32_t f, Arena& arena) {
    if (size_[v] == capacity_[v]) {
      int32_t* data = arena.take(2 * size_t(capacity_[v]));
      std::copy_n(data_[v], size_[v], data);
      data_[v] = data;
      capacity_[v] *= 2;
    }
    data_[v][size_[v]++] = f;
  }
  void erase(int32_t v, int32_t f) {
    int32_t* first = data_[v];
    int32_t* last = first + size_[v];
    int32_t* at = std::find(first, last, f);
    std::copy(at + 1, last, at);
    --size_[v];
  }
  void clear(int32_t v) { size_[v] = 0; }

 private:
  std::unique_ptr<int32_t[]> pool_;
  std::vector<int32_t*> data_;
  std::vector<int32_t> size_, capacity_;
};

// The half-edge collapse of u into v on the engine's storage: collapse_faces (collapse_p.h) with
// the faces on the edge dying and leaving their vertices' lists, u's other faces joining v's list
// (growing from `arena`), and u dead. `scratch` holds a copy of u's list while they change.
inline void collapse_incidence(int32_t u, int32_t v, const std::array<std::array<int32_t, 2>, 2>& pairs, int npairs,
                               std::vector<Tri>& tri, std::vector<Tri>& tcol, IncidenceLists& vfaces,
                               std::vector<uint8_t>& face_alive, std::vector<uint8_t>& vertex_alive, Arena& arena,
                               std::vector<int32_t>& scratch) {
  scratch.assign(vfaces[u].begin(), vfaces[u].end());
  collapse_faces(
      scratch, tri, tcol, u, v, pairs, npairs,
      [&](int32_t f) {
        face_alive[f] = 0;
        for (int32_t w : tri[f])
          if (w != u) vfaces.erase(w, f);
      },
      [&](int32_t f) { vfaces.push_back(v, f, arena); });
  vfaces.clear(u);
  vertex_alive[u] = 0;
}

// The live mesh, renumbered: live vertices in ascending order (`vmap`: each vertex's new index, -1
// when dead), live faces in `face_order` (every face index once), color values numbered by first
// use (`used`: each new color's value, `color(value, vertex)` its Color), the creases and the
// chains.
template <class ColorOf>
ControlMesh live_mesh(const std::vector<Vec2>& pos, const std::vector<uint8_t>& vertex_alive, const std::vector<Tri>& tri,
                      const std::vector<Tri>& tcol, const std::vector<uint8_t>& face_alive,
                      std::span<const int32_t> face_order, int num_colors, const std::vector<EdgeVerts>& creases,
                      const FeatureChains& chains, const ColorOf& color, std::vector<int32_t>& vmap,
                      std::vector<int32_t>& used) {
  ControlMesh out;
  vmap.assign(pos.size(), -1);
  used.clear();
  std::vector<int32_t> cmap(num_colors, -1);
  for (size_t v = 0; v < pos.size(); ++v) {
    if (!vertex_alive[v]) continue;
    vmap[v] = out.num_vertices();
    out.positions.push_back(pos[v]);
  }
  for (const int32_t f : face_order) {
    if (!face_alive[f]) continue;
    Tri t, c;
    for (int k = 0; k < 3; ++k) {
      t[k] = vmap[tri[f][k]];
      int32_t& ci = cmap[tcol[f][k]];
      if (ci < 0) {
        ci = out.num_colors();
        out.colors.push_back(color(tcol[f][k], tri[f][k]));
        used.push_back(tcol[f][k]);
      }
      c[k] = ci;
    }
    out.triangles.push_back(t);
    out.triangle_colors.push_back(c);
  }
  for (const EdgeVerts& e : creases)
    if (vmap[e[0]] >= 0 && vmap[e[1]] >= 0) out.creases.push_back({vmap[e[0]], vmap[e[1]]});
  chains.write(vmap, out.features);
  return out;
}

// The greedy loop of both engines: entries come out cheapest first while `more()`; a stale one
// (`live(e)` false) is skipped, a live one goes to `step(e)`. The cancel flag is looked at every
// kCancelEvery entries, the first one included. Returns false when cancelled (the caller throws on
// its own thread; a worker thread must not).
inline constexpr int64_t kCancelEvery = 4096;
template <class More, class Live, class Step>
bool run_collapses(CollapseQueue& queue, const std::atomic<bool>* cancel, More&& more, Live&& live, Step&& step) {
  Entry e;
  for (int64_t popped = 0; more(); ++popped) {
    if (popped % kCancelEvery == 0 && cancelled(cancel)) return false;  // before taking an entry
    if (!queue.pop(e, live)) break;
    if (!live(e)) continue;
    step(e);
  }
  return true;
}

}  // namespace subvec::detail
