// Objects as layers: see include/subvec/edit/objects.h for what each function does and why.
#include "subvec/edit/objects.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <set>
#include <span>
#include <string>
#include <vector>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "core/geometry_p.h"
#include "core/messages_p.h"
#include "edit/feature_edit_p.h"
#include "mesh/collapse_engine_p.h"
#include "mesh/coarsen_p.h"
#include "subvec/core/error.h"
#include "subvec/edit/feature_edit.h"
#include "subvec/mesh/topology.h"
#include "subvec/mesh/validate.h"
#include "subvec/render/renderer.h"

namespace subvec {
namespace {

using detail::invalid;
using detail::num;

double area(Vec2 a, Vec2 b, Vec2 c) {
  return 0.5 * ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
}

// Marks the edges of the closed vertex cycle `cycle` (first vertex repeated at the end).
std::vector<uint8_t> cycle_edges(const MeshTopology& topology, std::span<const int32_t> cycle) {
  std::vector<uint8_t> on(topology.num_edges(), 0);
  for (size_t i = 0; i + 1 < cycle.size(); ++i) on[topology.find_edge(cycle[i], cycle[i + 1])] = 1;
  return on;
}

// The faces of `mesh` on the side of the closed cycle of edges that does not reach the image
// border (1 inside, 0 outside). Throws when both sides reach it.
std::vector<uint8_t> inside_faces(const ControlMesh& mesh, const MeshTopology& topology,
                                  std::span<const int32_t> cycle, const std::string& what) {
  const std::vector<uint8_t> blocked = cycle_edges(topology, cycle);
  // Components of the faces, across every edge but the chain's.
  const int nf = mesh.num_triangles();
  std::vector<int32_t> component(nf, -1);
  std::vector<uint8_t> reaches_border;
  std::vector<int32_t> stack;
  for (int seed = 0; seed < nf; ++seed) {
    if (component[seed] >= 0) continue;
    const int32_t id = static_cast<int32_t>(reaches_border.size());
    reaches_border.push_back(0);
    component[seed] = id;
    stack.push_back(seed);
    while (!stack.empty()) {
      const int32_t f = stack.back();
      stack.pop_back();
      for (const int32_t e : topology.face_edges[f]) {
        if (blocked[e]) continue;
        const auto [a, b] = topology.edge_faces[e];
        if (b < 0) {
          reaches_border[id] = 1;
          continue;
        }
        const int32_t g = a == f ? b : a;
        if (component[g] < 0) {
          component[g] = id;
          stack.push_back(g);
        }
      }
    }
  }
  const int e0 = topology.find_edge(cycle[0], cycle[1]);
  const int32_t side_a = component[topology.edge_faces[e0][0]];
  const int32_t side_b = component[topology.edge_faces[e0][1]];
  if (reaches_border[side_a] == reaches_border[side_b]) {
    invalid(what + " does not enclose a region apart from the image border");
  }
  const int32_t inner = reaches_border[side_a] ? side_b : side_a;
  std::vector<uint8_t> inside(nf, 0);
  for (int f = 0; f < nf; ++f) inside[f] = component[f] == inner;
  return inside;
}

// Splits the features into the runs of edges on one side of the curve: edges whose faces are
// inside go to `in`, the others (those of the curve too: it stays a tear of the level) to `out`.
// The first run of a feature in each mesh keeps its id; later ones take ids from `next_id`.
void split_features(const ControlMesh& mesh, const MeshTopology& topology,
                    const std::vector<uint8_t>& inside, const std::vector<uint8_t>& on_curve,
                    int32_t& next_id, std::vector<Feature>& in, std::vector<Feature>& out) {
  for (int g = 0; g < static_cast<int>(mesh.features.size()); ++g) {
    const Feature& feature = mesh.features[g];
    std::vector<int32_t> v = feature.vertices;
    const size_t edges = v.size() - 1;
    auto side = [&](size_t i) {
      const int e = topology.find_edge(v[i], v[i + 1]);
      return !on_curve[e] && inside[topology.edge_faces[e][0]] != 0;
    };
    if (feature.closed()) {
      // Start a closed chain where it changes side, if it does.
      for (size_t i = 1; i <= edges; ++i) {
        if (side(i % edges) != side(i - 1)) {
          std::vector<int32_t> turned(v.begin() + long(i % edges), v.end() - 1);
          turned.insert(turned.end(), v.begin(), v.begin() + long(i % edges) + 1);
          v = std::move(turned);
          break;
        }
      }
    }
    bool first_in = true, first_out = true;
    size_t begin = 0;
    for (size_t i = 1; i <= edges; ++i) {
      if (i < edges && side(i) == side(begin)) continue;
      const bool is_in = side(begin);
      Feature run = feature;
      run.vertices.assign(v.begin() + long(begin), v.begin() + long(i) + 1);
      bool& first = is_in ? first_in : first_out;
      if (!first) run.id = next_id++;
      first = false;
      (is_in ? in : out).push_back(std::move(run));
      begin = i;
    }
  }
}

// The object: the inside faces, their vertices and colors renumbered in ascending order.
ControlMesh object_mesh(const ControlMesh& mesh, const MeshTopology& topology,
                        const std::vector<uint8_t>& inside, std::vector<Feature> features) {
  std::vector<int32_t> vmap(mesh.num_vertices(), -1), cmap(mesh.num_colors(), -1);
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    if (!inside[f]) continue;
    for (int k = 0; k < 3; ++k) {
      vmap[mesh.triangles[f][k]] = 0;
      cmap[mesh.triangle_colors[f][k]] = 0;
    }
  }
  ControlMesh o;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (vmap[v] < 0) continue;
    vmap[v] = o.num_vertices();
    o.positions.push_back(mesh.positions[v]);
  }
  for (int c = 0; c < mesh.num_colors(); ++c) {
    if (cmap[c] < 0) continue;
    cmap[c] = o.num_colors();
    o.colors.push_back(mesh.colors[c]);
  }
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    if (!inside[f]) continue;
    Tri t, tc;
    for (int k = 0; k < 3; ++k) t[k] = vmap[mesh.triangles[f][k]], tc[k] = cmap[mesh.triangle_colors[f][k]];
    o.triangles.push_back(t);
    o.triangle_colors.push_back(tc);
  }
  for (const EdgeVerts& e : mesh.creases) {
    if (inside[topology.edge_faces[topology.find_edge(e[0], e[1])][0]])
      o.creases.push_back({vmap[e[0]], vmap[e[1]]});
  }
  for (Feature& f : features) {
    for (int32_t& v : f.vertices) v = vmap[v];
  }
  o.features = std::move(features);
  return o;
}

