// The mesh the vector exports draw. Drawing the limit surface as flat-sided triangles errs by the
// distance between the surface and its chords and, in color, by what linear (PDF's Gouraud
// shading) or constant (SVG) color misses of the surface's. Both are measured, not estimated: the
// exact limit (LimitEvaluator: OpenSubdiv's Loop patches) at the parametric midpoints of a face's
// refined edges against what the triangles draw there. Each control face gets the smallest depth
// that meets the tolerances, so flat regions take a few triangles and steep ramps and tear corners
// many, and the faces are stitched where their depths differ (adaptive_limit_mesh).
#include "export/limit_mesh_p.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <unordered_map>

#include "core/parallel_p.h"
#include "render/renderer_p.h"
#include "subvec/render/renderer.h"

#include "core/messages_p.h"
#include "subvec/core/error.h"
#include "subvec/mesh/validate.h"

namespace subvec::detail {
namespace {

using detail::invalid;
using detail::num;

constexpr int64_t kMaxTriangles = int64_t{1} << 24;
// What the SVG writer spends, about, on a flat triangle (a subpath in its color's path) and on a
// linear gradient (its definition and its path): how Shading::kLinear chooses between them.
constexpr double kFlatTriangleBytes = 50, kGradientBytes = 200;

// Calls edge(i0, j0, i1, j1) for each edge of the triangles of a face's grid of size n (the
// grid points (i, j), i + j <= n): each once.
template <class Edge>
void for_each_grid_edge(int n, const Edge& edge) {
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i + j < n; ++i) {
      edge(i, j, i + 1, j);
      edge(i, j, i, j + 1);
      edge(i + 1, j, i, j + 1);
    }
  }
}

// Calls triangle(p, q, r) for each triangle of a face's grid of size n, corners in grid units:
// the upward (i, j), (i + 1, j), (i, j + 1), then the downward one beside it.
template <class Triangle>
void for_each_grid_triangle(int n, const Triangle& triangle) {
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i + j < n; ++i) {
      triangle(std::array<int, 2>{i, j}, std::array<int, 2>{i + 1, j}, std::array<int, 2>{i, j + 1});
      if (i + j + 1 < n) triangle(std::array<int, 2>{i + 1, j}, std::array<int, 2>{i + 1, j + 1}, std::array<int, 2>{i, j + 1});
    }
  }
}

// A face's limit values on the grid of parameters (i / n, j / n), i + j <= n.
struct Value {
  double x, y, c[3];
};
struct FaceGrid {
  int n = 0;
  std::vector<Value> values;
  Value& at(int i, int j) { return values[size_t(j) * (n + 1) + i]; }
  const Value& at(int i, int j) const { return values[size_t(j) * (n + 1) + i]; }
};

Value evaluate(const LimitEvaluator& evaluator, int face, double u, double v) {
  const LimitEvaluator::Sample s = evaluator.evaluate(face, u, v);
  return {s.position.x, s.position.y, {s.color[0], s.color[1], s.color[2]}};
}

// The grid at n = 2 * previous.n, reusing the previous grid's values (or all evaluated).
FaceGrid finer_grid(const LimitEvaluator& evaluator, int face, const FaceGrid& previous) {
  FaceGrid grid;
  grid.n = previous.n ? 2 * previous.n : 1;
  grid.values.resize(size_t(grid.n + 1) * (grid.n + 1));
  for (int j = 0; j <= grid.n; ++j) {
    for (int i = 0; i + j <= grid.n; ++i) {
      grid.at(i, j) = previous.n && i % 2 == 0 && j % 2 == 0
                          ? previous.at(i / 2, j / 2)
                          : evaluate(evaluator, face, double(i) / grid.n, double(j) / grid.n);
    }
  }
  return grid;
}

double midpoint_deviation(const Value& a, const Value& b, const Value& m) {
  return std::hypot(m.x - 0.5 * (a.x + b.x), m.y - 0.5 * (a.y + b.y));
}

