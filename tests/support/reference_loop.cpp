#include "support/reference_loop.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <numeric>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>

namespace subvec::testing {
namespace {

using EdgeKey = std::pair<int, int>;
EdgeKey edge_key(int a, int b) { return a < b ? EdgeKey{a, b} : EdgeKey{b, a}; }

// Corner k of face f; as an edge, it stands for (v_k, v_k+1).
struct Corner {
  int face;
  int k;
};

// What the masks need to look up, built naively from the triangle lists.
struct Adjacency {
  std::map<EdgeKey, std::vector<Corner>> edge_corners;  // one or two corners per edge
  std::vector<std::vector<Corner>> vertex_corners;      // #V
  std::vector<int> color_vertex;                        // #C: the vertex of each color value
};

Adjacency build_adjacency(const ReferenceMesh& m) {
  Adjacency adj;
  adj.vertex_corners.resize(m.num_vertices());
  adj.color_vertex.assign(m.num_colors(), -1);
  for (int f = 0; f < m.num_triangles(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int v = m.triangles[f][k];
      adj.edge_corners[edge_key(v, m.triangles[f][(k + 1) % 3])].push_back({f, k});
      adj.vertex_corners[v].push_back({f, k});
      int& owner = adj.color_vertex[m.triangle_colors[f][k]];
      if (owner >= 0 && owner != v) {
        throw std::logic_error("color value " + std::to_string(m.triangle_colors[f][k]) +
                               " is used at two vertices");
      }
      owner = v;
    }
  }
  return adj;
}

EdgeTag tag_of(const ReferenceMesh& m, const Adjacency& adj, int a, int b) {
  const Corner c = adj.edge_corners.at(edge_key(a, b)).front();
  return m.edge_tags[c.face][c.k];
}

// The ring around one value at vertex v: for vertex data the whole one-ring; for a color value the
// faces whose corner at v uses it (its fan). `ring` lists the neighbouring vertices' values (rows)
// as seen from those faces, `sharp` those across crease, tear and border edges.
struct Ring {
  std::vector<int> ring, sharp;
};

Ring gather_ring(const ReferenceMesh& m, const Adjacency& adj, int v, int color) {
  std::map<int, int> value_of;  // neighbour vertex -> its row (itself, or its color in the fan)
  for (const Corner& c : adj.vertex_corners[v]) {
    if (color >= 0 && m.triangle_colors[c.face][c.k] != color) continue;
    for (int step : {1, 2}) {
      const int corner = (c.k + step) % 3;
      const int w = m.triangles[c.face][corner];
      const int row = color >= 0 ? m.triangle_colors[c.face][corner] : w;
      auto [it, inserted] = value_of.emplace(w, row);
      if (!inserted && it->second != row) {
        throw std::logic_error("vertex " + std::to_string(w) +
                               " has two color values next to color " + std::to_string(color) +
                               " of vertex " + std::to_string(v) + " without a tear between them");
      }
    }
  }
  Ring r;
  for (auto [w, row] : value_of) {
    r.ring.push_back(row);
    if (is_sharp(tag_of(m, adj, v, w))) r.sharp.push_back(row);
  }
  return r;
}

enum class Rule { kRefine, kLimit };

// Vertex point (Fig. 2a-d) or limit point of the value in row `centre`.
Eigen::RowVectorXd vertex_rule(Rule rule, VertexTag tag, const Eigen::MatrixXd& values, int centre,
                               const Ring& r) {
  switch (tag) {
    case VertexTag::kCorner:
      return values.row(centre);
    case VertexTag::kCrease:
    case VertexTag::kTear: {
      if (r.sharp.size() != 2) {
        throw std::logic_error("crease/tear value " + std::to_string(centre) + " has " +
                               std::to_string(r.sharp.size()) + " sharp neighbours, not 2");
      }
      const double side = rule == Rule::kRefine ? 1.0 / 8 : 1.0 / 6;
      return (1 - 2 * side) * values.row(centre) +
             side * (values.row(r.sharp[0]) + values.row(r.sharp[1]));
    }
    case VertexTag::kSmooth: {
      const int n = static_cast<int>(r.ring.size());
      const double w = rule == Rule::kRefine ? (1 - loop_alpha(n)) / n : loop_limit_chi(n);
      Eigen::RowVectorXd out = (1 - n * w) * values.row(centre);
      for (int row : r.ring) out += w * values.row(row);
      return out;
    }
  }
  throw std::logic_error("unknown vertex tag");
}

// Vertex points (or limit points) of every vertex and every color value.
void apply_vertex_rules(Rule rule, const ReferenceMesh& m, const Adjacency& adj,
                        Eigen::MatrixXd& vertex_out, Eigen::MatrixXd& color_out) {
  // Corners keep their values; their rings are not needed (and the ring of a tear endpoint's
  // single color value sees both sides of the tear).
  for (int v = 0; v < m.num_vertices(); ++v) {
    vertex_out.row(v) =
        m.vertex_tags[v] == VertexTag::kCorner
            ? Eigen::RowVectorXd(m.vertex_values.row(v))
            : vertex_rule(rule, m.vertex_tags[v], m.vertex_values, v, gather_ring(m, adj, v, -1));
  }
  for (int c = 0; c < m.num_colors(); ++c) {
    const int v = adj.color_vertex[c];
    if (v < 0) throw std::logic_error("color value " + std::to_string(c) + " is not used");
    color_out.row(c) =
        m.vertex_tags[v] == VertexTag::kCorner
            ? Eigen::RowVectorXd(m.color_values.row(c))
            : vertex_rule(rule, m.vertex_tags[v], m.color_values, c, gather_ring(m, adj, v, c));
  }
}

// Edge point of the edge that corner c of a face starts (Fig. 2e-g): with `other` (the corner of
// the second face on a smooth edge) 3/8 on each end and 1/8 on the two opposite corners, without
// it the midpoint. `index` maps face corners to rows of `values`.
Eigen::RowVectorXd edge_rule(const Eigen::MatrixXd& values, const std::vector<Tri>& index, Corner c,
                             const Corner* other) {
  auto at = [&](Corner x, int step) { return values.row(index[x.face][(x.k + step) % 3]); };
  if (!other) return 0.5 * (at(c, 0) + at(c, 1));
  return 0.375 * (at(c, 0) + at(c, 1)) + 0.125 * (at(c, 2) + at(*other, 2));
}

VertexTag edge_point_tag(EdgeTag tag) {
  switch (tag) {
    case EdgeTag::kSmooth:
      return VertexTag::kSmooth;
    case EdgeTag::kTear:
      return VertexTag::kTear;
    case EdgeTag::kCrease:
    case EdgeTag::kBorder:
      return VertexTag::kCrease;
  }
  return VertexTag::kSmooth;
}

}  // namespace

double loop_alpha(int n) {
  const double c = 3.0 / 8 + 0.25 * std::cos(2 * std::numbers::pi / n);
  return c * c + 3.0 / 8;
}

double loop_limit_chi(int n) {
  const double beta = (1 - loop_alpha(n)) / n;
  return 1 / (3 / (8 * beta) + n);
}

ReferenceMesh reference_control_mesh(const ControlMesh& mesh, const MeshTopology& topology,
                                     Eigen::MatrixXd vertex_values, Eigen::MatrixXd color_values) {
  if (vertex_values.rows() != mesh.num_vertices() || color_values.rows() != mesh.num_colors()) {
    throw std::invalid_argument("reference_control_mesh: value rows do not match the mesh");
  }
  ReferenceMesh m;
  m.vertex_values = std::move(vertex_values);
  m.color_values = std::move(color_values);
  m.triangles = mesh.triangles;
  m.triangle_colors = mesh.triangle_colors;
  m.vertex_tags = topology.vertex_tags;
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    std::array<EdgeTag, 3> tags{};
    for (int k = 0; k < 3; ++k) tags[k] = topology.edge_tags[topology.face_edges[f][k]];
    m.edge_tags.push_back(tags);
    m.triangle_parent.push_back(f);
    m.triangle_uv.push_back({{{0, 0}, {1, 0}, {0, 1}}});
  }
  return m;
}

