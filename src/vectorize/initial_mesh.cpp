// The dense initial mesh. This is the only translation unit that includes CGAL (it compiles
// slowly); everything CGAL-specific stays in this file.
#include "subvec/vectorize/initial_mesh.h"

#include <algorithm>
#include <cmath>
#include <set>

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Constrained_triangulation_plus_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include "core/geometry_p.h"
#include "mesh/disjoint_sets_p.h"
#include "subvec/core/error.h"

namespace subvec {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_2<int32_t, Kernel>;
using FaceBase =
    CGAL::Constrained_triangulation_face_base_2<Kernel, CGAL::Triangulation_face_base_with_info_2<int32_t, Kernel>>;
using Tds = CGAL::Triangulation_data_structure_2<VertexBase, FaceBase>;
// Exact_predicates_tag: constraints may cross (features that touch after subpixel location);
// CGAL then inserts their intersection point instead of throwing.
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<Kernel, Tds, CGAL::Exact_predicates_tag>;
using CdtPlus = CGAL::Constrained_triangulation_plus_2<Cdt>;
using Point = Kernel::Point_2;

// Pixels whose centre lies closer than r to a feature's polyline; with `corners`, the (w + 1) x
// (h + 1) pixel corners instead.
std::vector<uint8_t> near_features(const std::vector<DetectedFeature>& features, int w, int h, double r,
                                   bool corners = false) {
  // A pixel corner (x, y) is the centre of pixel (x, y) of the grid shifted by half a pixel.
  const double shift = corners ? 0.5 : 0.0;
  const int mw = corners ? w + 1 : w, mh = corners ? h + 1 : h;
  std::vector<uint8_t> mask(size_t(mw) * mh, 0);
  for (const DetectedFeature& f : features) {
    for (size_t i = 0; i + 1 < f.points.size(); ++i) {
      const Vec2 a = f.points[i], b = f.points[i + 1];
      detail::for_pixels_near_segment(a.x + shift, a.y + shift, b.x + shift, b.y + shift, r, mw, mh,
                                      [&](int x, int y) { mask[size_t(y) * mw + x] = 1; });
    }
  }
  return mask;
}

// The points to triangulate: pixel centres not `dropped` (step 1); or a quadtree of step x step
// blocks (2, 4 or 8), where a block with no `fine` pixel and whose centre (a pixel corner) is not
// `dropped_corner` is one point at its centre, and any other block is its four quarters, down to
// the pixel centres. Then the border: corners and one vertex per pixel along each side.
// `block_at` gets the size of the block centred at each pixel corner ((w + 1) x (h + 1); 0: none).
std::vector<Point> grid_points(int w, int h, int step, const std::vector<uint8_t>& dropped,
                               const std::vector<uint8_t>& fine, const std::vector<uint8_t>& dropped_corner,
                               std::vector<uint8_t>& block_at) {
  std::vector<Point> points;
  points.reserve(step == 1 ? size_t(w) * h + 2 * size_t(w + h) + 4 : size_t(w) * h / 8);
  if (step == 1) {
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        if (!dropped[size_t(y) * w + x]) points.emplace_back(x + 0.5, y + 0.5);
  } else {
    block_at.assign(size_t(w + 1) * (h + 1), 0);
    const auto block = [&](auto&& self, int bx, int by, int s) -> void {
      if (bx >= w || by >= h) return;
      if (s == 1) {
        if (!dropped[size_t(by) * w + bx]) points.emplace_back(bx + 0.5, by + 0.5);
        return;
      }
      const int half = s / 2;
      bool coarse = bx + s <= w && by + s <= h && !dropped_corner[size_t(by + half) * (w + 1) + bx + half];
      for (int y = by; coarse && y < by + s; ++y)
        for (int x = bx; coarse && x < bx + s; ++x) coarse = !fine[size_t(y) * w + x];
      if (coarse) {
        points.emplace_back(bx + half, by + half);
        block_at[size_t(by + half) * (w + 1) + bx + half] = static_cast<uint8_t>(s);
        return;
      }
      self(self, bx, by, half), self(self, bx + half, by, half);
      self(self, bx, by + half, half), self(self, bx + half, by + half, half);
    };
    for (int by = 0; by < h; by += step)
      for (int bx = 0; bx < w; bx += step) block(block, bx, by, step);
  }
  points.emplace_back(0, 0), points.emplace_back(w, 0), points.emplace_back(w, h), points.emplace_back(0, h);
  for (int x = 0; x < w; ++x) points.emplace_back(x + 0.5, 0), points.emplace_back(x + 0.5, h);
  for (int y = 0; y < h; ++y) points.emplace_back(0, y + 0.5), points.emplace_back(w, y + 0.5);
  return points;
}

// Each feature, clamped to the domain, as a constraint of the triangulation.
std::vector<CdtPlus::Constraint_id> insert_features(CdtPlus& cdt, const std::vector<DetectedFeature>& features,
                                                    int w, int h) {
  std::vector<CdtPlus::Constraint_id> ids;
  for (const DetectedFeature& f : features) {
    std::vector<Point> poly;
    const size_t n = f.closed() ? f.points.size() - 1 : f.points.size();
    for (size_t i = 0; i < n; ++i) {
      const Vec2 p{std::clamp(f.points[i].x, 0.0, double(w)), std::clamp(f.points[i].y, 0.0, double(h))};
      if (poly.empty() || poly.back() != Point(p.x, p.y)) poly.emplace_back(p.x, p.y);
    }
    if (poly.size() < 2) continue;
    ids.push_back(cdt.insert_constraint(poly.begin(), poly.end(), f.closed()));
  }
  return ids;
}

// Positions and triangles, numbering the triangulation's vertices and faces (their info()).
ControlMesh mesh_of(CdtPlus& cdt) {
  ControlMesh mesh;
  int32_t next = 0;
  for (auto v : cdt.finite_vertex_handles()) {
    v->info() = next++;
    mesh.positions.push_back({v->point().x(), v->point().y()});
  }
  next = 0;
  for (auto f : cdt.finite_face_handles()) {
    f->info() = next++;
    mesh.triangles.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});
  }
  return mesh;
}

