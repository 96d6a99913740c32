// Private to the library: the mesh state between two levels (paper §5), in the mesh layer because
// the level building (vectorize/) and the pyramid's replay (pyramid/) both use it. The finer level
// loses the features that the coarser one drops (each seam closes: the colors on its two sides
// merge into their mean), then half-edge collapses remove vertices one at a time. A half-edge
// collapse keeps the kept vertex where it is, so the coarser level's vertices are a subset of the
// finer one's, and every removed vertex can be predicted from the neighbours it had when it went
// (the records the vector image pyramid replays, pyramid.cpp).
//
// Design note. The level building (vectorize/levels.cpp) decides which collapses to make; the pyramid
// (pyramid.cpp) replays the same collapses from a saved file. Both go through this one class, so
// the two can never disagree about what a collapse does to the topology or the colors.
#pragma once

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "mesh/chains_p.h"
#include "mesh/collapse_p.h"
#include "mesh/collapse_engine_p.h"
#include "subvec/mesh/vector_image.h"

namespace subvec::coarsen_detail {

using Kind = detail::VertexKind;

using Rgb = std::array<double, 3>;

// What a removed vertex was predicted from when it went (paper §6.4, eq. 3).
struct CollapseRecord {
  int32_t removed = -1, kept = -1;
  // The vertices its position is predicted from: the whole one-ring of a smooth vertex, the two
  // neighbours along the border side or the feature chain of a border or tear vertex.
  std::vector<int32_t> position_ring;
  struct Wedge {
    int32_t color = -1;                                  // merged color index of the removed vertex
    std::vector<std::pair<int32_t, int32_t>> neighbours;  // (vertex, merged color) it is predicted from
  };
  std::vector<Wedge> wedges;  // one per color value of the removed vertex (two on a tear)
};

class Coarsener {
 public:
  // `fine` keeps only the features whose ids are in `kept_ids`; the others' seams close. Throws
  // Error(kInvalidMesh) when a color value is shared by corners that no wedge joins.
  Coarsener(const ControlMesh& fine, int width, int height, const std::vector<int32_t>& kept_ids);

  // Fine color index -> merged color index, and the merged colors (means of what merged).
  const std::vector<int32_t>& merged_of() const { return merged_of_; }
  const std::vector<Rgb>& merged_colors() const { return merged_; }
  int num_merged() const { return static_cast<int>(merged_.size()); }

  Kind kind(int32_t v) const { return kind_[v]; }
  bool alive(int32_t v) const { return vertex_alive_[v] != 0; }
  const std::vector<uint8_t>& vertex_alive() const { return vertex_alive_; }
  int alive_vertices() const { return alive_count_; }
  const std::vector<Vec2>& positions() const { return pos_; }
  int num_vertices() const { return static_cast<int>(pos_.size()); }
  const std::vector<Tri>& triangles() const { return tri_; }
  const std::vector<Tri>& triangle_colors() const { return tcol_; }  // merged color indices
  bool face_alive(int32_t f) const { return face_alive_[f] != 0; }

  // The distinct neighbours of v, ascending.
  void neighbours(int32_t v, std::vector<int32_t>& out) const;
  // (color of u, color of v) in the faces on the edge (u, v): one pair unless a tear runs along it.
  int edge_color_pairs(int32_t u, int32_t v, std::array<std::array<int32_t, 2>, 2>& out) const;
  // Whether removing u into its neighbour v keeps the mesh valid: u is no corner, a border vertex
  // goes along its side and a tear vertex along its chain, whose control polygon then stays within
  // `feature_tolerance` pixels of the chain this step started from; the link condition; no two
  // sharp edges merge; no new edge joins two vertices of one image side; no triangle flips or
  // gets thinner than `min_area` square pixels.
  bool can_collapse(int32_t u, int32_t v, double feature_tolerance, double min_area = 1e-3) const;
  // Removes u into v (no checks) and returns what u is predicted from.
  CollapseRecord collapse(int32_t u, int32_t v);

  // The coarse mesh: live vertices in ascending order, live faces in their order, colors numbered
  // by first use (the merged values), the kept features. `parents`: each vertex's fine index;
  // `color_merged`: each color's merged index.
  ControlMesh result(std::vector<int32_t>& parents, std::vector<int32_t>& color_merged) const;

 private:
  int faces_with_edge(int32_t u, int32_t v, int32_t* out) const;
  bool tear_edge(int32_t a, int32_t b) const { return chains_.tear_edge(a, b); }
  bool sharp_edge(int32_t a, int32_t b) const;
  bool has_edge(int32_t a, int32_t b) const;

  int width_, height_;
  std::vector<Vec2> pos_;
  std::vector<Tri> tri_, tcol_;
  std::vector<uint8_t> face_alive_, vertex_alive_, sides_;
  detail::IncidenceLists vfaces_;  // the engine's incidence lists (collapse_engine_p.h)
  detail::Arena arena_;             // where they grow
  std::vector<Kind> kind_;
  std::vector<int32_t> merged_of_;
  std::vector<Rgb> merged_;
  detail::FeatureChains chains_;  // the kept features, as the simplifier's linked nodes
  std::vector<EdgeVerts> creases_;
  mutable detail::VertexMarks marks_;  // scratch for can_collapse
  int alive_count_ = 0;
};

// Removes the live vertices marked in `removable` by half-edge collapses, shortest edge first,
// until `target` of them remain or none can go (can_collapse, with chains held exactly). Returns
// the collapses made, (removed, kept), in order: the record a pyramid replays.
std::vector<EdgeVerts> collapse_shortest_first(Coarsener& c, const std::vector<uint8_t>& removable, int target);

}  // namespace subvec::coarsen_detail