ReferenceMesh reference_control_mesh(const ControlMesh& mesh, const MeshTopology& topology) {
  return reference_control_mesh(mesh, topology, position_values(mesh), color_values(mesh));
}

ReferenceMesh refine(const ReferenceMesh& m) {
  const Adjacency adj = build_adjacency(m);
  const int nv = m.num_vertices(), nc = m.num_colors(), nf = m.num_triangles();

  // New vertices: the vertex points keep their indices, the edge points follow. New color values:
  // likewise, one edge value per smooth or crease edge and one per side of a tear edge.
  const int num_edges = static_cast<int>(adj.edge_corners.size());
  int num_tear_sides = 0;
  for (const auto& [edge, corners] : adj.edge_corners)
    if (m.edge_tags[corners[0].face][corners[0].k] == EdgeTag::kTear) ++num_tear_sides;
  ReferenceMesh r;
  r.vertex_values.resize(nv + num_edges, m.vertex_values.cols());
  r.color_values.resize(nc + num_edges + num_tear_sides, m.color_values.cols());
  r.vertex_tags = m.vertex_tags;
  r.vertex_tags.resize(nv + num_edges);
  apply_vertex_rules(Rule::kRefine, m, adj, r.vertex_values, r.color_values);

  // Edge points (Fig. 2e-g), remembered per face corner for the children below.
  std::vector<std::array<int, 3>> edge_vertex(nf), edge_color(nf);
  int next_vertex = nv, next_color = nc;
  for (const auto& [edge, corners] : adj.edge_corners) {
    const Corner c0 = corners[0];
    const EdgeTag tag = m.edge_tags[c0.face][c0.k];
    for (const Corner& c : corners) {
      if (m.edge_tags[c.face][c.k] != tag) throw std::logic_error("faces disagree on an edge tag");
    }
    if (tag == EdgeTag::kSmooth && corners.size() != 2)
      throw std::logic_error("smooth edge with one face");
    const int v = next_vertex++;
    r.vertex_tags[v] = edge_point_tag(tag);
    r.vertex_values.row(v) = edge_rule(m.vertex_values, m.triangles, c0,
                                       tag == EdgeTag::kSmooth ? &corners[1] : nullptr);

    // Colors: a tear gives each side its own value, from its own face; elsewhere both faces must
    // name the same values at the ends (the second face runs the edge the other way) and share one.
    if (tag != EdgeTag::kTear && corners.size() == 2) {
      const Corner c1 = corners[1];
      if (m.triangle_colors[c0.face][c0.k] != m.triangle_colors[c1.face][(c1.k + 1) % 3] ||
          m.triangle_colors[c0.face][(c0.k + 1) % 3] != m.triangle_colors[c1.face][c1.k]) {
        throw std::logic_error("color values differ across a non-tear edge");
      }
    }
    for (size_t i = 0; i < corners.size(); ++i) {
      const Corner c = corners[i];
      edge_vertex[c.face][c.k] = v;
      if (i > 0 && tag != EdgeTag::kTear) {
        edge_color[c.face][c.k] = edge_color[c0.face][c0.k];
        continue;
      }
      edge_color[c.face][c.k] = next_color;
      r.color_values.row(next_color++) =
          edge_rule(m.color_values, m.triangle_colors, c,
                    tag == EdgeTag::kSmooth ? &corners[1 - i] : nullptr);
    }
  }
  r.color_values.conservativeResize(next_color, Eigen::NoChange);

  // Each triangle (v0, v1, v2) with edge points e_k on (v_k, v_k+1) becomes (v0, e0, e2),
  // (e0, v1, e1), (e2, e1, v2) and (e0, e1, e2), in the same orientation. Child edges along a
  // parent edge inherit its tag; the three inner edges are smooth.
  const EdgeTag kS = EdgeTag::kSmooth;
  for (int f = 0; f < nf; ++f) {
    const Tri& v = m.triangles[f];
    const Tri& vc = m.triangle_colors[f];
    const auto& e = edge_vertex[f];
    const auto& ec = edge_color[f];
    const auto& t = m.edge_tags[f];
    const auto& uv = m.triangle_uv[f];
    auto mid = [&](int a, int b) {
      return std::array<double, 2>{(uv[a][0] + uv[b][0]) / 2, (uv[a][1] + uv[b][1]) / 2};
    };
    const std::array<std::array<double, 2>, 3> euv{mid(0, 1), mid(1, 2), mid(2, 0)};
    r.triangles.insert(r.triangles.end(), {Tri{v[0], e[0], e[2]}, Tri{e[0], v[1], e[1]},
                                           Tri{e[2], e[1], v[2]}, Tri{e[0], e[1], e[2]}});
    r.triangle_colors.insert(r.triangle_colors.end(),
                             {Tri{vc[0], ec[0], ec[2]}, Tri{ec[0], vc[1], ec[1]},
                              Tri{ec[2], ec[1], vc[2]}, Tri{ec[0], ec[1], ec[2]}});
    r.edge_tags.insert(
        r.edge_tags.end(),
        {std::array<EdgeTag, 3>{t[0], kS, t[2]}, std::array<EdgeTag, 3>{t[0], t[1], kS},
         std::array<EdgeTag, 3>{kS, t[1], t[2]}, std::array<EdgeTag, 3>{kS, kS, kS}});
    r.triangle_uv.insert(r.triangle_uv.end(), {{uv[0], euv[0], euv[2]},
                                               {euv[0], uv[1], euv[1]},
                                               {euv[2], euv[1], uv[2]},
                                               {euv[0], euv[1], euv[2]}});
    r.triangle_parent.insert(r.triangle_parent.end(), 4, m.triangle_parent[f]);
  }
  return r;
}