// The smoothest fill of the hole's colors. With L the uniform Laplacian of the hole's triangles
// (a curve vertex's row over its neighbours in the hole), minimizes
//   sum over the hole's vertices and the curve's of |(L c)_v|^2
//   + kCurveWeight * sum over the curve of |c_v - o_v|^2
// where o_v is the mean color of v's outside neighbours off the curve (past the colors that
// fitted the tear's edge): a thin plate whose edge follows the colors around the hole, and bends
// away from them where they jump along the curve (below: the pull is robust). Sets the colors of
// the hole's corners.
constexpr double kCurveWeight = 1.0;
constexpr double kCurveRobust = 8.0;
constexpr int kCurveIterations = 5;

void fill_hole_colors(ControlMesh& mesh, const std::vector<uint8_t>& hole_face) {
  const int nv = mesh.num_vertices(), nf = mesh.num_triangles();
  std::vector<uint8_t> touches_hole(nv, 0), touches_outside(nv, 0);
  std::vector<std::set<int32_t>> outside_colors(nv);
  std::vector<std::set<int32_t>> neighbours(nv);  // within the hole
  for (int f = 0; f < nf; ++f) {
    const Tri& t = mesh.triangles[f];
    for (int k = 0; k < 3; ++k) {
      (hole_face[f] ? touches_hole : touches_outside)[t[k]] = 1;
      if (hole_face[f]) {
        neighbours[t[k]].insert(t[(k + 1) % 3]);
        neighbours[t[k]].insert(t[(k + 2) % 3]);
      }
    }
  }
  // The colors around the hole: at each curve vertex, those of its outside neighbours off the
  // curve (a control edge away from the tear, past the colors that fitted its edge), or its own
  // outside colors where it has no such neighbour.
  for (int pass = 0; pass < 2; ++pass) {
    for (int f = 0; f < nf; ++f) {
      if (hole_face[f]) continue;
      const Tri& t = mesh.triangles[f];
      for (int k = 0; k < 3; ++k) {
        const int32_t v = t[k];
        if (!touches_hole[v]) continue;
        for (const int d : {1, 2}) {
          const int j = (k + d) % 3;
          if (pass == 0 ? !touches_hole[t[j]] : outside_colors[v].empty() && t[j] == v)
            outside_colors[v].insert(mesh.triangle_colors[f][j]);
        }
        if (pass == 1 && outside_colors[v].empty()) outside_colors[v].insert(mesh.triangle_colors[f][k]);
      }
    }
  }
  // Every vertex of the hole is an unknown; the curve's are pulled to their outside means.
  std::vector<int32_t> unknown(nv, -1);
  int n = 0;
  for (int v = 0; v < nv; ++v) {
    if (touches_hole[v]) unknown[v] = n++;
  }
  std::vector<Eigen::Triplet<double>> entries;
  std::vector<int32_t> curve;           // the curve's unknowns
  std::vector<Eigen::Vector3d> target;  // and their outside colors
  int rows = 0;
  for (int v = 0; v < nv; ++v) {
    if (!touches_hole[v]) continue;
    const double w = 1.0 / double(neighbours[v].size());
    entries.emplace_back(rows, unknown[v], 1.0);
    for (const int32_t x : neighbours[v]) entries.emplace_back(rows, unknown[x], -w);
    ++rows;
    if (!touches_outside[v]) continue;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const int32_t c : outside_colors[v]) {
      const Color k = mesh.colors[c];
      mean += Eigen::Vector3d(k.r, k.g, k.b);
    }
    curve.push_back(unknown[v]);
    target.push_back(mean / double(outside_colors[v].size()));
  }
  Eigen::SparseMatrix<double> laplacian(rows, n);
  laplacian.setFromTriplets(entries.begin(), entries.end());
  const Eigen::SparseMatrix<double> smooth = laplacian.transpose() * laplacian;
  // Iteratively reweighted: a curve vertex whose fill lands more than kCurveRobust levels from
  // its outside color is pulled less (Huber), so an odd color on the rim (a piece of the object
  // left outside its curve) does not bend the fill around it.
  std::vector<double> weight(curve.size(), kCurveWeight);
  Eigen::MatrixX3d solution;
  for (int iteration = 0; iteration < kCurveIterations; ++iteration) {
    Eigen::SparseMatrix<double> normal = smooth;
    Eigen::MatrixX3d b = Eigen::MatrixX3d::Zero(n, 3);
    for (size_t i = 0; i < curve.size(); ++i) {
      normal.coeffRef(curve[i], curve[i]) += weight[i];
      b.row(curve[i]) += weight[i] * target[i].transpose();
    }
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
    if (solver.info() != Eigen::Success) invalid("the hole's color fill could not be solved");
    solution = solver.solve(b);
    for (size_t i = 0; i < curve.size(); ++i) {
      const double r = (solution.row(curve[i]).transpose() - target[i]).norm();
      weight[i] = kCurveWeight * std::min(1.0, kCurveRobust / std::max(r, 1e-9));
    }
  }
  auto clamp = [](double x) { return static_cast<float>(std::clamp(x, 0.0, 255.0)); };
  for (int f = 0; f < nf; ++f) {
    if (!hole_face[f]) continue;
    for (int k = 0; k < 3; ++k) {
      const auto x = solution.row(unknown[mesh.triangles[f][k]]);
      mesh.colors[mesh.triangle_colors[f][k]] = {clamp(x[0]), clamp(x[1]), clamp(x[2])};
    }
  }
}