// Face-varying colors: the corners of a vertex share one color value unless a tear (a
// constrained interior edge) separates them; values numbered in order of first use, as
// face_varying_indices() (topology.h) numbers them. Only vertices on a constraint can have
// several: around each of those, a union of the corners across every unconstrained edge, read
// off the triangulation's adjacency. Sets mesh.triangle_colors; returns the number of values.
int number_colors(const CdtPlus& cdt, const std::vector<CdtPlus::Constraint_id>& ids, ControlMesh& mesh) {
  const int nf = mesh.num_triangles();
  std::vector<uint8_t> on_constraint(mesh.num_vertices(), 0);
  detail::DisjointSets corners(size_t(nf) * 3);
  for (CdtPlus::Constraint_id cid : ids) {
    for (auto it = cdt.vertices_in_constraint_begin(cid); it != cdt.vertices_in_constraint_end(cid); ++it) {
      const auto v = *it;
      if (on_constraint[v->info()]) continue;
      on_constraint[v->info()] = 1;
      auto face = cdt.incident_faces(v);
      const auto first = face;
      do {
        const auto f = face, g = std::next(face);
        if (cdt.is_infinite(f) || cdt.is_infinite(g)) continue;
        const int j = f->index(g);  // the edge f and g share (it ends at v)
        if (!f->is_constrained(j)) corners.unite(3 * f->info() + f->index(v), 3 * g->info() + g->index(v));
      } while (++face != first);
    }
  }
  int num_colors = 0;
  mesh.triangle_colors.resize(nf);
  std::vector<int32_t> index(size_t(nf) * 3, -1), vertex_color(mesh.num_vertices(), -1);
  for (int32_t c = 0; c < 3 * nf; ++c) {
    const int32_t v = mesh.triangles[c / 3][c % 3];
    int32_t& id = on_constraint[v] ? index[corners.find(c)] : vertex_color[v];
    if (id < 0) id = num_colors++;
    mesh.triangle_colors[c / 3][c % 3] = id;
  }
  return num_colors;
}

// Features: each constraint's vertex sequence (including any intersection vertices CGAL added),
// split where an edge is already claimed by an earlier feature or lies on the border.
void add_features(const CdtPlus& cdt, const std::vector<CdtPlus::Constraint_id>& ids, int w, int h,
                  ControlMesh& mesh) {
  std::set<std::pair<int32_t, int32_t>> claimed;
  auto on_border = [&](int32_t a, int32_t b) {
    const Vec2 p = mesh.positions[a], q = mesh.positions[b];
    return (p.x == 0 && q.x == 0) || (p.y == 0 && q.y == 0) || (p.x == w && q.x == w) || (p.y == h && q.y == h);
  };
  int32_t feature_id = 0;
  for (CdtPlus::Constraint_id cid : ids) {
    std::vector<int32_t> chain;
    for (auto it = cdt.vertices_in_constraint_begin(cid); it != cdt.vertices_in_constraint_end(cid); ++it) {
      const int32_t v = (*it)->info();
      if (chain.empty() || chain.back() != v) chain.push_back(v);
    }
    Feature current;
    auto flush = [&] {
      if (current.vertices.size() >= 2) {
        current.id = feature_id++;
        mesh.features.push_back(std::move(current));
      }
      current = Feature{};
    };
    for (size_t i = 0; i + 1 < chain.size(); ++i) {
      const int32_t a = chain[i], b = chain[i + 1];
      const auto key = std::minmax(a, b);
      if (on_border(a, b) || !claimed.insert({key.first, key.second}).second) {
        flush();
        continue;
      }
      if (current.vertices.empty()) current.vertices.push_back(a);
      current.vertices.push_back(b);
    }
    flush();
  }
}

