// Selection tools (edit/selection.h has the semantics).
#include "subvec/edit/selection.h"

#include <algorithm>
#include <array>
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

// CIELAB (D65) of an sRGB color on the 0-255 scale: distances in it follow what the eye sees (a
// region's tolerance). Values outside 0-255 extend the curves.
std::array<double, 3> lab(const Color& c) {
  auto linear = [](double v) {
    v /= 255;
    return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
  };
  const double r = linear(c.r), g = linear(c.g), b = linear(c.b);
  const double x = (0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.95047;
  const double y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
  const double z = (0.0193 * r + 0.1192 * g + 0.9505 * b) / 1.08883;
  auto f = [](double t) { return t > 216.0 / 24389 ? std::cbrt(t) : (24389.0 / 27 * t + 16) / 116; };
  const double fx = f(x), fy = f(y), fz = f(z);
  return {116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz)};
}

// Grows `seeds` over triangles through the color values that `accept` takes (a color value's
// index and its vertex's position).
template <class Accept>
std::vector<int32_t> grow(const ControlMesh& mesh, const std::vector<int32_t>& seeds,
                          Accept&& accept) {
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
  for (size_t i = 0; i < queue.size(); ++i) {
    const int32_t c = queue[i];
    for (int32_t j = offsets[c]; j < offsets[c + 1]; ++j) {
      for (int32_t d : mesh.triangle_colors[faces[j]]) {
        if (seen[d]) continue;
        if (!accept(d, mesh.positions[vertex_of[d]])) continue;
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
  return nearest_feature(mesh.features, mesh, topology, p);
}

FeaturePick nearest_feature(std::span<const Feature> chains, const ControlMesh& mesh,
                            const MeshTopology& topology, Vec2 p) {
  FeaturePick pick;
  pick.distance = std::numeric_limits<double>::infinity();
  constexpr int kSamplesPerSpan = 16;
  for (size_t f = 0; f < chains.size(); ++f) {
    for (const CurvePiece& piece : feature_pieces(topology, chains[f])) {
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

std::vector<Feature> crease_chains(const ControlMesh& mesh, const MeshTopology& topology) {
  const int nv = mesh.num_vertices();
  std::vector<std::vector<int32_t>> around(nv);  // crease edges at each vertex
  for (size_t e = 0; e < mesh.creases.size(); ++e)
    for (const int32_t v : mesh.creases[e]) around[v].push_back(static_cast<int32_t>(e));
  const auto stops = [&](int32_t v) { return around[v].size() != 2 || topology.vertex_tags[v] == VertexTag::kCorner; };
  std::vector<uint8_t> used(mesh.creases.size(), 0);
  // From vertex v along crease edge e: the chain's vertices until a stop or back at the start.
  const auto walk = [&](int32_t v, int32_t e, std::vector<int32_t>& out, bool mark) {
    const int32_t start = v;
    for (;;) {
      if (mark) used[e] = 1;
      const EdgeVerts& edge = mesh.creases[e];
      v = edge[0] == v ? edge[1] : edge[0];
      out.push_back(v);
      if (v == start || stops(v)) return;
      e = around[v][0] == e ? around[v][1] : around[v][0];
    }
  };
  std::vector<Feature> chains;
  for (size_t e0 = 0; e0 < mesh.creases.size(); ++e0) {
    if (used[e0]) continue;
    // Back from the edge's first vertex to the chain's end (or round a loop), then forward.
    const int32_t a = mesh.creases[e0][0];
    std::vector<int32_t> back{a};
    if (!stops(a)) walk(a, around[a][0] == int32_t(e0) ? around[a][1] : around[a][0], back, false);
    const bool loop = back.size() > 1 && back.back() == a;
    int32_t first = loop ? a : back.back();
    int32_t first_edge = int32_t(e0);
    if (!loop && first != a) {
      // The edge leaving `first` towards a: the last one the walk back crossed.
      const int32_t prev = back[back.size() - 2];
      for (const int32_t e : around[first])
        if (mesh.creases[e][0] == prev || mesh.creases[e][1] == prev) first_edge = e;
    }
    Feature f;
    f.id = -1 - static_cast<int32_t>(chains.size());
    f.vertices = {first};
    walk(first, first_edge, f.vertices, true);
    chains.push_back(std::move(f));
  }
  return chains;
}

std::vector<Feature> editable_chains(const ControlMesh& mesh, const MeshTopology& topology) {
  std::vector<Feature> chains = mesh.features;
  for (Feature& f : crease_chains(mesh, topology)) chains.push_back(std::move(f));
  return chains;
}

ColorSelection select_vertex_colors(const ControlMesh& mesh, const MeshTopology& topology, Vec2 at,
                                    double radius) {
  ColorSelection s;
  s.seed_vertex = nearest_vertex(mesh, at);
  if (s.seed_vertex < 0) return s;
  s.seed_color = corner_color(mesh, face_towards(mesh, topology, s.seed_vertex, at), s.seed_vertex);
  const Vec2 o = mesh.positions[s.seed_vertex];
  s.colors = grow(mesh, {s.seed_color},
                  [&](int32_t, Vec2 q) { return radius > 0 && std::hypot(q.x - o.x, q.y - o.y) <= radius; });
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
  s.colors = grow(mesh, seeds, [&](int32_t, Vec2 q) {
    if (!(radius > 0)) return false;
    double d = std::numeric_limits<double>::infinity();
    for (size_t k = 0; k + 1 < feature.vertices.size(); ++k) {
      d = std::min(d, segment_distance(q, mesh.positions[feature.vertices[k]],
                                       mesh.positions[feature.vertices[k + 1]]));
    }
    return d <= radius;
  });
  return s;
}

std::optional<EditSelect> edit_select_from_name(std::string_view name) {
  if (name == "vertex") return EditSelect::kVertex;
  if (name == "feature") return EditSelect::kFeature;
  if (name == "region") return EditSelect::kRegion;
  if (name == "vertices") return EditSelect::kVertices;
  if (name == "all") return EditSelect::kAll;
  return std::nullopt;
}

ColorSelection select_region_colors(const ControlMesh& mesh, Vec2 at, double radius,
                                    double tolerance) {
  if (!(radius >= 0) || !(tolerance >= 0) || std::isinf(tolerance)) {
    throw Error(ErrorCode::kInvalidArgument,
                "a region needs a radius >= 0 and a finite tolerance >= 0");
  }
  ColorSelection s;
  // The clicked triangle: the one containing `at`, or else the nearest (a point on the border).
  int face = -1;
  double face_distance = std::numeric_limits<double>::infinity();
  for (int f = 0; f < mesh.num_triangles() && face_distance > 0; ++f) {
    const Vec2 a = mesh.positions[mesh.triangles[f][0]], b = mesh.positions[mesh.triangles[f][1]],
               c = mesh.positions[mesh.triangles[f][2]];
    const bool inside = cross(b.x - a.x, b.y - a.y, at.x - a.x, at.y - a.y) >= 0 &&
                        cross(c.x - b.x, c.y - b.y, at.x - b.x, at.y - b.y) >= 0 &&
                        cross(a.x - c.x, a.y - c.y, at.x - c.x, at.y - c.y) >= 0;
    const double d = inside ? 0
                            : std::min({segment_distance(at, a, b), segment_distance(at, b, c),
                                        segment_distance(at, c, a)});
    if (d < face_distance) face_distance = d, face = f;
  }
  if (face < 0) return s;
  double seed_d2 = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    const Vec2 q = mesh.positions[mesh.triangles[face][k]];
    const double d2 = (q.x - at.x) * (q.x - at.x) + (q.y - at.y) * (q.y - at.y);
    if (d2 < seed_d2) {
      seed_d2 = d2, s.seed_vertex = mesh.triangles[face][k], s.seed_color = mesh.triangle_colors[face][k];
    }
  }
  const std::array<double, 3> seed = lab(mesh.colors[s.seed_color]);
  // The fill reaches a value once per triangle around it: its color verdict is taken once.
  std::vector<int8_t> near(mesh.colors.size(), -1);
  s.colors = grow(mesh, {s.seed_color}, [&](int32_t c, Vec2 q) {
    if (near[c] < 0) {
      const std::array<double, 3> v = lab(mesh.colors[c]);
      const double dl = v[0] - seed[0], da = v[1] - seed[1], db = v[2] - seed[2];
      near[c] = dl * dl + da * da + db * db <= tolerance * tolerance;
    }
    return near[c] == 1 && std::hypot(q.x - at.x, q.y - at.y) <= radius;
  });
  return s;
}

ColorSelection select_vertices_colors(const ControlMesh& mesh, std::span<const int32_t> vertices) {
  if (vertices.empty()) throw Error(ErrorCode::kInvalidArgument, "no vertices selected");
  std::vector<uint8_t> in(mesh.positions.size(), 0);
  for (const int32_t v : vertices) {
    if (v < 0 || v >= mesh.num_vertices()) {
      throw Error(ErrorCode::kInvalidArgument, "vertex " + std::to_string(v) +
                                                   " is out of range (the level has " +
                                                   std::to_string(mesh.num_vertices()) + ")");
    }
    in[v] = 1;
  }
  ColorSelection s;
  s.seed_vertex = vertices.front();
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    for (int k = 0; k < 3; ++k) {
      if (!in[mesh.triangles[f][k]]) continue;
      s.colors.push_back(mesh.triangle_colors[f][k]);
      if (s.seed_color < 0 && mesh.triangles[f][k] == s.seed_vertex) s.seed_color = mesh.triangle_colors[f][k];
    }
  }
  std::sort(s.colors.begin(), s.colors.end());
  s.colors.erase(std::unique(s.colors.begin(), s.colors.end()), s.colors.end());
  return s;
}

ColorSelection select_all_colors(const ControlMesh& mesh, const MeshTopology& topology, Vec2 at) {
  ColorSelection s = select_vertex_colors(mesh, topology, at, 0);
  s.colors.resize(mesh.colors.size());
  for (size_t c = 0; c < s.colors.size(); ++c) s.colors[c] = static_cast<int32_t>(c);
  return s;
}

ColorSelection select_colors(const ControlMesh& mesh, const MeshTopology& topology,
                             EditSelect select, Vec2 at, double radius, double tolerance,
                             std::span<const int32_t> vertices) {
  switch (select) {
    case EditSelect::kVertex: return select_vertex_colors(mesh, topology, at, radius);
    case EditSelect::kFeature: return select_feature_colors(mesh, topology, at, radius);
    case EditSelect::kVertices: return select_vertices_colors(mesh, vertices);
    case EditSelect::kAll: return select_all_colors(mesh, topology, at);
    case EditSelect::kRegion: break;
  }
  return select_region_colors(mesh, at, radius, tolerance);
}

}  // namespace subvec