// The errors of a face drawn at depth d, from its limit values at 2^(d+1) (`fine`). A chord's
// distance from the limit shows as such only where the surface has an edge in the image: on the
// face's sides that are tears or the image border (bit k of `sharp_sides`: side k, from corner k).
// Elsewhere the image shows colors, and a point of the surface drawn `delta` away from where it
// belongs errs by the color's slope times delta, which is added to the color error.
struct FaceError {
  double position = 0, color = 0;
  int64_t pieces = 0, over = 0;
};
FaceError face_error(const FaceGrid& fine, const FaceTolerance& tolerance, int sharp_sides) {
  const int n = fine.n / 2;
  FaceError error;
  auto at = [&](int i, int j) -> const Value& { return fine.at(i, j); };
  // Is the edge (i0, j0)-(i1, j1) (grid units at depth d) on a sharp side of the face?
  auto sharp = [&](int i0, int j0, int i1, int j1) {
    return ((sharp_sides & 1) && j0 == 0 && j1 == 0) || ((sharp_sides & 2) && i0 + j0 == n && i1 + j1 == n) ||
           ((sharp_sides & 4) && i0 == 0 && i1 == 0);
  };
  auto length = [](const Value& a, const Value& b) { return std::hypot(a.x - b.x, a.y - b.y); };
  // The slope of each channel at the fine grid point (i, j), levels per pixel: the gradient of the
  // linear color over the fine triangle from (i, j) to its next grid points.
  auto slope = [&](int i, int j, double* out) {
    const int s = i + j < fine.n ? 1 : -1;
    const Value &p = at(i, j), &q = at(i + s, j), &r = at(i, j + s);
    const double ax = q.x - p.x, ay = q.y - p.y, bx = r.x - p.x, by = r.y - p.y;
    const double det = ax * by - ay * bx;
    if (!(std::abs(det) > 1e-9 * (ax * ax + ay * ay + bx * bx + by * by))) {
      out[0] = out[1] = out[2] = 0;
      return;
    }
    for (int k = 0; k < 3; ++k) {
      const double dq = q.c[k] - p.c[k], dr = r.c[k] - p.c[k];
      out[k] = std::hypot((dq * by - dr * ay) / det, (dr * ax - dq * bx) / det);
    }
  };
  // The color error at the midpoint (fine grid point (i, j)) of an edge whose flat or linear color
  // there is `drawn`, drawn `delta` away from where it belongs.
  auto color_error = [&](int i, int j, const double* drawn, double delta) {
    const Value& m = at(i, j);
    double g[3] = {0, 0, 0}, e = 0;
    if (delta > 0) slope(i, j, g);
    for (int k = 0; k < 3; ++k) e = std::max(e, std::abs(m.c[k] - drawn[k]) + g[k] * delta);
    return e;
  };
  auto record = [&](double position, double color, double longest) {
    error.position = std::max(error.position, position);
    error.color = std::max(error.color, color);
    ++error.pieces;
    error.over += (position > tolerance.position || color > tolerance.color) &&
                  longest > tolerance.small;
  };
  if (tolerance.shading == Shading::kGouraud) {
    auto edge = [&](int i0, int j0, int i1, int j1) {
      const Value &a = at(2 * i0, 2 * j0), &b = at(2 * i1, 2 * j1), &m = at(i0 + i1, j0 + j1);
      double mean[3];
      for (int k = 0; k < 3; ++k) mean[k] = 0.5 * (a.c[k] + b.c[k]);
      const double delta = midpoint_deviation(a, b, m);
      record(sharp(i0, j0, i1, j1) ? delta : 0, color_error(i0 + i1, j0 + j1, mean, delta),
             length(a, b));
    };
    for_each_grid_edge(n, edge);
    return error;
  }
  if (tolerance.shading == Shading::kLinear) {
    // A triangle against the LinearColor fitted to its corners and edge midpoints: the mean of its
    // error there. (The largest error made every cell on a textured photograph split: a linear
    // gradient cannot follow the hump of color around each control vertex, which averages out.)
    auto triangle = [&](std::array<int, 2> p, std::array<int, 2> q, std::array<int, 2> r) {
      const std::array<std::array<int, 2>, 3> c = {p, q, r};
      std::array<ColorSample, 6> samples;
      for (int e = 0; e < 3; ++e) {
        const Value& a = at(2 * c[e][0], 2 * c[e][1]);
        const Value& m = at(c[e][0] + c[(e + 1) % 3][0], c[e][1] + c[(e + 1) % 3][1]);
        samples[e] = {a.x, a.y, {a.c[0], a.c[1], a.c[2]}};
        samples[3 + e] = {m.x, m.y, {m.c[0], m.c[1], m.c[2]}};
      }
      const LinearColor fit = fit_linear_color(samples);
      double position = 0, color = 0, longest = 0, drawn[3];
      for (int e = 0; e < 3; ++e) {
        const auto &s0 = c[e], &t0 = c[(e + 1) % 3];
        const Value &a = at(2 * s0[0], 2 * s0[1]), &b = at(2 * t0[0], 2 * t0[1]);
        const double delta = midpoint_deviation(a, b, at(s0[0] + t0[0], s0[1] + t0[1]));
        if (sharp(s0[0], s0[1], t0[0], t0[1])) position = std::max(position, delta);
        fit.at(a.x, a.y, drawn);
        const double e0 = color_error(2 * s0[0], 2 * s0[1], drawn, 0);
        // The chord's midpoint draws the fit's color there, for the limit's point `delta` away.
        fit.at(0.5 * (a.x + b.x), 0.5 * (a.y + b.y), drawn);
        const double e1 = color_error(s0[0] + t0[0], s0[1] + t0[1], drawn, delta);
        color += (e0 + e1) / 6;  // the mean over the six samples
        longest = std::max(longest, length(a, b));
      }
      record(position, color, longest);
    };
    for_each_grid_triangle(n, triangle);
    return error;
  }
  // Flat: a triangle (corners p, q, r in grid units at depth d) against its mean color at its
  // corners and edge midpoints.
  auto triangle = [&](std::array<int, 2> p, std::array<int, 2> q, std::array<int, 2> r) {
    const std::array<std::array<int, 2>, 3> c = {p, q, r};
    double mean[3] = {0, 0, 0};
    for (const auto& k : c)
      for (int ch = 0; ch < 3; ++ch) mean[ch] += at(2 * k[0], 2 * k[1]).c[ch] / 3;
    double position = 0, color = 0, longest = 0;
    for (int e = 0; e < 3; ++e) {
      const auto &s = c[e], &t = c[(e + 1) % 3];
      const Value &a = at(2 * s[0], 2 * s[1]), &b = at(2 * t[0], 2 * t[1]);
      const Value& m = at(s[0] + t[0], s[1] + t[1]);
      const double delta = midpoint_deviation(a, b, m);
      if (sharp(s[0], s[1], t[0], t[1])) position = std::max(position, delta);
      color = std::max({color, color_error(2 * s[0], 2 * s[1], mean, 0),
                        color_error(s[0] + t[0], s[1] + t[1], mean, delta)});
      longest = std::max(longest, length(a, b));
    }
    record(position, color, longest);
  };
  for_each_grid_triangle(n, triangle);
  return error;
}

}  // namespace