// Whether p lies on the closed polygon through `points` (within 1e-6 px).
bool on_polygon(std::span<const Vec2> points, Vec2 p) {
  for (size_t i = 0, j = points.size() - 1; i < points.size(); j = i++) {
    const Vec2 a = points[j], b = points[i];
    const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
    const double t = len2 > 0 ? std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / len2, 0.0, 1.0) : 0.0;
    if (std::hypot(a.x + t * dx - p.x, a.y + t * dy - p.y) <= 1e-6) return true;
  }
  return false;
}

// The closed cycle of control edges around the faces whose centroid `mask` holds: the largest
// edge-connected group of them (faces with a vertex on the image border left out), its holes
// filled, and the faces round any vertex the outline would pass twice added, so that the outline
// is one simple loop. Returns it closed (first == last), or empty when nothing is left.
std::vector<int32_t> cycle_around_mask(const ControlMesh& mesh, const MeshTopology& topology, const RegionMask& mask,
                                       int width, int height) {
  const int nf = mesh.num_triangles();
  std::vector<uint8_t> on_border(mesh.num_vertices(), 0);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Vec2 p = mesh.positions[v];
    on_border[v] = p.x <= 0 || p.y <= 0 || p.x >= width || p.y >= height;
  }
  std::vector<uint8_t> inside(nf, 0);
  std::vector<double> area_of(nf, 0);
  for (int f = 0; f < nf; ++f) {
    const Tri& t = mesh.triangles[f];
    const Vec2 a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
    area_of[f] = area(a, b, c);
    if (on_border[t[0]] || on_border[t[1]] || on_border[t[2]]) continue;
    const int x = std::clamp(static_cast<int>((a.x + b.x + c.x) / 3), 0, mask.width - 1);
    const int y = std::clamp(static_cast<int>((a.y + b.y + c.y) / 3), 0, mask.height - 1);
    inside[f] = mask.at(x, y);
  }
  auto across = [&](int f, int k) {
    const auto& ef = topology.edge_faces[topology.face_edges[f][k]];
    return ef[0] == f ? ef[1] : ef[0];
  };
  // The largest group.
  std::vector<int> group(nf, -1), queue;
  int best = -1;
  double best_area = 0;
  for (int f0 = 0; f0 < nf; ++f0) {
    if (!inside[f0] || group[f0] >= 0) continue;
    double sum = 0;
    queue.assign(1, f0);
    group[f0] = f0;
    for (size_t q = 0; q < queue.size(); ++q) {
      sum += area_of[queue[q]];
      for (int k = 0; k < 3; ++k) {
        const int g = across(queue[q], k);
        if (g >= 0 && inside[g] && group[g] < 0) group[g] = f0, queue.push_back(g);
      }
    }
    if (sum > best_area) best = f0, best_area = sum;
  }
  if (best < 0) return {};
  for (int f = 0; f < nf; ++f) inside[f] = group[f] == best;
  for (int round = 0; round < 32; ++round) {
    // Holes: the faces outside that the outside cannot reach from the image border.
    std::vector<uint8_t> reached(nf, 0);
    queue.clear();
    for (int f = 0; f < nf; ++f) {
      if (inside[f]) continue;
      for (int k = 0; k < 3; ++k)
        if (across(f, k) < 0 && !reached[f]) reached[f] = 1, queue.push_back(f);
    }
    for (size_t q = 0; q < queue.size(); ++q) {
      for (int k = 0; k < 3; ++k) {
        const int g = across(queue[q], k);
        if (g >= 0 && !inside[g] && !reached[g]) reached[g] = 1, queue.push_back(g);
      }
    }
    for (int f = 0; f < nf; ++f)
      if (!inside[f] && !reached[f]) inside[f] = 1;
    // The outline's directed edges; a vertex that starts two is a pinch.
    std::vector<int> starts(mesh.num_vertices(), 0);
    for (int f = 0; f < nf; ++f) {
      if (!inside[f]) continue;
      for (int k = 0; k < 3; ++k) {
        const int g = across(f, k);
        if (g < 0 || !inside[g]) ++starts[mesh.triangles[f][k]];
      }
    }
    bool pinched = false;
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      if (starts[v] < 2) continue;
      pinched = true;
      const auto [b, e] = topology.faces_of(v);
      for (const int32_t* f = b; f != e; ++f) inside[*f] = 1;
    }
    if (pinched) continue;
    std::vector<int32_t> next(mesh.num_vertices(), -1);
    int first = -1, count = 0;
    for (int f = 0; f < nf; ++f) {
      if (!inside[f]) continue;
      for (int k = 0; k < 3; ++k) {
        const int g = across(f, k);
        if (g >= 0 && inside[g]) continue;
        const int32_t a = mesh.triangles[f][k], b = mesh.triangles[f][(k + 1) % 3];
        if (on_border[a] || on_border[b]) return {};  // (pinches grew it to the border)
        next[a] = b, ++count;
        if (first < 0 || a < first) first = a;
      }
    }
    std::vector<int32_t> cycle{first};
    for (int steps = 0; steps < count; ++steps) cycle.push_back(next[cycle.back()]);
    if (cycle.back() != first || cycle.size() < 4) return {};  // more than one loop
    return cycle;
  }
  return {};
}

