// The edge collapse on an index mesh: triangles as vertex triples, face-varying color indices and,
// per vertex, the ids of its incident faces (any range of int32_t). Shared by the simplification of
// vectorization (vectorize/simplify.cpp) and the coarsening between levels (mesh/coarsen.cpp), so
// that the two agree about what a collapse may not do to a mesh (break the link condition, fold
// two sharp edges into one, flip or flatten a triangle) and about what it does to the faces and
// their colors (collapse_faces). The 5D quadric they order collapses by is mesh/quadric_p.h.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "subvec/mesh/vector_image.h"

namespace subvec::detail {

// What a vertex is to the collapses (paper §3.2): smooth, on the image border between two
// corners, on a tear (feature) chain, or a corner (image corner, feature end, junction).
enum class VertexKind : uint8_t { kSmooth, kBorder, kTear, kCorner };

// Which sides of the width x height image p lies on, as a bit mask: 1 x = 0, 2 y = 0, 4 x = width,
// 8 y = height (two bits at an image corner).
inline uint8_t image_sides(Vec2 p, int width, int height) {
  return static_cast<uint8_t>((p.x == 0 ? 1 : 0) | (p.y == 0 ? 2 : 0) | (p.x == width ? 4 : 0) | (p.y == height ? 8 : 0));
}

// The paper's constraints on removing u into its neighbour v over an edge with `edge_faces` faces,
// by their kinds (§4; §5 for the levels): a corner stays; a smooth vertex may go into any
// neighbour; a border vertex only along its image side (`same_side`) over a border edge (one face)
// into a border vertex or a corner; a tear vertex only where `along_chain()` allows (the caller's
// chain: v next to u on it, and what else the caller's chain rules ask).
template <class AlongChain>
bool kinds_allow_collapse(VertexKind ku, VertexKind kv, int edge_faces, bool same_side, AlongChain&& along_chain) {
  switch (ku) {
    case VertexKind::kSmooth:
      return true;
    case VertexKind::kBorder:
      return edge_faces == 1 && same_side && (kv == VertexKind::kBorder || kv == VertexKind::kCorner);
    case VertexKind::kTear:
      return along_chain();
    case VertexKind::kCorner:
      return false;
  }
  return false;
}

// A stamp per vertex for neighbourhood queries: taking a new stamp unmarks every vertex at once.
struct VertexMarks {
  std::vector<uint32_t> mark;  // sized to the vertex count by the owner
  uint32_t stamp = 0;
  uint32_t next_stamp() {
    if (++stamp == 0) std::fill(mark.begin(), mark.end(), 0u), stamp = 1;
    return stamp;
  }
};

inline double signed_area(Vec2 a, Vec2 b, Vec2 c) {
  return 0.5 * ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
}

// The faces among `faces_of_u` (u's incident faces) that have the vertex v: how many, and the
// first two in `out`.
template <class Faces>
int faces_with_edge(const Faces& faces_of_u, const std::vector<Tri>& tri, int32_t v, int32_t* out) {
  int n = 0;
  for (int32_t f : faces_of_u) {
    const Tri& t = tri[f];
    if (t[0] == v || t[1] == v || t[2] == v) {
      if (n < 2) out[n] = f;
      ++n;
    }
  }
  return n;
}

// (color of u, color of v) in each of the `n` faces on the edge (u, v), colors from `tcol` (one per
// corner); the second face's pair is dropped when it repeats the first (no tear along the edge).
// Returns how many pairs.
inline int edge_color_pairs(const int32_t* faces, int n, const std::vector<Tri>& tri,
                            const std::vector<Tri>& tcol, int32_t u, int32_t v,
                            std::array<std::array<int32_t, 2>, 2>& out) {
  int pairs = 0;
  for (int i = 0; i < n; ++i) {
    int32_t cu = -1, cv = -1;
    for (int k = 0; k < 3; ++k) {
      if (tri[faces[i]][k] == u) cu = tcol[faces[i]][k];
      if (tri[faces[i]][k] == v) cv = tcol[faces[i]][k];
    }
    if (pairs == 1 && out[0][0] == cu && out[0][1] == cv) continue;
    out[pairs++] = {cu, cv};
  }
  return pairs;
}

// The link condition for collapsing the edge (u, v), which has `edge_faces` faces: u and v have
// exactly as many common neighbours, the third vertices of those faces.
template <class Faces>
bool link_condition(const Faces& faces_of_u, const Faces& faces_of_v, const std::vector<Tri>& tri,
                    int32_t u, int32_t v, int edge_faces, VertexMarks& marks) {
  // Mark u's neighbours, then count v's marked ones, each once.
  const uint32_t of_u = marks.next_stamp(), counted = marks.next_stamp();
  for (int32_t f : faces_of_u)
    for (int32_t w : tri[f]) marks.mark[w] = of_u;
  int common = 0;
  for (int32_t f : faces_of_v) {
    for (int32_t w : tri[f]) {
      if (w == u || w == v || marks.mark[w] != of_u) continue;
      marks.mark[w] = counted;
      ++common;
    }
  }
  return common == edge_faces;
}

// Whether one of the `n` faces on the edge (u, v) has a third vertex w with sharp(u, w) and
// sharp(v, w): the collapse would fold those two sharp edges into one.
template <class Sharp>
bool folds_sharp_edges(const int32_t* faces, int n, const std::vector<Tri>& tri, int32_t u,
                       int32_t v, Sharp&& sharp) {
  for (int i = 0; i < n; ++i) {
    for (int32_t w : tri[faces[i]])
      if (w != u && w != v && sharp(u, w) && sharp(v, w)) return true;
  }
  return false;
}

// No flipped or thin triangle: whether every face among `faces_of_x` that survives the collapse
// of u into v (every face but those with both) keeps a signed area over `min_area` once u is
// renamed v, with its corners at position(vertex).
template <class Faces, class Position>
bool faces_keep_area(const Faces& faces_of_x, const std::vector<Tri>& tri, int32_t u, int32_t v,
                     Position&& position, double min_area) {
  for (int32_t f : faces_of_x) {
    Tri t = tri[f];
    bool has_u = false, has_v = false;
    for (int32_t& w : t) {
      has_u |= w == u;
      has_v |= w == v;
    }
    if (has_u && has_v) continue;  // dies
    for (int32_t& w : t)
      if (w == u) w = v;
    if (signed_area(position(t[0]), position(t[1]), position(t[2])) <= min_area) return false;
  }
  return true;
}

// Applies the half-edge collapse of u into v to u's faces (`faces_of_u`: a copy, since the lists
// change): a face that has v dies, and `dies(f)` is told; every other face takes v in u's place,
// the corner with v's color on its side of the edge (the pair among the `npairs` (color of u, color
// of v) of edge_color_pairs whose u color it had, else the first), and `survives(f)` is told.
template <class Dies, class Survives>
void collapse_faces(std::span<const int32_t> faces_of_u, std::vector<Tri>& tri, std::vector<Tri>& tcol,
                    int32_t u, int32_t v, const std::array<std::array<int32_t, 2>, 2>& pairs, int npairs,
                    Dies&& dies, Survives&& survives) {
  for (int32_t f : faces_of_u) {
    Tri& t = tri[f];
    if (t[0] == v || t[1] == v || t[2] == v) {
      dies(f);
      continue;
    }
    for (int k = 0; k < 3; ++k) {
      if (t[k] != u) continue;
      t[k] = v;
      int32_t cv = npairs > 0 ? pairs[0][1] : tcol[f][k];
      for (int i = 0; i < npairs; ++i)
        if (pairs[i][0] == tcol[f][k]) cv = pairs[i][1];
      tcol[f][k] = cv;
    }
    survives(f);
  }
}

}  // namespace subvec::detail