LinearColor fit_linear_color(std::span<const ColorSample> samples) {
  LinearColor out;
  const double n = double(samples.size());
  if (samples.empty()) return out;
  for (const ColorSample& s : samples) {
    out.centre[0] += s.x / n, out.centre[1] += s.y / n;
    for (int k = 0; k < 3; ++k) out.mean[k] += s.c[k] / n;
  }
  // Least squares per channel: the gradient b_k solves S b_k = r_k, S the points' scatter.
  double sxx = 0, sxy = 0, syy = 0, r[3][2] = {};
  for (const ColorSample& s : samples) {
    const double dx = s.x - out.centre[0], dy = s.y - out.centre[1];
    sxx += dx * dx, sxy += dx * dy, syy += dy * dy;
    for (int k = 0; k < 3; ++k) r[k][0] += dx * (s.c[k] - out.mean[k]), r[k][1] += dy * (s.c[k] - out.mean[k]);
  }
  const double det = sxx * syy - sxy * sxy;
  if (!(det > 1e-12 * (sxx + syy) * (sxx + syy))) return out;  // collinear points: flat
  // Along a unit direction d the best slopes are (r_k . d) / (d^T S d), and they take away
  // sum_k (r_k . d)^2 / (d^T S d) of the squared residual: the best d is the top eigenvector of
  // the pencil (M, S), M = sum_k r_k r_k^T, i.e. of A = S^-1 M.
  double m00 = 0, m01 = 0, m11 = 0;
  for (int k = 0; k < 3; ++k) m00 += r[k][0] * r[k][0], m01 += r[k][0] * r[k][1], m11 += r[k][1] * r[k][1];
  const double a00 = (syy * m00 - sxy * m01) / det, a01 = (syy * m01 - sxy * m11) / det;
  const double a10 = (sxx * m01 - sxy * m00) / det, a11 = (sxx * m11 - sxy * m01) / det;
  const double trace = a00 + a11, disc = std::max(0.0, trace * trace - 4 * (a00 * a11 - a01 * a10));
  const double lambda = 0.5 * (trace + std::sqrt(disc));
  // (A - lambda I) d = 0: of the two rows' null vectors, the better conditioned.
  double dx = a01, dy = lambda - a00;
  if (std::hypot(lambda - a11, a10) > std::hypot(dx, dy)) dx = lambda - a11, dy = a10;
  const double norm = std::hypot(dx, dy);
  if (!(norm > 0)) return out;  // no variation: flat
  out.direction[0] = dx / norm, out.direction[1] = dy / norm;
  const double dsd = sxx * out.direction[0] * out.direction[0] + 2 * sxy * out.direction[0] * out.direction[1] +
                     syy * out.direction[1] * out.direction[1];
  for (int k = 0; k < 3; ++k) out.slope[k] = (r[k][0] * out.direction[0] + r[k][1] * out.direction[1]) / dsd;
  return out;
}

