// Selection tools (edit/selection.h has the semantics).
#include "subvec/edit/selection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/geometry_p.h"
#include "subvec/core/error.h"
#include "subvec/mesh/curves.h"

namespace subvec {
namespace {

using detail::cross;
using detail::segment_distance;

int corner_of(const ControlMesh& mesh, int face, int vertex) {
  const Tri& t = mesh.triangles[face];
  return t[0] == vertex ? 0 : t[1] == vertex ? 1 : t[2] == vertex ? 2 : -1;
}

int corner_color(const ControlMesh& mesh, int face, int vertex) {
  return mesh.triangle_colors[face][corner_of(mesh, face, vertex)];
}

// The face around vertex v whose corner sector contains the direction to p (the first incident
// face when none does: p on v, or outside the image next to a border vertex).
int face_towards(const ControlMesh& mesh, const MeshTopology& topology, int v, Vec2 p) {
  auto [begin, end] = topology.faces_of(v);
  const Vec2 o = mesh.positions[v];
  const double dx = p.x - o.x, dy = p.y - o.y;
  int best = *begin;
  double best_score = -std::numeric_limits<double>::infinity();
  for (const int32_t* f = begin; f != end; ++f) {
    const int k = corner_of(mesh, *f, v);
    const Vec2 a = mesh.positions[mesh.triangles[*f][(k + 1) % 3]];
    const Vec2 b = mesh.positions[mesh.triangles[*f][(k + 2) % 3]];
    const double ax = a.x - o.x, ay = a.y - o.y, bx = b.x - o.x, by = b.y - o.y;
    const double la = std::hypot(ax, ay), lb = std::hypot(bx, by);
    // Inside the sector iff the direction is left of (a - o) and right of (b - o): score by the
    // smaller normalised cross product, so the containing sector wins and ties go to the first.
    const double score = std::min(cross(ax, ay, dx, dy) / la, cross(dx, dy, bx, by) / lb);
    if (score > best_score) best_score = score, best = *f;
  }
  return best;
}

// Grows `seeds` over triangles through color values whose vertex is within `radius` of the seed
// geometry (`distance` of a position).
template <class Distance>
std::vector<int32_t> grow(const ControlMesh& mesh, std::vector<int32_t> seeds, double radius,
                          Distance&& distance) {
  const int nc = mesh.num_colors(), nf = mesh.num_triangles();
  std::vector<int32_t> vertex_of(nc, -1), offsets(size_t(nc) + 1, 0), faces(size_t(nf) * 3);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      vertex_of[mesh.triangle_colors[f][k]] = mesh.triangles[f][k];
      ++offsets[mesh.triangle_colors[f][k] + 1];
    }
  for (int c = 0; c < nc; ++c) offsets[c + 1] += offsets[c];
  {
    std::vector<int32_t> fill(offsets.begin(), offsets.end() - 1);
    for (int f = 0; f < nf; ++f)
      for (int32_t c : mesh.triangle_colors[f]) faces[fill[c]++] = f;
  }
  std::vector<uint8_t> seen(nc, 0);
  std::vector<int32_t> queue;
  for (int32_t c : seeds)
    if (!seen[c]) seen[c] = 1, queue.push_back(c);
  for (size_t i = 0; i < queue.size() && radius > 0; ++i) {
    const int32_t c = queue[i];
    for (int32_t j = offsets[c]; j < offsets[c + 1]; ++j) {
      for (int32_t d : mesh.triangle_colors[faces[j]]) {
        if (seen[d]) continue;
        if (distance(mesh.positions[vertex_of[d]]) > radius) continue;
        seen[d] = 1;
        queue.push_back(d);
      }
    }
  }
  std::sort(queue.begin(), queue.end());
  return queue;
}

}  // namespace

std::vector<CurvePiece> feature_pieces(const MeshTopology& topology, const Feature& feature) {
  std::vector<int32_t> chain = feature.vertices;
  std::vector<CurvePiece> pieces;
  auto is_corner = [&](int32_t v) { return topology.vertex_tags[v] == VertexTag::kCorner; };
  if (feature.closed()) {
    chain.pop_back();
    const auto corner = std::find_if(chain.begin(), chain.end(), is_corner);
    if (corner == chain.end()) return {CurvePiece{chain, true}};
    std::rotate(chain.begin(), corner, chain.end());
    chain.push_back(chain.front());
  }
  CurvePiece piece;
  for (size_t k = 0; k < chain.size(); ++k) {
    piece.vertices.push_back(chain[k]);
    if (k > 0 && k + 1 < chain.size() && is_corner(chain[k])) {
      pieces.push_back(std::move(piece));
      piece = CurvePiece{{chain[k]}, false};
    }
  }
  if (piece.vertices.size() >= 2) pieces.push_back(std::move(piece));
  return pieces;
}

