#include "support/test_meshes.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <stdexcept>

namespace subvec::testing {
namespace {

constexpr double kPi = std::numbers::pi;

// Two more smooth fields, for the other sides of tears.
Color second_color(Vec2 p) {
  return {static_cast<float>(30 + 3 * p.y), static_cast<float>(200 - 60 * std::sin(0.3 * p.x)),
          static_cast<float>(40 + 0.2 * p.x * p.y)};
}
Color third_color(Vec2 p) {
  return {static_cast<float>(220 - 4 * p.x), static_cast<float>(90 + 50 * std::cos(0.25 * p.y)),
          static_cast<float>(15 + 6 * p.y)};
}

Vec2 centroid(const ControlMesh& m, int face) {
  Vec2 c;
  for (int v : m.triangles[face]) c.x += m.positions[v].x / 3, c.y += m.positions[v].y / 3;
  return c;
}

// Triangulates the annulus between two closed rings of vertices around `centre` (both star-shaped
// from it) by merging them in order of angle, like rotating calipers: each step advances the ring
// whose next vertex comes first. Triangles have positive signed area.
void zip_rings(ControlMesh& m, Vec2 centre, std::vector<int> inner, std::vector<int> outer) {
  auto angle = [&](int v) {
    return std::atan2(m.positions[v].y - centre.y, m.positions[v].x - centre.x);
  };
  std::sort(inner.begin(), inner.end(), [&](int a, int b) { return angle(a) < angle(b); });
  // Angles unwrapped from inner[0]; the outer ring starts at its first vertex at or after it.
  const double start = angle(inner[0]);
  auto unwrapped = [&](int v) {
    double a = angle(v);
    while (a < start) a += 2 * kPi;
    return a;
  };
  std::sort(outer.begin(), outer.end(), [&](int a, int b) { return unwrapped(a) < unwrapped(b); });
  const size_t n = inner.size(), k = outer.size();
  auto inner_angle = [&](size_t i) {
    return i == n ? unwrapped(inner[0]) + 2 * kPi : unwrapped(inner[i]);
  };
  auto outer_angle = [&](size_t j) {
    return j == k ? unwrapped(outer[0]) + 2 * kPi : unwrapped(outer[j]);
  };
  size_t i = 0, j = 0;
  while (i < n || j < k) {
    if (j == k || (i < n && inner_angle(i + 1) < outer_angle(j + 1))) {
      m.triangles.push_back({inner[i], outer[j % k], inner[(i + 1) % n]});
      ++i;
    } else {
      m.triangles.push_back({inner[i % n], outer[j], outer[(j + 1) % k]});
      ++j;
    }
  }
}

// The 12 border vertices of a w x h image: the corners and the thirds of each side.
std::vector<int> add_border(ControlMesh& m, double w, double h) {
  const double xs[] = {0, w / 3, 2 * w / 3, w}, ys[] = {0, h / 3, 2 * h / 3, h};
  std::vector<int> border;
  for (double x : xs) {
    for (double y : ys) {
      if (x != 0 && x != w && y != 0 && y != h) continue;
      border.push_back(m.num_vertices());
      m.positions.push_back({x, y});
    }
  }
  return border;
}

int grid_index(int cols, int i, int j) { return j * (cols + 1) + i; }

// Union-find over triangle corners (3 f + k).
int find_root(std::vector<int>& parent, int x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

}  // namespace

Color smooth_color(Vec2 p) {
  return {static_cast<float>(128 + 80 * std::sin(0.21 * p.x + 0.13 * p.y)),
          static_cast<float>(60 + 5 * p.x + 0.1 * p.y * p.y),
          static_cast<float>(128 + 60 * std::cos(0.17 * p.x - 0.23 * p.y))};
}

void assign_colors(TestMesh& m, const std::function<Color(Vec2, int)>& color) {
  ControlMesh& mesh = m.mesh;
  const MeshTopology topology = m.topology();
  const int nf = mesh.num_triangles();
  std::vector<int> parent(size_t(nf) * 3);
  std::iota(parent.begin(), parent.end(), 0);
  // Corners at the same vertex are joined across every interior edge that is not a tear.
  for (int e = 0; e < topology.num_edges(); ++e) {
    const auto [f, g] = topology.edge_faces[e];
    if (g < 0 || topology.edge_tags[e] == EdgeTag::kTear) continue;
    for (int v : topology.edges[e]) {
      int kf = 0, kg = 0;
      while (mesh.triangles[f][kf] != v) ++kf;
      while (mesh.triangles[g][kg] != v) ++kg;
      parent[find_root(parent, 3 * f + kf)] = find_root(parent, 3 * g + kg);
    }
  }
  mesh.colors.clear();
  mesh.triangle_colors.assign(nf, Tri{});
  std::vector<int> value_of_root(parent.size(), -1);
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      int& value = value_of_root[find_root(parent, 3 * f + k)];
      if (value < 0) {
        value = mesh.num_colors();
        mesh.colors.push_back(color(mesh.positions[mesh.triangles[f][k]], f));
      }
      mesh.triangle_colors[f][k] = value;
    }
  }
}