LinearError linear_error(const LimitEvaluator& evaluator, const ControlMesh& mesh, int depth,
                         double position_tolerance, double color_tolerance,
                         std::vector<double>* positions) {
  const int n = 1 << depth, fine = 2 * n;
  // Values at the parameters (i / fine, j / fine), i + j <= fine, of one face.
  struct Value {
    double x, y, c[3];
  };
  std::vector<Value> grid(size_t(fine + 1) * (fine + 1));
  auto at = [&](int i, int j) -> Value& { return grid[size_t(j) * (fine + 1) + i]; };
  LinearError error;
  for (int f = 0; f < mesh.num_triangles(); ++f) {
    for (int j = 0; j <= fine; ++j) {
      for (int i = 0; i + j <= fine; ++i) {
        const LimitEvaluator::Sample s = evaluator.evaluate(f, double(i) / fine, double(j) / fine);
        at(i, j) = {s.position.x, s.position.y, {s.color[0], s.color[1], s.color[2]}};
      }
    }
    auto edge = [&](int i0, int j0, int i1, int j1) {
      const Value &a = at(2 * i0, 2 * j0), &b = at(2 * i1, 2 * j1), &m = at(i0 + i1, j0 + j1);
      const double position = std::hypot(m.x - 0.5 * (a.x + b.x), m.y - 0.5 * (a.y + b.y));
      double color = 0;
      for (int k = 0; k < 3; ++k)
        color = std::max(color, std::abs(m.c[k] - 0.5 * (a.c[k] + b.c[k])));
      if (positions) positions->push_back(position);
      error.max_position = std::max(error.max_position, position);
      error.max_color = std::max(error.max_color, color);
      error.over += position > position_tolerance || color > color_tolerance;
      ++error.edges;
    };
    for_each_grid_edge(n, edge);
  }
  return error;
}

std::vector<std::vector<uint8_t>> face_depths(const LimitEvaluator& evaluator, const ControlMesh& mesh,
                                              const MeshTopology& topology, std::span<const FaceTolerance> tolerances,
                                              int max_depth, std::span<LinearError* const> errors) {
  const int faces = mesh.num_triangles();
  const size_t count = tolerances.size();
  std::vector<std::vector<uint8_t>> depths(count, std::vector<uint8_t>(faces, 0));
  std::vector<std::vector<FaceError>> face_errors(count, std::vector<FaceError>(faces));
  parallel_for(faces, 0, [&](int f) {
    int sharp_sides = 0;
    for (int k = 0; k < 3; ++k) {
      const EdgeTag tag = topology.edge_tags[topology.face_edges[f][k]];
      if (tag == EdgeTag::kTear || tag == EdgeTag::kBorder) sharp_sides |= 1 << k;
    }
    // One grid refined once for all the tolerances: each settles at its own depth.
    FaceGrid fine = finer_grid(evaluator, f, finer_grid(evaluator, f, {}));  // n = 2: depth 0
    std::vector<uint8_t> open(count, 1);
    for (int depth = 0;; ++depth) {
      size_t left = 0;
      for (size_t i = 0; i < count; ++i) {
        if (!open[i]) continue;
        face_errors[i][f] = face_error(fine, tolerances[i], sharp_sides);
        if (face_errors[i][f].over == 0 || depth >= max_depth) {
          depths[i][f] = static_cast<uint8_t>(depth);
          open[i] = 0;
        } else {
          ++left;
        }
      }
      if (left == 0) break;
      fine = finer_grid(evaluator, f, fine);
    }
  });
  for (size_t i = 0; i < count && i < errors.size(); ++i) {
    if (!errors[i]) continue;
    LinearError& error = *errors[i];
    error = {};
    for (const FaceError& e : face_errors[i]) {
      error.max_position = std::max(error.max_position, e.position);
      error.max_color = std::max(error.max_color, e.color);
      error.edges += e.pieces;
      error.over += e.over;
    }
  }
  return depths;
}

std::vector<uint8_t> face_depths(const LimitEvaluator& evaluator, const ControlMesh& mesh,
                                 const MeshTopology& topology, const FaceTolerance& tolerance,
                                 int max_depth, LinearError* error) {
  LinearError* const errors[1] = {error};
  return std::move(face_depths(evaluator, mesh, topology, std::span(&tolerance, 1), max_depth, errors)[0]);
}