std::vector<Vec2> piece_points(const ControlMesh& mesh, const CurvePiece& piece) {
  std::vector<Vec2> points;
  points.reserve(piece.vertices.size());
  for (int32_t v : piece.vertices) points.push_back(mesh.positions[v]);
  return points;
}

int nearest_vertex(const ControlMesh& mesh, Vec2 p) {
  int best = -1;
  double best_d2 = std::numeric_limits<double>::infinity();
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const double dx = mesh.positions[v].x - p.x, dy = mesh.positions[v].y - p.y;
    const double d2 = dx * dx + dy * dy;
    if (d2 < best_d2) best_d2 = d2, best = v;
  }
  return best;
}

FeaturePick nearest_feature(const ControlMesh& mesh, const MeshTopology& topology, Vec2 p) {
  FeaturePick pick;
  pick.distance = std::numeric_limits<double>::infinity();
  constexpr int kSamplesPerSpan = 16;
  for (size_t f = 0; f < mesh.features.size(); ++f) {
    for (const CurvePiece& piece : feature_pieces(topology, mesh.features[f])) {
      const std::vector<Vec2> points = piece_points(mesh, piece);
      const std::vector<Vec2> curve = sample_bspline(points, piece.closed, kSamplesPerSpan);
      for (size_t i = 0; i + 1 < curve.size(); ++i) {
        Vec2 q;
        const double d = segment_distance(p, curve[i], curve[i + 1], &q);
        if (d < pick.distance) {
          pick.feature = static_cast<int>(f);
          pick.distance = d;
          pick.nearest = q;
          const double c = cross(curve[i + 1].x - curve[i].x, curve[i + 1].y - curve[i].y,
                                 p.x - q.x, p.y - q.y);
          pick.side = c > 0 ? 1 : c < 0 ? -1 : 0;
        }
      }
    }
  }
  if (pick.feature < 0) pick.distance = 0;
  return pick;
}

ColorSelection select_vertex_colors(const ControlMesh& mesh, const MeshTopology& topology, Vec2 at,
                                    double radius) {
  ColorSelection s;
  s.seed_vertex = nearest_vertex(mesh, at);
  if (s.seed_vertex < 0) return s;
  s.seed_color = corner_color(mesh, face_towards(mesh, topology, s.seed_vertex, at), s.seed_vertex);
  const Vec2 o = mesh.positions[s.seed_vertex];
  s.colors = grow(mesh, {s.seed_color}, radius,
                  [&](Vec2 q) { return std::hypot(q.x - o.x, q.y - o.y); });
  return s;
}

ColorSelection select_feature_colors(const ControlMesh& mesh, const MeshTopology& topology,
                                     Vec2 at, double radius) {
  const FeaturePick pick = nearest_feature(mesh, topology, at);
  if (pick.feature < 0) {
    throw Error(ErrorCode::kInvalidArgument, "nothing to select: the level has no features");
  }
  const Feature& feature = mesh.features[pick.feature];
  const int side = pick.side >= 0 ? 1 : -1;
  ColorSelection s;
  std::vector<int32_t> seeds;
  double seed_d2 = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k + 1 < feature.vertices.size(); ++k) {
    const int u = feature.vertices[k], w = feature.vertices[k + 1];
    const int e = topology.find_edge(u, w);
    // The face in which u -> w runs in the face's own order lies left of u -> w (positive side).
    for (const int32_t f : topology.edge_faces[e]) {
      if (f < 0) continue;
      const int ku = corner_of(mesh, f, u);
      const bool forward = mesh.triangles[f][(ku + 1) % 3] == w;
      if (forward != (side > 0)) continue;
      for (const int v : {u, w}) {
        const int c = corner_color(mesh, f, v);
        seeds.push_back(c);
        const double dx = mesh.positions[v].x - at.x, dy = mesh.positions[v].y - at.y;
        if (dx * dx + dy * dy < seed_d2) seed_d2 = dx * dx + dy * dy, s.seed_vertex = v, s.seed_color = c;
      }
    }
  }
  s.colors = grow(mesh, seeds, radius, [&](Vec2 q) {
    double d = std::numeric_limits<double>::infinity();
    for (size_t k = 0; k + 1 < feature.vertices.size(); ++k) {
      d = std::min(d, segment_distance(q, mesh.positions[feature.vertices[k]],
                                       mesh.positions[feature.vertices[k + 1]]));
    }
    return d;
  });
  return s;
}

}  // namespace subvec
