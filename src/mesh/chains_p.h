// The feature chains of the collapse engine, shared by the simplification (vectorize/simplify.cpp)
// and the coarsening between levels (mesh/coarsen.cpp): each feature a doubly linked list of nodes,
// so that removing a vertex and visiting its neighbourhood along the chain cost O(1) whatever the
// feature's length, with the chain's initial positions kept as the target it must stay near.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <numeric>
#include <vector>

#include "mesh/collapse_p.h"
#include "subvec/mesh/vector_image.h"

namespace subvec::detail {

struct ChainNode {
  int32_t vertex = -1;
  int32_t prev = -1, next = -1;  // -1 at the ends of an open chain
  double param = 0;              // position along the initial chain, in target indices
  bool alive = true;
};

struct Chain {
  int32_t head = -1;         // first node (any node of a closed chain)
  int32_t size = 0;          // live nodes
  std::vector<Vec2> target;  // the chain's initial positions (the detected polyline)
  bool closed = false;
  int32_t id = 0;
  double saliency = 0;
};

class FeatureChains {
 public:
  // Chains for `features` over vertices at `pos`. A vertex of kind kTear inside a chain (not the
  // end of an open one) gets a node that collapses may remove; every other chain vertex is a
  // corner of the chain. A kTear vertex left without a node (the end of an open chain) becomes a
  // kCorner in `kind`.
  void build(const std::vector<Feature>& features, const std::vector<Vec2>& pos, std::vector<VertexKind>& kind) {
    const int32_t nv = static_cast<int32_t>(pos.size());
    chain_of.assign(nv, -1);
    node_of.assign(nv, -1);
    for (const Feature& f : features) {
      Chain c;
      c.id = f.id;
      c.saliency = f.saliency;
      c.closed = f.closed();
      const int32_t n = static_cast<int32_t>(f.vertices.size()) - (c.closed ? 1 : 0);
      const int32_t first = static_cast<int32_t>(nodes.size());
      c.head = first;
      c.size = n;
      for (int32_t i = 0; i < n; ++i) {
        const int32_t v = f.vertices[i];
        ChainNode node{v, i > 0 ? first + i - 1 : (c.closed ? first + n - 1 : -1),
                       i + 1 < n ? first + i + 1 : (c.closed ? first : -1), static_cast<double>(i), true};
        c.target.push_back(pos[v]);
        const bool end = !c.closed && (i == 0 || i + 1 == n);
        if (kind[v] == VertexKind::kTear && !end) {
          chain_of[v] = static_cast<int32_t>(chains.size());
          node_of[v] = static_cast<int32_t>(nodes.size());
        }
        nodes.push_back(node);
      }
      chains.push_back(std::move(c));
    }
    for (int32_t v = 0; v < nv; ++v)
      if (kind[v] == VertexKind::kTear && node_of[v] < 0) kind[v] = VertexKind::kCorner;
    // Chain nodes at other vertices (a corner may end or join several chains), for tear_edge().
    corner_offsets.assign(size_t(nv) + 1, 0);
    for (const ChainNode& n : nodes)
      if (node_of[n.vertex] < 0) ++corner_offsets[n.vertex + 1];
    std::partial_sum(corner_offsets.begin(), corner_offsets.end(), corner_offsets.begin());
    corner_nodes.resize(corner_offsets.back());
    std::vector<int32_t> fill(corner_offsets.begin(), corner_offsets.end() - 1);
    for (int32_t i = 0; i < static_cast<int32_t>(nodes.size()); ++i)
      if (node_of[nodes[i].vertex] < 0) corner_nodes[fill[nodes[i].vertex]++] = i;
  }

  // Whether (a, b) is a tear edge: consecutive in a chain.
  bool tear_edge(int32_t a, int32_t b) const {
    if (node_of[a] >= 0) return linked(node_of[a], b);
    if (node_of[b] >= 0) return linked(node_of[b], a);
    for (int32_t i = corner_offsets[a]; i < corner_offsets[a + 1]; ++i)
      if (linked(corner_nodes[i], b)) return true;
    return false;
  }
  // Whether v is next to the tear vertex u on u's chain.
  bool chain_neighbour(int32_t u, int32_t v) const { return node_of[u] >= 0 && linked(node_of[u], v); }

  // Removes the node of the tear vertex u; its two chain edges become one. Safe while other
  // threads unlink nodes of the same (open) chain elsewhere.
  void unlink(int32_t u) {
    const int32_t removed = node_of[u];
    ChainNode& n = nodes[removed];
    Chain& c = chains[chain_of[u]];
    if (n.prev >= 0) nodes[n.prev].next = n.next;
    if (n.next >= 0) nodes[n.next].prev = n.prev;
    if (c.head == removed) c.head = n.next;
    n.alive = false;
    std::atomic_ref<int32_t>(c.size).fetch_sub(1, std::memory_order_relaxed);
    node_of[u] = -1;
    chain_of[u] = -1;
  }

  // The chains as features over the vertices renumbered by `vmap`.
  void write(const std::vector<int32_t>& vmap, std::vector<Feature>& out) const {
    for (const Chain& c : chains) {
      Feature g;
      g.id = c.id;
      g.saliency = c.saliency;
      int32_t n = c.head;
      for (int32_t i = 0; i < c.size; ++i, n = nodes[n].next) g.vertices.push_back(vmap[nodes[n].vertex]);
      if (c.closed) g.vertices.push_back(g.vertices.front());
      out.push_back(std::move(g));
    }
  }

  std::vector<ChainNode> nodes;
  std::vector<Chain> chains;
  std::vector<int32_t> chain_of;  // chain of a tear vertex (one with a node), else -1
  std::vector<int32_t> node_of;   // node of a tear vertex, else -1
  std::vector<int32_t> corner_offsets, corner_nodes;  // chain nodes of the other vertices, CSR

 private:
  bool linked(int32_t node, int32_t other) const {
    const ChainNode& n = nodes[node];
    return (n.prev >= 0 && nodes[n.prev].vertex == other) || (n.next >= 0 && nodes[n.next].vertex == other);
  }
};

}  // namespace subvec::detail