RefinedMesh adaptive_limit_mesh(const ControlMesh& mesh, const MeshTopology& topology,
                                const LimitEvaluator& evaluator, std::span<const uint8_t> depths,
                                std::vector<std::array<float, 6>>* params) {
  const int faces = mesh.num_triangles();
  // An edge is sampled at the finer depth of its faces.
  std::vector<uint8_t> edge_depth(topology.num_edges(), 0);
  for (int f = 0; f < faces; ++f)
    for (const int32_t e : topology.face_edges[f])
      edge_depth[e] = std::max(edge_depth[e], depths[f]);

  RefinedMesh out;
  out.depth = faces ? *std::max_element(depths.begin(), depths.end()) : 0;
  // Shared vertices: a control vertex's limit point, or a point on a control edge at the dyadic
  // parameter t = k / 2^16 from its lower-numbered end (depth <= 16). Shared color values: a
  // corner's color index, or such a point on one side of the edge (both sides but across tears).
  std::vector<int32_t> corner_vertex(mesh.num_vertices(), -1), corner_color(mesh.num_colors(), -1);
  std::unordered_map<uint64_t, int32_t> edge_vertex, edge_color;
  auto new_vertex = [&](const Value& v) {
    out.positions.push_back(static_cast<float>(v.x));
    out.positions.push_back(static_cast<float>(v.y));
    return out.num_vertices() - 1;
  };
  auto new_color = [&](const Value& v) {
    for (int k = 0; k < 3; ++k) out.colors.push_back(static_cast<float>(v.c[k]));
    return out.num_colors() - 1;
  };
  constexpr int kKeyBits = 16;
  struct Point {
    int32_t vertex, color;
    float u = 0, v = 0;  // in the face it was made for
  };
  // The point of face f at parameters (u, v) = (i, j) / 2^depth; `side` is the face's edge k that
  // it lies on (-1 inside), `t` its parameter along that edge from corner k, as a multiple of 2^-16.
  auto point_of = [&](int f, int depth, int i, int j) -> Point {
    const Tri& v = mesh.triangles[f];
    const Tri& c = mesh.triangle_colors[f];
    const int n = 1 << depth;
    const int corner = i == 0 && j == 0 ? 0 : i == n && j == 0 ? 1 : i == 0 && j == n ? 2 : -1;
    if (corner >= 0) {
      int32_t& vertex = corner_vertex[v[corner]];
      int32_t& color = corner_color[c[corner]];
      if (vertex < 0 || color < 0) {
        const Value value = evaluate(evaluator, f, double(i) / n, double(j) / n);
        if (vertex < 0) vertex = new_vertex(value);
        if (color < 0) color = new_color(value);
      }
      return {vertex, color};
    }
    const int side = j == 0 ? 0 : i + j == n ? 1 : i == 0 ? 2 : -1;
    if (side < 0) {
      const Value value = evaluate(evaluator, f, double(i) / n, double(j) / n);
      return {new_vertex(value), new_color(value)};
    }
    const int step = side == 0 ? i : side == 1 ? j : n - j;  // along the edge from corner `side`
    const int32_t a = v[side], b = v[(side + 1) % 3];
    const int32_t e = topology.face_edges[f][side];
    const uint64_t t = uint64_t(a < b ? step : n - step) << (kKeyBits - depth);
    const uint64_t key = (uint64_t(e) << (kKeyBits + 1)) | (t << 1);
    const bool tear = topology.edge_tags[e] == EdgeTag::kTear;
    const uint64_t color_key = key | uint64_t(tear && topology.edge_faces[e][0] != f);
    const auto vertex = edge_vertex.find(key);
    const auto color = edge_color.find(color_key);
    if (vertex != edge_vertex.end() && color != edge_color.end()) return {vertex->second, color->second};
    const Value value = evaluate(evaluator, f, double(i) / n, double(j) / n);
    const int32_t p = vertex != edge_vertex.end() ? vertex->second : edge_vertex[key] = new_vertex(value);
    const int32_t q = color != edge_color.end() ? color->second : edge_color[color_key] = new_color(value);
    return {p, q};
  };
  // The same, with its parameters in face f.
  auto point = [&](int f, int depth, int i, int j) -> Point {
    Point p = point_of(f, depth, i, j);
    p.u = static_cast<float>(double(i) / (1 << depth)), p.v = static_cast<float>(double(j) / (1 << depth));
    return p;
  };
  auto triangle = [&](int f, const Point& a, const Point& b, const Point& c) {
    if (params) params->push_back({a.u, a.v, b.u, b.v, c.u, c.v});
    out.triangles.push_back({a.vertex, b.vertex, c.vertex});
    out.triangle_colors.push_back({a.color, b.color, c.color});
    out.triangle_parent.push_back(f);
  };

  std::vector<Point> grid;
  for (int f = 0; f < faces; ++f) {
    const int d = depths[f], n = 1 << d;
    // The face's grid points, each made once.
    grid.assign(size_t(n + 1) * (n + 1), Point{-1, -1});
    auto at = [&](int i, int j) -> const Point& {
      Point& p = grid[size_t(j) * (n + 1) + i];
      if (p.vertex < 0) p = point(f, d, i, j);
      return p;
    };
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i + j < n; ++i) {
        if (i + j + 1 < n) triangle(f, at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
        // The upward triangle (i, j), (i + 1, j), (i, j + 1), with the extra points of the finer
        // edges it lies on, in order around it, at the depth of that edge.
        const std::array<std::array<int, 2>, 3> corners = {{{i, j}, {i + 1, j}, {i, j + 1}}};
        std::vector<Point> polygon;
        std::array<bool, 3> split = {false, false, false};
        for (int s = 0; s < 3; ++s) {
          const auto &p = corners[s], &q = corners[(s + 1) % 3];
          polygon.push_back(at(p[0], p[1]));
          // Which face edge the side (p, q) lies on, if any.
          const int side = s == 0 && j == 0 ? 0 : s == 1 && i + j + 1 == n ? 1 : s == 2 && i == 0 ? 2 : -1;
          if (side < 0) continue;
          const int e = edge_depth[topology.face_edges[f][side]];
          if (e <= d) continue;
          split[s] = true;
          const int m = 1 << (e - d);
          for (int k = 1; k < m; ++k)
            polygon.push_back(point(f, e, p[0] * m + k * (q[0] - p[0]), p[1] * m + k * (q[1] - p[1])));
        }
        const int splits = split[0] + split[1] + split[2];
        if (splits == 0) {
          triangle(f, polygon[0], polygon[1], polygon[2]);
        } else if (splits == 1) {
          // Fan from the corner opposite the split side: the corner after it, going round.
          const int s = split[0] ? 0 : split[1] ? 1 : 2;
          // Only side s has extra points, so corner s is polygon[s], and from it the polygon runs
          // along the split side to the opposite corner, last.
          std::rotate(polygon.begin(), polygon.begin() + s, polygon.end());
          const Point apex = polygon.back();
          for (size_t k = 0; k + 2 < polygon.size(); ++k) triangle(f, apex, polygon[k], polygon[k + 1]);
        } else {
          // Fan from the triangle's centre.
          const Value value = evaluate(evaluator, f, (i + 1.0 / 3) / n, (j + 1.0 / 3) / n);
          const Point centre{new_vertex(value), new_color(value), static_cast<float>((i + 1.0 / 3) / n),
                             static_cast<float>((j + 1.0 / 3) / n)};
          for (size_t k = 0; k < polygon.size(); ++k)
            triangle(f, centre, polygon[k], polygon[(k + 1) % polygon.size()]);
        }
      }
    }
  }

  // The refined edges along the control mesh's sharp edges.
  for (int e = 0; e < topology.num_edges(); ++e) {
    const EdgeTag tag = topology.edge_tags[e];
    if (tag == EdgeTag::kSmooth) continue;
    std::vector<EdgeVerts>& list = tag == EdgeTag::kTear     ? out.tear_edges
                                   : tag == EdgeTag::kCrease ? out.crease_edges
                                                             : out.border_edges;
    const auto [a, b] = topology.edges[e];
    const int m = 1 << edge_depth[e];
    int32_t previous = corner_vertex[a];
    for (int k = 1; k <= m; ++k) {
      const int32_t next =
          k == m ? corner_vertex[b]
                 : edge_vertex.at((uint64_t(e) << (kKeyBits + 1)) |
                                  (uint64_t(k) << (kKeyBits - edge_depth[e]) << 1));
      list.push_back({previous, next});
      previous = next;
    }
  }
  return out;
}