ReferenceMesh push_to_limit(const ReferenceMesh& m) {
  const Adjacency adj = build_adjacency(m);
  ReferenceMesh r = m;
  apply_vertex_rules(Rule::kLimit, m, adj, r.vertex_values, r.color_values);
  return r;
}

ReferenceMesh reference_loop(const ControlMesh& mesh, const MeshTopology& topology, int depth,
                             bool limit) {
  ReferenceMesh m = reference_control_mesh(mesh, topology);
  for (int level = 0; level < depth; ++level) m = refine(m);
  return limit ? push_to_limit(m) : m;
}

StencilMesh reference_stencils(const ControlMesh& mesh, const MeshTopology& topology, int depth,
                               bool limit) {
  ReferenceMesh m = reference_control_mesh(
      mesh, topology, Eigen::MatrixXd::Identity(mesh.num_vertices(), mesh.num_vertices()),
      Eigen::MatrixXd::Identity(mesh.num_colors(), mesh.num_colors()));
  for (int level = 0; level < depth; ++level) m = refine(m);
  if (limit) m = push_to_limit(m);
  StencilMesh s;
  s.position_stencils = std::move(m.vertex_values);
  s.color_stencils = std::move(m.color_values);
  s.positions = s.position_stencils * position_values(mesh);
  s.colors = s.color_stencils * color_values(mesh);
  std::set<EdgeKey> seen;
  for (int f = 0; f < m.num_triangles(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int a = m.triangles[f][k], b = m.triangles[f][(k + 1) % 3];
      const EdgeTag tag = m.edge_tags[f][k];
      if (tag == EdgeTag::kSmooth || !seen.insert(edge_key(a, b)).second) continue;
      (tag == EdgeTag::kTear     ? s.tear_edges
       : tag == EdgeTag::kCrease ? s.crease_edges
                                 : s.border_edges)
          .push_back({a, b});
    }
  }
  s.triangles = std::move(m.triangles);
  s.triangle_colors = std::move(m.triangle_colors);
  s.triangle_parent = std::move(m.triangle_parent);
  return s;
}