// Makes every edge of `cycle` (closed) a tear: its runs of edges that are not tears yet become
// new features (a crease among them stops being one), and the colors split along them, each side
// keeping its value, so the picture is unchanged but for the tear rules along the new edges.
void tear_along(ControlMesh& mesh, int width, int height, const MeshTopology& topology,
                const std::vector<int32_t>& cycle) {
  const size_t n = cycle.size() - 1;  // edges
  std::vector<uint8_t> tear(n);
  for (size_t i = 0; i < n; ++i) tear[i] = topology.edge_tags[topology.find_edge(cycle[i], cycle[i + 1])] == EdgeTag::kTear;
  std::erase_if(mesh.creases, [&](const EdgeVerts& c) {
    for (size_t i = 0; i < n; ++i)
      if (std::minmax(c[0], c[1]) == std::minmax(cycle[i], cycle[i + 1])) return true;
    return false;
  });
  int32_t next_id = 0;
  for (const Feature& f : mesh.features) next_id = std::max(next_id, f.id + 1);
  const size_t start = std::find(tear.begin(), tear.end(), 1) - tear.begin();
  if (start == n) {
    mesh.features.push_back({next_id, cycle, 0.0});  // no tear on the way: one closed feature
  } else {
    // Runs of non-tear edges, from the first tear edge round.
    Feature run{next_id, {}, 0.0};
    for (size_t k = 1; k <= n; ++k) {
      const size_t i = (start + k) % n;
      if (tear[i]) {
        if (!run.vertices.empty()) mesh.features.push_back(run), run = {++next_id, {}, 0.0};
        continue;
      }
      if (run.vertices.empty()) run.vertices.push_back(cycle[i]);
      run.vertices.push_back(cycle[i + 1]);
    }
    if (!run.vertices.empty()) mesh.features.push_back(run);
  }
  edit_detail::split_colors_at_tears(mesh, MeshTopology::build(mesh, width, height));
}

