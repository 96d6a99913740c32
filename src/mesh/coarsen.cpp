// The mesh state between two levels; see coarsen_p.h.
#include "mesh/coarsen_p.h"

#include <algorithm>
#include <cmath>
#include <numeric>
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
    // An object's mesh (MeshTopology::kNoFrame) has no image sides: its boundary vertices are
    // corners, kept by every coarsening.
    sides_[v] = width < 0 ? 0 : detail::image_sides(pos_[v], width, height);
    switch (topo.vertex_tags[v]) {
      case VertexTag::kSmooth: kind_[v] = Kind::kSmooth; break;
      case VertexTag::kTear: kind_[v] = Kind::kTear; break;
      case VertexTag::kCrease: kind_[v] = sides_[v] ? Kind::kBorder : Kind::kCorner; break;
      case VertexTag::kCorner: kind_[v] = Kind::kCorner; break;
    }
  }
  // A vertex that is a tear by its edges but ends a chain (two features meeting end to end) is a
  // chain end: it stays.
  chains_.build(merged.features, pos_, kind_);
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
    const int32_t node = chains_.node_of[u];
    if (node < 0) return false;
    const detail::Chain& c = chains_.chains[chains_.chain_of[u]];
    if (c.closed && c.size <= 4) return false;
    const detail::ChainNode& prev = chains_.nodes[chains_.nodes[node].prev];
    const detail::ChainNode& next = chains_.nodes[chains_.nodes[node].next];
    if (prev.vertex != v && next.vertex != v) return false;
    // The chain's initial points from prev to next (u's among them) must stay near the new edge.
    const Vec2 a = pos_[prev.vertex], b = pos_[next.vertex];
    const int np = static_cast<int>(c.target.size());
    for (int i = static_cast<int>(prev.param) + 1;; ++i) {
      const int j = i % np;
      if (j == static_cast<int>(next.param)) break;
      if (detail::segment_distance(c.target[j], a, b) > feature_tolerance) return false;
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
  const bool tear = kind_[u] == Kind::kTear;
  if (tear) {
    const detail::ChainNode& node = chains_.nodes[chains_.node_of[u]];
    chain_nbrs = {chains_.nodes[node.prev].vertex, chains_.nodes[node.next].vertex};
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
  if (tear) {
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
    if (tear) {
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
  std::vector<int32_t> scratch;
  detail::collapse_incidence(u, v, pairs, npairs, tri_, tcol_, vfaces_, face_alive_, vertex_alive_, arena_, scratch);
  --alive_count_;
  if (tear) chains_.unlink(u);  // its two chain edges become one
  return r;
}

ControlMesh Coarsener::result(std::vector<int32_t>& parents, std::vector<int32_t>& color_merged) const {
  std::vector<int32_t> order(tri_.size()), vmap;
  std::iota(order.begin(), order.end(), 0);
  ControlMesh out = detail::live_mesh(pos_, vertex_alive_, tri_, tcol_, face_alive_, order, num_merged(), creases_, chains_,
                                      [&](int32_t m, int32_t) {
    return Color{static_cast<float>(merged_[m][0]), static_cast<float>(merged_[m][1]), static_cast<float>(merged_[m][2])};
  }, vmap, color_merged);
  parents.clear();
  for (size_t v = 0; v < vmap.size(); ++v)
    if (vmap[v] >= 0) parents.push_back(static_cast<int32_t>(v));
  return out;
}

std::vector<EdgeVerts> collapse_shortest_first(Coarsener& c, const std::vector<uint8_t>& removable, int target) {
  const int nv = c.num_vertices();
  int remaining = 0;
  for (int v = 0; v < nv; ++v) remaining += removable[v] && c.alive(v);
  detail::CollapseQueue queue;
  std::vector<uint32_t> version(nv, 0);
  auto plan = [&](int32_t u, int32_t v) {
    if (!removable[u]) return;
    const Vec2 a = c.positions()[u], b = c.positions()[v];
    queue.push(detail::make_entry((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y), u, v,
                                  version[u], version[v]));
  };
  std::vector<int32_t> ring, ring2;
  for (int32_t v = 0; v < nv; ++v) {
    if (!removable[v] || !c.alive(v)) continue;
    c.neighbours(v, ring);
    for (const int32_t w : ring) plan(v, w);
  }
  std::vector<EdgeVerts> made;
  const auto more = [&] { return remaining > target; };
  const auto live = [&](const detail::Entry& e) { return detail::entry_live(e, c.vertex_alive(), version); };
  const auto step = [&](const detail::Entry& e) {
    const int32_t u = e.remove(), v = e.keep;
    if (!c.can_collapse(u, v, 0.0)) return;
    c.neighbours(u, ring);
    c.collapse(u, v);
    made.push_back({u, v});
    --remaining;
    for (const int32_t w : ring) ++version[w];
    for (const int32_t w : ring) {
      c.neighbours(w, ring2);
      for (const int32_t x : ring2) plan(w, x), plan(x, w);
    }
  };
  detail::run_collapses(queue, nullptr, more, live, step);
  return made;
}

}  // namespace subvec::coarsen_detail