TestMesh grid_mesh(int cols, int rows, double spacing, bool jitter) {
  TestMesh t;
  t.name =
      "grid_" + std::to_string(cols) + "x" + std::to_string(rows) + (jitter ? "_jittered" : "");
  t.width = static_cast<int>(cols * spacing);
  t.height = static_cast<int>(rows * spacing);
  if (t.width != cols * spacing || t.height != rows * spacing) {
    throw std::invalid_argument("grid_mesh: the image size must be whole pixels");
  }
  ControlMesh& m = t.mesh;
  for (int j = 0; j <= rows; ++j) {
    for (int i = 0; i <= cols; ++i) {
      Vec2 p{i * spacing, j * spacing};
      if (jitter && i > 0 && i < cols && j > 0 && j < rows) {
        p.x += 0.15 * spacing * std::sin(1.7 * i + 2.3 * j + 0.5);
        p.y += 0.15 * spacing * std::cos(2.1 * i - 1.3 * j + 0.3);
      }
      m.positions.push_back(p);
    }
  }
  for (int j = 0; j < rows; ++j) {
    for (int i = 0; i < cols; ++i) {
      const int a = grid_index(cols, i, j), b = grid_index(cols, i + 1, j);
      const int c = grid_index(cols, i, j + 1), d = grid_index(cols, i + 1, j + 1);
      m.triangles.push_back({a, b, d});
      m.triangles.push_back({a, d, c});
    }
  }
  assign_colors(t, [](Vec2 p, int) { return smooth_color(p); });
  return t;
}

TestMesh valence_mesh(int n) {
  if (n < 3 || n > 12) throw std::invalid_argument("valence_mesh: n out of range 3..12");
  TestMesh t;
  t.name = "valence_" + std::to_string(n);
  t.width = t.height = 16;
  ControlMesh& m = t.mesh;
  const Vec2 centre{8, 8};
  t.focus = 0;
  m.positions.push_back(centre);
  std::vector<int> ring;
  for (int k = 0; k < n; ++k) {
    const double a = 0.3 + 2 * kPi * k / n;
    ring.push_back(m.num_vertices());
    m.positions.push_back({centre.x + 3 * std::cos(a), centre.y + 3 * std::sin(a)});
  }
  for (int k = 0; k < n; ++k) m.triangles.push_back({0, ring[k], ring[(k + 1) % n]});
  zip_rings(m, centre, ring, add_border(m, t.width, t.height));
  assign_colors(t, [](Vec2 p, int) { return smooth_color(p); });
  return t;
}