Object& object_at(VectorImage& image, int object) {
  if (object < 0 || object >= static_cast<int>(image.objects.size())) {
    invalid("object " + std::to_string(object) + " is out of range (" +
            std::to_string(image.objects.size()) + " objects)");
  }
  return image.objects[object];
}

}  // namespace

namespace {

// make_object() along a closed cycle of tear edges of the level (first vertex repeated at the end),
// which may be one closed feature or parts of several meeting at junctions.
MakeObjectResult make_object_along(VectorImage& image, int level, std::vector<int32_t> cycle,
                                   const MeshTopology& topology, const std::string& what,
                                   const std::string& name) {
  const ControlMesh& mesh = image.levels[level];
  const std::vector<uint8_t> inside = inside_faces(mesh, topology, cycle, what);
  const std::vector<uint8_t> on_curve = cycle_edges(topology, cycle);
  std::vector<Vec2> curve;
  for (const int32_t v : cycle) curve.push_back(mesh.positions[v]);

  int32_t next_id = 0;
  for (const Feature& f : mesh.features) next_id = std::max(next_id, f.id + 1);
  std::vector<Feature> in, out;
  split_features(mesh, topology, inside, on_curve, next_id, in, out);
  MakeObjectResult result;
  result.features_moved = static_cast<int>(in.size());

  Object object;
  object.level = level;
  object.name = name;
  object.mesh = object_mesh(mesh, topology, inside, std::move(in));
  result.object_vertices = object.mesh.num_vertices();

  // The background: the same triangles, the features and creases outside (and the curve's),
  // colors renumbered by the tears that remain (one value per hole vertex, one on the hole's side
  // of each curve vertex).
  ControlMesh back;
  back.positions = mesh.positions;
  back.triangles = mesh.triangles;
  back.features = std::move(out);
  for (const EdgeVerts& e : mesh.creases) {
    if (!inside[topology.edge_faces[topology.find_edge(e[0], e[1])][0]]) back.creases.push_back(e);
  }
  {
    const MeshTopology t = MeshTopology::build(back, image.width, image.height);
    int nc = 0;
    back.triangle_colors = face_varying_indices(back, t, nc);
    back.colors.assign(nc, Color{});
    for (int f = 0; f < back.num_triangles(); ++f) {
      for (int k = 0; k < 3; ++k) {
        if (!inside[f]) back.colors[back.triangle_colors[f][k]] = mesh.colors[mesh.triangle_colors[f][k]];
      }
    }
  }
  // Simplify the hole to the level's mean density.
  double hole_area = 0;
  std::vector<uint8_t> hole_vertex(back.num_vertices(), 1);
  for (int f = 0; f < back.num_triangles(); ++f) {
    const Tri& t = back.triangles[f];
    if (inside[f]) {
      hole_area += area(back.positions[t[0]], back.positions[t[1]], back.positions[t[2]]);
    } else {
      for (const int32_t v : t) hole_vertex[v] = 0;
    }
  }
  const int target = static_cast<int>(std::lround(
      hole_area * mesh.num_vertices() / (double(image.width) * double(image.height))));
  std::vector<int32_t> kept;
  for (const Feature& f : back.features) kept.push_back(f.id);
  coarsen_detail::Coarsener coarsener(back, image.width, image.height, kept);
  result.removed = static_cast<int>(coarsen_detail::collapse_shortest_first(coarsener, hole_vertex, target).size());
  std::vector<int32_t> parents, color_merged;
  back = coarsener.result(parents, color_merged);
  // The hole's faces after the collapses: those inside the curve (whose vertices all stay),
  // found again in the new numbering.
  std::vector<int32_t> renumbered(mesh.num_vertices(), -1);
  for (size_t v = 0; v < parents.size(); ++v) renumbered[parents[v]] = static_cast<int32_t>(v);
  for (int32_t& v : cycle) v = renumbered[v];
  const MeshTopology t = MeshTopology::build(back, image.width, image.height);
  const std::vector<uint8_t> hole = inside_faces(back, t, cycle, what);
  fill_hole_colors(back, hole);
  for (const int32_t p : parents) result.fill_vertices += hole_vertex[p];

  // The level's strokes on the object (at least half their points inside the curve or on it: the
  // curve's own stroke outlines the object) go with it.
  std::vector<Stroke> strokes;
  for (const Stroke& stroke : image.strokes) {
    size_t in_curve = 0;
    if (stroke.level == level) {
      for (const Vec2& p : stroke.points) in_curve += detail::inside_polygon(curve, p.x, p.y) || on_polygon(curve, p);
    }
    (2 * in_curve >= stroke.points.size() && in_curve > 0 ? object.strokes : strokes).push_back(stroke);
  }
  result.strokes_moved = static_cast<int>(object.strokes.size());

  validate_level(back, image.width, image.height, level);
  validate_object(object, image.width, image.height, static_cast<int>(image.levels.size()),
                  static_cast<int>(image.objects.size()));
  image.strokes = std::move(strokes);
  image.levels[level] = std::move(back);
  if (level + 1 < static_cast<int>(image.levels.size())) {
    image.levels[level + 1].parent_vertices.clear();
    image.levels[level + 1].collapses.clear();
  }
  image.objects.push_back(std::move(object));
  result.object = static_cast<int>(image.objects.size()) - 1;
  return result;
}

// The area of a closed feature's control polygon, square pixels.
double polygon_area(const ControlMesh& mesh, const Feature& feature) {
  double twice = 0;
  for (size_t i = 0; i + 1 < feature.vertices.size(); ++i) {
    const Vec2 a = mesh.positions[feature.vertices[i]], b = mesh.positions[feature.vertices[i + 1]];
    twice += a.x * b.y - b.x * a.y;
  }
  return std::abs(twice) / 2;
}

void check_level_index(const VectorImage& image, int level) {
  if (level < 0 || level >= static_cast<int>(image.levels.size())) {
    invalid("level " + std::to_string(level) + " is out of range (" +
            std::to_string(image.levels.size()) + " levels)");
  }
}

}  // namespace

