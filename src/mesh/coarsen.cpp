// The mesh state between two levels; see coarsen_p.h.
#include "mesh/coarsen_p.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/geometry_p.h"
#include "mesh/collapse_p.h"
#include "subvec/core/error.h"
#include "subvec/mesh/topology.h"

namespace subvec::coarsen_detail {

Coarsener::Coarsener(const ControlMesh& fine, int width, int height, const std::vector<int32_t>& kept_ids)
    : width_(width), height_(height) {
  ControlMesh merged;
  merged.positions = fine.positions;
  merged.triangles = fine.triangles;
  merged.triangle_colors = fine.triangle_colors;
  merged.creases = fine.creases;
  for (const Feature& f : fine.features)
    if (std::find(kept_ids.begin(), kept_ids.end(), f.id) != kept_ids.end()) merged.features.push_back(f);
  const MeshTopology topo = MeshTopology::build(merged, width, height);
  int num_merged = 0;
  tcol_ = face_varying_indices(merged, topo, num_merged);
  tri_ = fine.triangles;
  pos_ = fine.positions;
  creases_ = fine.creases;

  // Each fine color value lies in one merged wedge; the merged value is the mean of its values.
  merged_of_.assign(fine.colors.size(), -1);
  merged_.assign(num_merged, Rgb{0, 0, 0});
  std::vector<int> count(num_merged, 0);
  for (size_t f = 0; f < tri_.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int32_t c = fine.triangle_colors[f][k], m = tcol_[f][k];
      if (merged_of_[c] == m) continue;
      if (merged_of_[c] >= 0) {
        throw Error(ErrorCode::kInvalidMesh, "color " + std::to_string(c) +
                                                 " is shared by corners in separate wedges; the pyramid needs "
                                                 "one color value per wedge");
      }
      merged_of_[c] = m;
      merged_[m][0] += fine.colors[c].r, merged_[m][1] += fine.colors[c].g, merged_[m][2] += fine.colors[c].b;
      ++count[m];
    }
  }
  for (int m = 0; m < num_merged; ++m)
    for (double& x : merged_[m]) x /= std::max(count[m], 1);

  const int nv = fine.num_vertices();
  face_alive_.assign(tri_.size(), 1);
  vertex_alive_.assign(nv, 1);
  alive_count_ = nv;
  {
    std::vector<int32_t> counts(nv, 0);
    for (const Tri& t : tri_)
      for (int32_t v : t) ++counts[v];
    vfaces_.reserve(counts);
  }
  for (size_t f = 0; f < tri_.size(); ++f)
    for (int32_t v : tri_[f]) vfaces_.push_back(v, static_cast<int32_t>(f), arena_);
  marks_.mark.assign(nv, 0);
  sides_.assign(nv, 0);
  kind_.assign(nv, Kind::kSmooth);
  for (int v = 0; v < nv; ++v) {
    const Vec2 p = pos_[v];
    sides_[v] = static_cast<uint8_t>((p.x == 0 ? 1 : 0) | (p.y == 0 ? 2 : 0) | (p.x == width ? 4 : 0) |
                                     (p.y == height ? 8 : 0));
    switch (topo.vertex_tags[v]) {
      case VertexTag::kSmooth: kind_[v] = Kind::kSmooth; break;
      case VertexTag::kTear: kind_[v] = Kind::kTear; break;
      case VertexTag::kCrease: kind_[v] = sides_[v] ? Kind::kBorder : Kind::kCorner; break;
      case VertexTag::kCorner: kind_[v] = Kind::kCorner; break;
    }
  }
  chain_of_.assign(nv, -1);
  for (const Feature& f : merged.features) {
    Chain c;
    c.id = f.id;
    c.saliency = f.saliency;
    c.closed = f.closed();
    c.nodes.assign(f.vertices.begin(), f.vertices.end() - (c.closed ? 1 : 0));
    for (size_t i = 0; i < c.nodes.size(); ++i) {
      c.original.push_back(static_cast<int32_t>(i));
      c.points.push_back(pos_[c.nodes[i]]);
      if (kind_[c.nodes[i]] == Kind::kTear) chain_of_[c.nodes[i]] = static_cast<int32_t>(chains_.size());
    }
    for (size_t i = 0; i + 1 < f.vertices.size(); ++i) tear_edges_.insert(key(f.vertices[i], f.vertices[i + 1]));
    chains_.push_back(std::move(c));
  }
  // A vertex that is a tear by its edges but lies on two chains (two features meeting end to end)
  // is a chain end: keep it.
  for (int v = 0; v < nv; ++v)
    if (kind_[v] == Kind::kTear && chain_slot(v) < 0) kind_[v] = Kind::kCorner;
}