double check_export_options(const VectorImage& image, const ExportOptions& options) {
  const int levels = static_cast<int>(image.levels.size());
  if (options.level < 0 || options.level >= levels) {
    invalid("level " + std::to_string(options.level) + " is out of range (the image has " +
            std::to_string(levels) + (levels == 1 ? " level)" : " levels)"));
  }
  if (!(options.scale > 0) || !std::isfinite(options.scale))
    invalid("scale " + num(options.scale) + " is not a positive number");
  if (options.width < 0) invalid("width " + std::to_string(options.width) + " is negative");
  const double scale = export_scale(options, image.width);
  // The page, in output units: PDF viewers and SVG renderers draw nothing sensible outside these
  // bounds (the numbers of a page 1e300 units wide print with hundreds of digits).
  const double page_width = image.width * scale, page_height = image.height * scale;
  if (!(page_width <= Limits::kMaxDimension && page_height <= Limits::kMaxDimension)) {
    throw Error(ErrorCode::kLimit, "output size " + num(page_width) + "x" + num(page_height) +
                                       " is too large (at most " +
                                       std::to_string(Limits::kMaxDimension) + " units a side)");
  }
  if (page_width < 1 || page_height < 1) {
    invalid("output size " + num(page_width) + "x" + num(page_height) +
            " is too small (at least 1 unit a side)");
  }
  if (!(options.tolerance > 0) || !std::isfinite(options.tolerance))
    invalid("tolerance " + num(options.tolerance) + " is not a positive number");
  if (!(options.color_tolerance > 0) || !std::isfinite(options.color_tolerance))
    invalid("color tolerance " + num(options.color_tolerance) + " is not a positive number");
  if (!(options.flat_color_tolerance > 0) || !std::isfinite(options.flat_color_tolerance))
    invalid("flat color tolerance " + num(options.flat_color_tolerance) + " is not a positive number");
  if (!(options.linear_color_tolerance > 0) || !std::isfinite(options.linear_color_tolerance))
    invalid("linear color tolerance " + num(options.linear_color_tolerance) + " is not a positive number");
  if (options.depth > 8) invalid("depth " + std::to_string(options.depth) + " is over 8");
  if (options.max_depth < 0 || options.max_depth > 8)
    invalid("max depth " + std::to_string(options.max_depth) + " is out of range (0 to 8)");
  return scale;
}