MakeObjectResult make_object(VectorImage& image, int level, int feature, const std::string& name) {
  check_level_index(image, level);
  const ControlMesh& mesh = image.levels[level];
  if (feature < 0 || feature >= static_cast<int>(mesh.features.size())) {
    invalid("feature " + std::to_string(feature) + " is out of range (" +
            std::to_string(mesh.features.size()) + " features on level " + std::to_string(level) + ")");
  }
  const Feature& chain = mesh.features[feature];
  const std::string what = "feature " + std::to_string(feature) + " (id " + std::to_string(chain.id) + ")";
  if (!chain.closed()) invalid(what + " is open; an object needs a closed feature");
  {
    std::vector<int32_t> sorted(chain.vertices.begin(), chain.vertices.end() - 1);
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
      invalid(what + " passes through a vertex twice; an object needs a simple closed curve");
  }
  const MeshTopology topology = validate_level(mesh, image.width, image.height, level);
  return make_object_along(image, level, chain.vertices, topology, what, name);
}

constexpr double kFramedShare = 0.2;

MakeObjectResult make_object_in_rect(VectorImage& image, int level, const PixelRect& rect,
                                     const std::string& name) {
  check_level_index(image, level);
  // A closed tear inside the rectangle: the largest.
  const ControlMesh& mesh = image.levels[level];
  int best = -1;
  double best_area = 0;
  for (int f = 0; f < static_cast<int>(mesh.features.size()); ++f) {
    const Feature& feature = mesh.features[f];
    if (!feature.closed()) continue;
    const bool within = std::all_of(feature.vertices.begin(), feature.vertices.end(), [&](int32_t v) {
      const Vec2 a = mesh.positions[v];
      return a.x >= rect.x && a.x <= rect.x + rect.width && a.y >= rect.y && a.y <= rect.y + rect.height;
    });
    const double a = polygon_area(mesh, feature);
    if (within && (best < 0 || a > best_area)) best = f, best_area = a;
  }
  // It must be what the rectangle frames, not a detail inside it: a fifth of its area at least.
  if (best >= 0 && best_area < kFramedShare * double(rect.width) * double(rect.height)) best = -1;
  if (best >= 0) return make_object(image, level, best, name);

  // GrabCut on the level as drawn (without its objects), then its boundary cut in as a tear.
  VectorImage alone;
  alone.width = image.width;
  alone.height = image.height;
  alone.levels.push_back(mesh);
  RenderOptions options;
  const RegionMask mask = segment_foreground(render(alone, options), rect);
  const std::vector<DetectedFeature> boundary = region_boundary_features(mask);
  if (boundary.size() != 1 || !boundary[0].closed()) {
    invalid("the foreground GrabCut finds in the rectangle reaches the image border; an object needs a closed boundary");
  }
  VectorImage work = image;
  ControlMesh& cut = work.levels[level];
  const int before = static_cast<int>(cut.features.size());
  FeatureEditResult added;
  try {
    added = add_feature(cut, image.width, image.height, boundary[0].points, FeatureKind::kTear);
  } catch (const Error& e) {
    // Where the boundary runs along features at a glancing angle, its fitted curve would cross
    // them between control points, and add_feature refuses it. Then the object's outline is the
    // cycle of control edges round the faces GrabCut's foreground holds: it follows the tears
    // where the foreground does, and is made a tear where it is not one yet (the picture does not
    // change but for the tear rules along it).
    const MeshTopology topology = validate_level(mesh, image.width, image.height, level);
    const std::vector<int32_t> cycle = cycle_around_mask(mesh, topology, mask, image.width, image.height);
    if (cycle.empty()) {
      invalid(std::string("the boundary GrabCut finds in the rectangle cannot be cut in (") + e.what() +
              "), nor followed along control edges; make an object of a closed feature instead (draw one with the pen)");
    }
    ControlMesh along = mesh;
    tear_along(along, image.width, image.height, topology, cycle);
    work.levels[level] = std::move(along);
    const MeshTopology now = validate_level(work.levels[level], image.width, image.height, level);
    MakeObjectResult result =
        make_object_along(work, level, cycle, now, "the control edges round the foreground in the rectangle", name);
    result.along_edges = true;
    image = std::move(work);
    return result;
  }
  // The curve: the new pieces, joined end to end at their junctions.
  std::vector<std::vector<int32_t>> pieces;
  for (int f = before; f < static_cast<int>(cut.features.size()); ++f) pieces.push_back(cut.features[f].vertices);
  std::vector<int32_t> cycle = pieces.front();
  std::vector<uint8_t> used(pieces.size(), 0);
  used[0] = 1;
  for (size_t joined = 1; joined < pieces.size(); ++joined) {
    bool found = false;
    for (size_t k = 0; k < pieces.size() && !found; ++k) {
      if (used[k]) continue;
      std::vector<int32_t> piece = pieces[k];
      if (piece.back() == cycle.back()) std::reverse(piece.begin(), piece.end());
      if (piece.front() != cycle.back()) continue;
      cycle.insert(cycle.end(), piece.begin() + 1, piece.end());
      used[k] = found = true;
    }
    if (!found) break;
  }
  if (cycle.size() < 4 || cycle.front() != cycle.back()) {
    invalid("the boundary GrabCut finds does not close after meeting " + std::to_string(added.junctions) +
            " features; draw the object's outline with the pen instead");
  }
  const MeshTopology topology = validate_level(cut, image.width, image.height, level);
  const std::string what = "the boundary of the foreground in the rectangle";
  MakeObjectResult result = make_object_along(work, level, cycle, topology, what, name);
  image = std::move(work);
  return result;
}