// The mean color of the s x s pixels from (x0, y0).
std::array<double, 3> block_mean(const Image8& image, int x0, int y0, int s) {
  std::array<double, 3> sum{};
  const int c = image.channels;
  for (int y = y0; y < y0 + s; ++y) {
    const uint8_t* row = image.row(y);
    for (int x = x0; x < x0 + s; ++x)
      for (int k = 0; k < 3; ++k) sum[k] += row[c * x + k];
  }
  for (double& v : sum) v /= double(s) * s;
  return sum;
}

// Each color value sampled at its vertex (bilinearly), or on its side of the tears; a block
// centre of the coarse grid (block_at, from grid_points()) takes its block's mean, so that the
// quadrics see every pixel.
void sample_colors(const Image8& image, int num_colors, double side_offset, const std::vector<uint8_t>& block_at,
                   ControlMesh& mesh) {
  std::vector<Vec2> toward(num_colors, Vec2{0, 0});
  std::vector<int32_t> owner(num_colors, -1);
  std::vector<int> sectors(mesh.num_vertices(), 0);
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int32_t ci = mesh.triangle_colors[f][k];
      if (owner[ci] < 0) {
        owner[ci] = mesh.triangles[f][k];
        ++sectors[owner[ci]];
      }
    }
  }
  // Where a vertex has several sectors, the mean direction of each toward its faces' centroids.
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    const Tri& t = mesh.triangles[f];
    if (sectors[t[0]] < 2 && sectors[t[1]] < 2 && sectors[t[2]] < 2) continue;
    const Vec2 c{(mesh.positions[t[0]].x + mesh.positions[t[1]].x + mesh.positions[t[2]].x) / 3,
                 (mesh.positions[t[0]].y + mesh.positions[t[1]].y + mesh.positions[t[2]].y) / 3};
    for (int k = 0; k < 3; ++k) {
      if (sectors[t[k]] < 2) continue;
      const int32_t ci = mesh.triangle_colors[f][k];
      const Vec2 p = mesh.positions[t[k]];
      const double len = std::hypot(c.x - p.x, c.y - p.y);
      if (len > 0) toward[ci].x += (c.x - p.x) / len, toward[ci].y += (c.y - p.y) / len;
    }
  }
  mesh.colors.resize(num_colors);
  for (int ci = 0; ci < num_colors; ++ci) {
    const int32_t v = owner[ci];
    Vec2 p = mesh.positions[v];
    if (sectors[v] > 1) {  // a vertex on a tear: sample inside this side
      const double len = std::hypot(toward[ci].x, toward[ci].y);
      if (len > 0) p.x += side_offset * toward[ci].x / len, p.y += side_offset * toward[ci].y / len;
    }
    const int s = block_at.empty() || sectors[v] > 1 || p.x != std::floor(p.x) || p.y != std::floor(p.y)
                      ? 0
                      : block_at[size_t(p.y) * (image.width + 1) + size_t(p.x)];
    const auto rgb = s > 0 ? block_mean(image, int(p.x) - s / 2, int(p.y) - s / 2, s) : sample_bilinear(image, p.x, p.y);
    mesh.colors[ci] = {static_cast<float>(rgb[0]), static_cast<float>(rgb[1]), static_cast<float>(rgb[2])};
  }
}

}  // namespace

ControlMesh build_initial_mesh(const Image8& image, const std::vector<DetectedFeature>& features,
                               const InitialMeshOptions& options) {
  const int w = image.width, h = image.height;
  if (w < 1 || h < 1) throw Error(ErrorCode::kInvalidArgument, "empty image");
  if (!valid_grid_step(options.grid_step)) {
    throw Error(ErrorCode::kInvalidArgument, "initial mesh: grid step must be 0 (automatic), 1, 2, 4 or 8");
  }
  const int step = std::max(1, options.grid_step);
  // Grid points closer than min_grid_distance to a feature would make slivers: drop them, and
  // split the blocks whose centre they would be. Blocks with a pixel within fine_band of a feature
  // are split too.
  const double r = options.min_grid_distance;
  const std::vector<uint8_t> dropped = near_features(features, w, h, r);
  std::vector<uint8_t> wider_band, dropped_corner;
  if (step >= 2) {
    if (options.fine_band > r) wider_band = near_features(features, w, h, options.fine_band);
    dropped_corner = near_features(features, w, h, r, true);
  }
  const std::vector<uint8_t>& fine = wider_band.empty() ? dropped : wider_band;
  std::vector<uint8_t> block_at;
  const std::vector<Point> points = grid_points(w, h, step, dropped, fine, dropped_corner, block_at);
  CdtPlus cdt;
  cdt.insert(points.begin(), points.end());
  const std::vector<CdtPlus::Constraint_id> ids = insert_features(cdt, features, w, h);
  ControlMesh mesh = mesh_of(cdt);
  const int num_colors = number_colors(cdt, ids, mesh);
  add_features(cdt, ids, w, h, mesh);
  sample_colors(image, num_colors, options.side_offset, block_at, mesh);
  return mesh;
}

}  // namespace subvec