StencilMesh opensubdiv_stencils(const ControlMesh& mesh, const MeshTopology& topology, int depth,
                                bool limit) {
  const Subdivision subdivision(mesh, topology, depth, {}, limit);
  StencilMesh s;
  s.position_stencils = Eigen::MatrixXd(subdivision.position_stencils());
  s.color_stencils = Eigen::MatrixXd(subdivision.color_stencils());
  s.positions = s.position_stencils * position_values(mesh);
  s.colors = s.color_stencils * color_values(mesh);
  const RefinedMesh& refined = subdivision.topology();
  s.triangles = refined.triangles;
  s.triangle_colors = refined.triangle_colors;
  s.triangle_parent = refined.triangle_parent;
  s.tear_edges = refined.tear_edges;
  s.crease_edges = refined.crease_edges;
  s.border_edges = refined.border_edges;
  return s;
}

Eigen::MatrixXd position_values(const ControlMesh& mesh) {
  Eigen::MatrixXd p(mesh.num_vertices(), 2);
  for (int i = 0; i < mesh.num_vertices(); ++i)
    p.row(i) << mesh.positions[i].x, mesh.positions[i].y;
  return p;
}

Eigen::MatrixXd color_values(const ControlMesh& mesh) {
  Eigen::MatrixXd c(mesh.num_colors(), 3);
  for (int i = 0; i < mesh.num_colors(); ++i)
    c.row(i) << mesh.colors[i].r, mesh.colors[i].g, mesh.colors[i].b;
  return c;
}

std::vector<int> match_points(const Eigen::MatrixXd& points, const Eigen::MatrixXd& targets,
                              double tolerance) {
  // Targets sorted by x; each query scans the slab |x - x_query| <= tolerance.
  std::vector<int> order(targets.rows());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return targets(a, 0) < targets(b, 0); });
  std::vector<int> match(points.rows(), -1);
  for (int i = 0; i < points.rows(); ++i) {
    const double x = points(i, 0);
    auto it = std::lower_bound(order.begin(), order.end(), x - tolerance,
                               [&](int t, double value) { return targets(t, 0) < value; });
    double best = tolerance;
    for (; it != order.end() && targets(*it, 0) <= x + tolerance; ++it) {
      const double d = (targets.row(*it) - points.row(i)).norm();
      if (d <= best) {
        best = d;
        match[i] = *it;
      }
    }
  }
  return match;
}

}  // namespace subvec::testing