TestMesh torn_disk() {
  TestMesh t;
  t.name = "torn_disk";
  t.width = t.height = 20;
  ControlMesh& m = t.mesh;
  const Vec2 centre{10, 10};
  m.positions.push_back(centre);
  std::vector<int> tear, middle;
  for (int k = 0; k < 8; ++k) {
    const double a = 0.2 + 2 * kPi * k / 8, r = 4.5 + 0.6 * std::sin(3 * a);
    tear.push_back(m.num_vertices());
    m.positions.push_back({centre.x + r * std::cos(a), centre.y + r * std::sin(a)});
  }
  for (int k = 0; k < 12; ++k) {
    const double a = 0.05 + 2 * kPi * k / 12;
    middle.push_back(m.num_vertices());
    m.positions.push_back({centre.x + 7.5 * std::cos(a), centre.y + 7.5 * std::sin(a)});
  }
  for (int k = 0; k < 8; ++k) m.triangles.push_back({0, tear[k], tear[(k + 1) % 8]});
  zip_rings(m, centre, tear, middle);
  zip_rings(m, centre, middle, add_border(m, t.width, t.height));
  Feature feature;
  feature.id = 1;
  feature.vertices = tear;
  feature.vertices.push_back(tear[0]);
  m.features.push_back(feature);
  t.focus = tear[0];
  // Faces 0..7 (the fan around the centre) are the inside.
  assign_colors(t, [](Vec2 p, int face) { return face < 8 ? smooth_color(p) : second_color(p); });
  return t;
}

TestMesh open_tear() {
  TestMesh t = grid_mesh(8, 6, 3, true);
  t.name = "open_tear";
  Feature feature;
  feature.id = 1;
  for (int i = 2; i <= 6; ++i) feature.vertices.push_back(grid_index(8, i, 3));
  t.mesh.features.push_back(feature);
  t.focus = grid_index(8, 2, 3);
  const ControlMesh& m = t.mesh;
  assign_colors(t, [&m](Vec2 p, int face) {
    return centroid(m, face).y < 9 ? smooth_color(p) : second_color(p);
  });
  return t;
}

TestMesh tear_junction() {
  TestMesh t = grid_mesh(8, 8, 3, true);
  t.name = "tear_junction";
  const int junction = grid_index(8, 4, 4);
  t.focus = junction;
  Feature left{1, {junction}, 0}, right{2, {junction}, 0}, down{3, {junction}, 0};
  for (int i = 3; i >= 1; --i) left.vertices.push_back(grid_index(8, i, 4));
  for (int i = 5; i <= 7; ++i) right.vertices.push_back(grid_index(8, i, 4));
  for (int j = 5; j <= 8; ++j) down.vertices.push_back(grid_index(8, 4, j));
  t.mesh.features = {left, right, down};
  const ControlMesh& m = t.mesh;
  assign_colors(t, [&m](Vec2 p, int face) {
    const Vec2 c = centroid(m, face);
    return c.y < 12 ? smooth_color(p) : c.x < 12 ? second_color(p) : third_color(p);
  });
  return t;
}

TestMesh interior_crease() {
  TestMesh t = grid_mesh(8, 6, 3, true);
  t.name = "interior_crease";
  const int chain[] = {grid_index(8, 0, 3), grid_index(8, 1, 3), grid_index(8, 2, 3),
                       grid_index(8, 3, 3), grid_index(8, 4, 4), grid_index(8, 5, 4)};
  for (size_t i = 0; i + 1 < std::size(chain); ++i)
    t.mesh.creases.push_back({chain[i], chain[i + 1]});
  t.focus = chain[std::size(chain) - 1];
  assign_colors(t, [](Vec2 p, int) { return smooth_color(p); });
  return t;
}

std::vector<TestMesh> all_test_meshes() {
  std::vector<TestMesh> meshes{grid_mesh(6, 5, 4, true)};
  for (int n = 3; n <= 8; ++n) meshes.push_back(valence_mesh(n));
  meshes.push_back(torn_disk());
  meshes.push_back(open_tear());
  meshes.push_back(tear_junction());
  meshes.push_back(interior_crease());
  return meshes;
}

}  // namespace subvec::testing