int closed_feature_around(const ControlMesh& mesh, Vec2 p) {
  int best = -1;
  double best_area = 0;
  for (int f = 0; f < static_cast<int>(mesh.features.size()); ++f) {
    const Feature& feature = mesh.features[f];
    if (!feature.closed()) continue;
    std::vector<Vec2> polygon;
    for (const int32_t v : feature.vertices) polygon.push_back(mesh.positions[v]);
    const bool inside = detail::inside_polygon(polygon, p.x, p.y);
    const double area = polygon_area(mesh, feature);
    if (inside && (best < 0 || area < best_area)) best = f, best_area = area;
  }
  return best;
}

Vec2 object_center(const Object& object) {
  const std::vector<Vec2>& p = object.mesh.positions;
  if (p.empty()) return {};
  double x0 = p[0].x, x1 = p[0].x, y0 = p[0].y, y1 = p[0].y;
  for (const Vec2& q : p) {
    x0 = std::min(x0, q.x), x1 = std::max(x1, q.x), y0 = std::min(y0, q.y), y1 = std::max(y1, q.y);
  }
  return {0.5 * (x0 + x1), 0.5 * (y0 + y1)};
}

void transform_object(VectorImage& image, int object, const ObjectTransform& transform) {
  Object& o = object_at(image, object);
  const Vec2 pivot = transform.pivot.value_or(object_center(o));
  for (const auto& [field, value] :
       {std::pair{"translate x", transform.translate.x}, {"translate y", transform.translate.y},
        {"rotate", transform.rotate_degrees}, {"pivot x", pivot.x}, {"pivot y", pivot.y}}) {
    if (!std::isfinite(value)) invalid(std::string(field) + " " + num(value) + " is not finite");
  }
  detail::check_positive("scale", transform.scale);
  const double angle = transform.rotate_degrees * std::numbers::pi / 180;
  const double c = transform.scale * std::cos(angle), s = transform.scale * std::sin(angle);
  auto move = [&](Vec2& p) {
    const double x = p.x - pivot.x, y = p.y - pivot.y;
    p = {pivot.x + c * x - s * y + transform.translate.x, pivot.y + s * x + c * y + transform.translate.y};
  };
  Object check = o;
  for (Vec2& p : check.mesh.positions) move(p);
  // Its strokes move with it, their widths scaled (a stroke is the same shape at any scale).
  for (Stroke& stroke : check.strokes) {
    for (Vec2& p : stroke.points) move(p);
    stroke.width = static_cast<float>(stroke.width * transform.scale);
  }
  // A scale of 1e-300 or a translation of 1e30 is refused by the object's validation, unchanged.
  validate_object(check, image.width, image.height, static_cast<int>(image.levels.size()), object);
  o = std::move(check);
}

void set_object_visible(VectorImage& image, int object, bool visible) {
  object_at(image, object).visible = visible;
}

void reorder_object(VectorImage& image, int object, int to) {
  object_at(image, object);
  if (to < 0 || to >= static_cast<int>(image.objects.size())) {
    invalid("position " + std::to_string(to) + " is out of range (" +
            std::to_string(image.objects.size()) + " objects)");
  }
  Object moving = std::move(image.objects[object]);
  image.objects.erase(image.objects.begin() + object);
  image.objects.insert(image.objects.begin() + to, std::move(moving));
}

}  // namespace subvec