int Coarsener::chain_slot(int32_t v) const {
  const int32_t c = chain_of_[v];
  if (c < 0) return -1;
  const auto& nodes = chains_[c].nodes;
  const auto it = std::find(nodes.begin(), nodes.end(), v);
  if (it == nodes.end()) return -1;
  const int slot = static_cast<int>(it - nodes.begin());
  // An open chain's ends are corners, never tear vertices.
  if (!chains_[c].closed && (slot == 0 || slot + 1 == static_cast<int>(nodes.size()))) return -1;
  return slot;
}

void Coarsener::neighbours(int32_t v, std::vector<int32_t>& out) const {
  out.clear();
  for (int32_t f : vfaces_[v])
    for (int32_t w : tri_[f])
      if (w != v) out.push_back(w);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

int Coarsener::faces_with_edge(int32_t u, int32_t v, int32_t* out) const {
  return detail::faces_with_edge(vfaces_[u], tri_, v, out);
}

bool Coarsener::has_edge(int32_t a, int32_t b) const {
  int32_t faces[2];
  return faces_with_edge(a, b, faces) > 0;
}

bool Coarsener::sharp_edge(int32_t a, int32_t b) const {
  int32_t faces[2];
  return tear_edge(a, b) || faces_with_edge(a, b, faces) == 1;
}

int Coarsener::edge_color_pairs(int32_t u, int32_t v, std::array<std::array<int32_t, 2>, 2>& out) const {
  int32_t faces[2];
  const int nf = std::min(faces_with_edge(u, v, faces), 2);
  return detail::edge_color_pairs(faces, nf, tri_, tcol_, u, v, out);
}

bool Coarsener::can_collapse(int32_t u, int32_t v, double feature_tolerance, double min_area) const {
  if (u == v || !vertex_alive_[u] || !vertex_alive_[v]) return false;
  int32_t faces[2];
  const int nf = faces_with_edge(u, v, faces);
  if (nf < 1 || nf > 2) return false;
  const auto along_chain = [&] {
    const int slot = chain_slot(u);
    if (slot < 0) return false;
    const Chain& c = chains_[chain_of_[u]];
    const int n = static_cast<int>(c.nodes.size());
    if (c.closed && n <= 4) return false;
    const int prev = slot > 0 ? slot - 1 : n - 1, next = slot + 1 < n ? slot + 1 : 0;
    if (c.nodes[prev] != v && c.nodes[next] != v) return false;
    // The chain's points from prev to next (u's among them) must stay near the new edge.
    const Vec2 a = pos_[c.nodes[prev]], b = pos_[c.nodes[next]];
    const int np = static_cast<int>(c.points.size());
    for (int i = c.original[prev] + 1;; ++i) {
      const int j = i % np;
      if (j == c.original[next]) break;
      if (detail::segment_distance(c.points[j], a, b) > feature_tolerance) return false;
    }
    return true;
  };
  if (!detail::kinds_allow_collapse(kind_[u], kind_[v], nf, (sides_[u] & sides_[v]) != 0, along_chain)) return false;
  // Link condition: the common neighbours are exactly the faces' third vertices.
  if (!detail::link_condition(vfaces_[u], vfaces_[v], tri_, u, v, nf, marks_)) return false;
  // A dying face must not fold two sharp edges into one.
  if (detail::folds_sharp_edges(faces, nf, tri_, u, v,
                                [&](int32_t a, int32_t b) { return sharp_edge(a, b); })) {
    return false;
  }
  // No new edge between two vertices of one image side (only border edges may join them): none
  // from v to a neighbour of u but the faces' third vertices (u and v's common neighbours).
  std::vector<int32_t> nu;
  neighbours(u, nu);
  const auto third_vertex = [&](int32_t w) {
    for (int i = 0; i < nf; ++i)
      if (tri_[faces[i]][0] == w || tri_[faces[i]][1] == w || tri_[faces[i]][2] == w) return true;
    return false;
  };
  for (int32_t w : nu) {
    if (w == v || third_vertex(w)) continue;
    if ((sides_[v] & sides_[w]) != 0) return false;
  }
  // No flipped or thin triangle (u goes to v, which stays where it is).
  return detail::faces_keep_area(vfaces_[u], tri_, u, v, [&](int32_t w) { return pos_[w]; }, min_area);
}

CollapseRecord Coarsener::collapse(int32_t u, int32_t v) {
  CollapseRecord r;
  r.removed = u;
  r.kept = v;
  std::vector<int32_t> ring;
  neighbours(u, ring);
  std::array<int32_t, 2> chain_nbrs{-1, -1};
  int tear_slot = -1;
  if (kind_[u] == Kind::kTear) {
    tear_slot = chain_slot(u);
    const auto& nodes = chains_[chain_of_[u]].nodes;
    const int n = static_cast<int>(nodes.size());
    chain_nbrs = {nodes[tear_slot > 0 ? tear_slot - 1 : n - 1], nodes[tear_slot + 1 < n ? tear_slot + 1 : 0]};
    r.position_ring = {chain_nbrs[0], chain_nbrs[1]};
  } else if (kind_[u] == Kind::kBorder) {
    for (int32_t w : ring)
      if ((sides_[u] & sides_[w]) && sharp_edge(u, w) && !tear_edge(u, w)) r.position_ring.push_back(w);
  } else {
    r.position_ring = ring;
  }
  // Wedges: the corners u shares a face with, by u's color in that face. A tear vertex's sides are
  // predicted along its chain, from neighbours that are two-sided there too: a chain end whose one
  // color serves both sides would pull the jump toward zero. Failing those, from the rest of the
  // same side.
  std::array<bool, 2> one_sided{false, false};
  if (tear_slot >= 0) {
    for (int i = 0; i < 2; ++i) {
      int32_t seen = -1;
      bool single = true;
      for (int32_t f : vfaces_[u]) {
        for (int k = 0; k < 3; ++k) {
          if (tri_[f][k] != chain_nbrs[i]) continue;
          if (seen >= 0 && tcol_[f][k] != seen) single = false;
          seen = tcol_[f][k];
        }
      }
      one_sided[i] = single;
    }
  }
  std::vector<int32_t> colors;
  for (int32_t f : vfaces_[u])
    for (int k = 0; k < 3; ++k)
      if (tri_[f][k] == u) colors.push_back(tcol_[f][k]);
  std::sort(colors.begin(), colors.end());
  colors.erase(std::unique(colors.begin(), colors.end()), colors.end());
  for (int32_t c : colors) {
    CollapseRecord::Wedge w;
    w.color = c;
    for (int32_t f : vfaces_[u]) {
      int ku = 0;
      while (tri_[f][ku] != u) ++ku;
      if (tcol_[f][ku] != c) continue;
      for (int k = 0; k < 3; ++k) {
        if (k == ku) continue;
        const int32_t x = tri_[f][k];
        w.neighbours.push_back({x, tcol_[f][k]});
      }
    }
    if (tear_slot >= 0) {
      auto along = [&](const std::pair<int32_t, int32_t>& n) {
        return (n.first == chain_nbrs[0] && !one_sided[0]) || (n.first == chain_nbrs[1] && !one_sided[1]);
      };
      auto single = [&](const std::pair<int32_t, int32_t>& n) {
        return (n.first == chain_nbrs[0] && one_sided[0]) || (n.first == chain_nbrs[1] && one_sided[1]);
      };
      if (std::any_of(w.neighbours.begin(), w.neighbours.end(), along)) {
        std::erase_if(w.neighbours, [&](const auto& n) { return !along(n); });
      } else {
        std::erase_if(w.neighbours, single);
      }
    }
    std::sort(w.neighbours.begin(), w.neighbours.end());
    w.neighbours.erase(std::unique(w.neighbours.begin(), w.neighbours.end()), w.neighbours.end());
    r.wedges.push_back(std::move(w));
  }

  // Apply: u's faces take v, with v's color on their side; the faces on the edge die.
  std::array<std::array<int32_t, 2>, 2> pairs;
  const int npairs = edge_color_pairs(u, v, pairs);
  const std::vector<int32_t> faces_of_u(vfaces_[u].begin(), vfaces_[u].end());
  detail::collapse_faces(
      faces_of_u, tri_, tcol_, u, v, pairs, npairs,
      [&](int32_t f) {
        face_alive_[f] = 0;
        for (int32_t w : tri_[f])
          if (w != u) vfaces_.erase(w, f);
      },
      [&](int32_t f) { vfaces_.push_back(v, f, arena_); });
  vfaces_.clear(u);
  vertex_alive_[u] = 0;
  --alive_count_;
  if (tear_slot >= 0) {
    Chain& c = chains_[chain_of_[u]];
    c.nodes.erase(c.nodes.begin() + tear_slot);
    c.original.erase(c.original.begin() + tear_slot);
    tear_edges_.erase(key(u, chain_nbrs[0]));
    tear_edges_.erase(key(u, chain_nbrs[1]));
    tear_edges_.insert(key(chain_nbrs[0], chain_nbrs[1]));
    chain_of_[u] = -1;
  }
  return r;
}

ControlMesh Coarsener::result(std::vector<int32_t>& parents, std::vector<int32_t>& color_merged) const {
  ControlMesh out;
  std::vector<int32_t> vmap(pos_.size(), -1), cmap(merged_.size(), -1);
  parents.clear();
  color_merged.clear();
  for (size_t v = 0; v < pos_.size(); ++v) {
    if (!vertex_alive_[v]) continue;
    vmap[v] = out.num_vertices();
    out.positions.push_back(pos_[v]);
    parents.push_back(static_cast<int32_t>(v));
  }
  for (size_t f = 0; f < tri_.size(); ++f) {
    if (!face_alive_[f]) continue;
    Tri t, c;
    for (int k = 0; k < 3; ++k) {
      t[k] = vmap[tri_[f][k]];
      int32_t& ci = cmap[tcol_[f][k]];
      if (ci < 0) {
        ci = out.num_colors();
        const Rgb& m = merged_[tcol_[f][k]];
        out.colors.push_back({static_cast<float>(m[0]), static_cast<float>(m[1]), static_cast<float>(m[2])});
        color_merged.push_back(tcol_[f][k]);
      }
      c[k] = ci;
    }
    out.triangles.push_back(t);
    out.triangle_colors.push_back(c);
  }
  for (const EdgeVerts& e : creases_)
    if (vmap[e[0]] >= 0 && vmap[e[1]] >= 0) out.creases.push_back({vmap[e[0]], vmap[e[1]]});
  for (const Chain& c : chains_) {
    Feature g;
    g.id = c.id;
    g.saliency = c.saliency;
    for (int32_t v : c.nodes) g.vertices.push_back(vmap[v]);
    if (c.closed) g.vertices.push_back(g.vertices.front());
    out.features.push_back(std::move(g));
  }
  return out;
}

}  // namespace subvec::coarsen_detail