namespace {

// export_mesh() of one control mesh (a level's, or an object's) with its topology.
RefinedMesh export_mesh_of(const ControlMesh& mesh, const MeshTopology& topology, double scale,
                           const ExportOptions& options, Shading shading, ExportReport& report,
                           LinearCells* cells) {
  const int64_t faces = mesh.num_triangles();
  const LimitEvaluator evaluator(mesh, topology);
  std::vector<uint8_t> depths, color_depths, flat_faces;
  if (options.depth >= 0) {
    if (faces << (2 * options.depth) > kMaxTriangles) {
      throw Error(ErrorCode::kLimit, "depth " + std::to_string(options.depth) + " over " +
                                         std::to_string(faces) +
                                         " faces would make more than 2^24 triangles");
    }
    depths.assign(faces, static_cast<uint8_t>(options.depth));
  } else {
    FaceTolerance tolerance;
    tolerance.shading = shading;
    tolerance.position = options.tolerance / scale;
    tolerance.color = shading == Shading::kGouraud ? options.color_tolerance
                      : shading == Shading::kFlat  ? options.flat_color_tolerance
                                                   : options.linear_color_tolerance;
    tolerance.small = 1 / scale;
    // No face goes deeper than `subvec render` refines the whole image at this scale (its depth
    // rule, which also keeps the triangles under 2^24): the renderer is the reference.
    double edge_sum = 0;
    for (const Tri& t : mesh.triangles) {
      for (int k = 0; k < 3; ++k) {
        const Vec2 &a = mesh.positions[t[k]], &b = mesh.positions[t[(k + 1) % 3]];
        edge_sum += std::hypot(a.x - b.x, a.y - b.y) * scale;
      }
    }
    const int max_depth = std::min(
        options.max_depth, choose_depth(faces ? edge_sum / double(3 * faces) : 0,
                                        RenderOptions{}.max_edge_pixels, scale, faces));
    LinearError error;
    if (shading == Shading::kLinear) {
      // Geometry: chords within the position tolerance on the sharp sides, whatever the color.
      FaceTolerance geometry = tolerance;
      geometry.shading = Shading::kFlat;
      geometry.color = INFINITY;
      // Colors: each cell's fit within the color tolerance. Or flat triangles, where they take
      // fewer bytes: a face whose color curves needs many cells, and a linear gradient costs
      // about four flat triangles. The three depths of a face come from one refinement of its grid.
      FaceTolerance color = tolerance;
      color.position = INFINITY;
      FaceTolerance flat = tolerance;
      flat.shading = Shading::kFlat;
      flat.position = INFINITY;
      flat.color = options.flat_color_tolerance;
      const FaceTolerance kinds[3] = {geometry, color, flat};
      LinearError* const errors[3] = {nullptr, &error, nullptr};
      std::vector<std::vector<uint8_t>> all = face_depths(evaluator, mesh, topology, kinds, max_depth, errors);
      depths = std::move(all[0]);
      color_depths = std::move(all[1]);
      const std::vector<uint8_t>& flat_depths = all[2];
      flat_faces.assign(faces, 0);
      for (int64_t f = 0; f < faces; ++f) {
        const int as_flat = std::max(depths[f], flat_depths[f]);
        const double flat_bytes = kFlatTriangleBytes * double(int64_t{1} << (2 * as_flat));
        const double linear_bytes = kGradientBytes * double(int64_t{1} << (2 * color_depths[f]));
        if (flat_bytes < linear_bytes) {
          flat_faces[f] = 1;
          depths[f] = color_depths[f] = static_cast<uint8_t>(as_flat);
        } else {
          depths[f] = std::max(depths[f], color_depths[f]);
        }
      }
    } else {
      depths = face_depths(evaluator, mesh, topology, tolerance, max_depth, &error);
    }
    report.max_position_error = error.max_position * scale;
    report.max_color_error = error.max_color;
    report.over_tolerance = error.edges ? double(error.over) / double(error.edges) : 0;
  }
  if (cells && color_depths.empty()) color_depths = depths;  // an explicit depth: one cell a triangle
  std::vector<std::array<float, 6>> params;
  RefinedMesh refined = adaptive_limit_mesh(mesh, topology, evaluator, depths, cells ? &params : nullptr);
  if (cells) {
    // Cells numbered face by face: face f's cells are the 4^c triangles of its grid at its color
    // depth c, (i, j) upward as 2 (j-row-major index), downward + 1.
    std::vector<int64_t> first(size_t(faces) + 1, 0);
    for (int64_t f = 0; f < faces; ++f) first[f + 1] = first[f] + (int64_t{1} << (2 * color_depths[f]));
    auto cell_index = [&](int f, int i, int j, bool down) {
      const int n = 1 << color_depths[f];
      // Triangles of rows below j: row r holds 2 (n - r) - 1.
      int64_t k = int64_t(j) * (2 * n - j);
      return first[f] + k + 2 * i + (down ? 1 : 0);
    };
    cells->cell_of.resize(refined.triangles.size());
    for (int32_t t = 0; t < refined.num_triangles(); ++t) {
      const std::array<float, 6>& q = params[size_t(t)];
      const int f = refined.triangle_parent[t];
      const int n = 1 << color_depths[f];
      const double u = (double(q[0]) + q[2] + q[4]) / 3 * n, v = (double(q[1]) + q[3] + q[5]) / 3 * n;
      const int i = std::clamp(int(std::floor(u)), 0, n - 1), j = std::clamp(int(std::floor(v)), 0, n - 1 - i);
      const bool down = (u - i) + (v - j) > 1 && i + j + 1 < n;
      cells->cell_of[size_t(t)] = static_cast<int32_t>(cell_index(f, i, j, down));
    }
    cells->colors.assign(size_t(first[faces]), LinearColor{});
    parallel_for(static_cast<int>(faces), 0, [&](int f) {
      const int n = 1 << color_depths[f];
      for (int j = 0; j < n; ++j) {
        for (int i = 0; i + j < n; ++i) {
          for (int down = 0; down < 2; ++down) {
            if (down && i + j + 1 >= n) continue;
            // The cell's corners in the face's parameters.
            const double c[3][2] = {{double(i + down), double(j)},
                                    {double(i + (down ? 1 : 0)), double(j + 1)},
                                    {double(down ? i : i + 1), double(down ? j + 1 : j)}};
            const double d[3][2] = {{c[0][0] / n, c[0][1] / n}, {c[1][0] / n, c[1][1] / n}, {c[2][0] / n, c[2][1] / n}};
            std::array<ColorSample, 7> samples;
            constexpr double kWeights[7][3] = {{1, 0, 0},     {0, 1, 0},     {0, 0, 1},       {0.5, 0.5, 0},
                                               {0, 0.5, 0.5}, {0.5, 0, 0.5}, {1.0 / 3, 1.0 / 3, 1.0 / 3}};
            for (int k = 0; k < 7; ++k) {
              const double* w = kWeights[k];
              const Value value = evaluate(evaluator, f, w[0] * d[0][0] + w[1] * d[1][0] + w[2] * d[2][0],
                                           w[0] * d[0][1] + w[1] * d[1][1] + w[2] * d[2][1]);
              samples[k] = {value.x, value.y, {value.c[0], value.c[1], value.c[2]}};
            }
            LinearColor& fit = cells->colors[size_t(cell_index(f, i, j, down != 0))];
            if (!flat_faces.empty() && flat_faces[f]) {
              // A flat triangle: the mean of its corners.
              for (int k = 0; k < 3; ++k) fit.mean[k] = (samples[0].c[k] + samples[1].c[k] + samples[2].c[k]) / 3;
            } else {
              fit = fit_linear_color(samples);
            }
          }
        }
      }
    });
  }
  report.depth = refined.depth;
  report.min_depth = depths.empty() ? 0 : *std::min_element(depths.begin(), depths.end());
  report.triangles = refined.num_triangles();
  return refined;
}

}  // namespace

RefinedMesh export_mesh(const VectorImage& image, const ExportOptions& options, Shading shading,
                        ExportReport& report, LinearCells* cells) {
  const double scale = check_export_options(image, options);
  const ControlMesh& mesh = image.levels[options.level];
  const MeshTopology topology = validate_level(mesh, image.width, image.height, options.level);
  return export_mesh_of(mesh, topology, scale, options, shading, report, cells);
}

std::vector<ObjectMesh> export_object_meshes(const VectorImage& image, const ExportOptions& options,
                                             Shading shading, ExportReport& report) {
  const double scale = check_export_options(image, options);
  std::vector<ObjectMesh> out;
  for (const ObjectTopology& o : visible_objects(image, options.level)) {
    ExportReport part;
    LinearCells cells;
    RefinedMesh mesh = export_mesh_of(image.objects[o.object].mesh, o.topology, scale, options, shading, part,
                                      shading == Shading::kLinear ? &cells : nullptr);
    report.depth = std::max(report.depth, part.depth);
    report.min_depth = std::min(report.min_depth, part.min_depth);
    report.triangles += part.triangles;
    report.max_position_error = std::max(report.max_position_error, part.max_position_error);
    report.max_color_error = std::max(report.max_color_error, part.max_color_error);
    ++report.objects;
    out.push_back({o.object, std::move(mesh), std::move(cells)});
  }
  return out;
}

}  // namespace subvec::detail
