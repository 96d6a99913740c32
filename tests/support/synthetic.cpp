// Synthetic vector image generator (see synthetic.h).
//
// Construction: an nx x ny grid of cells, each split by a diagonal. Features are curves (circles,
// an arc, a segment) traced on the grid vertices as 8-connected chains: straight steps follow grid
// edges, diagonal steps force the diagonal of the cell they cross. Triangles are labelled by the
// closed feature they lie in; colors are a smooth random field per label plus, near an open
// feature, a jump that fades out at its ends. Color values are made per vertex and per wedge (the
// incident triangles connected without crossing a tear). Finally interior non-feature vertices
// are jittered by less than a quarter cell, which keeps every triangle positive.
#include "support/synthetic.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <numbers>
#include <numeric>
#include <set>
#include <stdexcept>

namespace subvec::test {
namespace {

// splitmix64: portable, seeded, good enough for test data.
class Random {
 public:
  explicit Random(uint64_t seed) : state_(seed * 0x9E3779B97F4A7C15ull + 1) {}
  double uniform(double lo, double hi) {
    state_ += 0x9E3779B97F4A7C15ull;
    uint64_t z = state_;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return lo + (hi - lo) * double(z >> 11) / double(uint64_t{1} << 53);
  }

 private:
  uint64_t state_;
};

using GridPoint = std::array<int, 2>;

// Traces a curve (grid coordinates, t in [0, 1]) as an 8-connected chain of grid vertices.
std::vector<GridPoint> trace(const std::function<std::array<double, 2>(double)>& curve,
                             bool closed) {
  std::vector<GridPoint> chain;
  constexpr int kSteps = 20000;
  for (int s = 0; s <= kSteps; ++s) {
    const auto p = curve(double(s) / kSteps);
    const GridPoint g{static_cast<int>(std::lround(p[0])), static_cast<int>(std::lround(p[1]))};
    if (!chain.empty() && chain.back() == g) continue;
    if (closed && chain.size() > 2 && g == chain.front() && s > kSteps / 2) break;
    // Cut out a loop if the rounding came back to a vertex already on the chain.
    auto it = std::find(chain.begin(), chain.end(), g);
    if (it != chain.end()) {
      chain.erase(it + 1, chain.end());
      continue;
    }
    chain.push_back(g);
  }
  if (closed && chain.front() != chain.back()) chain.push_back(chain.front());
  // Cut the corners of staircases: a vertex whose neighbours are diagonal neighbours is skipped,
  // so the chain takes the cell diagonal instead.
  for (size_t k = 1; k + 1 < chain.size();) {
    if (std::abs(chain[k + 1][0] - chain[k - 1][0]) == 1 &&
        std::abs(chain[k + 1][1] - chain[k - 1][1]) == 1) {
      chain.erase(chain.begin() + static_cast<std::ptrdiff_t>(k));
    } else {
      ++k;
    }
  }
  for (size_t i = 1; i < chain.size(); ++i) {
    if (std::abs(chain[i][0] - chain[i - 1][0]) > 1 ||
        std::abs(chain[i][1] - chain[i - 1][1]) > 1) {
      throw std::logic_error("synthetic: curve traced with a gap");
    }
  }
  return chain;
}

}  // namespace

VectorImage make_synthetic_image(const SyntheticOptions& o) {
  const double aspect = double(o.width) / o.height;
  const int nx = std::max(4, static_cast<int>(std::lround(std::sqrt(o.vertices * aspect))) - 1);
  const int ny = std::max(4, static_cast<int>(std::lround(std::sqrt(o.vertices / aspect))) - 1);
  const double hx = double(o.width) / nx, hy = double(o.height) / ny;
  auto vid = [&](int i, int j) { return j * (nx + 1) + i; };
  Random rng(o.seed);

  // Features in grid coordinates, placed relative to the grid and kept apart and off the border.
  std::vector<std::vector<GridPoint>> chains;
  std::vector<bool> closed;
  if (o.features) {
    const double n = std::min(nx, ny);
    auto circle = [&](double cx, double cy, double r) {
      return [=](double t) {
        const double a = 2 * std::numbers::pi * t;
        return std::array<double, 2>{cx * nx + r * n * std::cos(a), cy * ny + r * n * std::sin(a)};
      };
    };
    chains.push_back(trace(circle(0.3, 0.33, 0.16), true));
    chains.push_back(trace(circle(0.68, 0.62, 0.2), true));
    chains.push_back(trace(
        [&](double t) {
          return std::array<double, 2>{(0.1 + 0.32 * t) * nx,
                                       (0.84 + 0.06 * std::sin(2 * std::numbers::pi * t)) * ny};
        },
        false));
    chains.push_back(trace(
        [&](double t) {
          return std::array<double, 2>{(0.58 + 0.3 * t) * nx, (0.24 - 0.16 * t) * ny};
        },
        false));
    closed = {true, true, false, false};
  }

  // Cell diagonals: '\' (i,j)-(i+1,j+1) by default; a diagonal step may require '/'.
  std::vector<uint8_t> anti(size_t(nx) * ny, 0);
  std::vector<int> on_feature((nx + 1) * (ny + 1), -1);
  for (size_t f = 0; f < chains.size(); ++f) {
    for (size_t k = 0; k < chains[f].size(); ++k) {
      const auto [i, j] = chains[f][k];
      if (i < 1 || j < 1 || i >= nx || j >= ny)
        throw std::logic_error("synthetic: feature on the border");
      int& owner = on_feature[vid(i, j)];
      if (owner >= 0 && owner != int(f)) throw std::logic_error("synthetic: features touch");
      owner = int(f);
      if (k == 0) continue;
      const auto [pi, pj] = chains[f][k - 1];
      const int di = i - pi, dj = j - pj;
      if (di != 0 && dj != 0 && di != dj) anti[size_t(std::min(j, pj)) * nx + std::min(i, pi)] = 1;
    }
  }

  ControlMesh mesh;
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) mesh.positions.push_back({i * hx, j * hy});
  }
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const int v00 = vid(i, j), v10 = vid(i + 1, j), v01 = vid(i, j + 1), v11 = vid(i + 1, j + 1);
      if (anti[size_t(j) * nx + i]) {
        mesh.triangles.push_back({v00, v10, v01});
        mesh.triangles.push_back({v10, v11, v01});
      } else {
        mesh.triangles.push_back({v00, v10, v11});
        mesh.triangles.push_back({v00, v11, v01});
      }
    }
  }
  for (size_t f = 0; f < chains.size(); ++f) {
    Feature feature;
    feature.id = static_cast<int32_t>(f);
    for (const auto [i, j] : chains[f]) feature.vertices.push_back(vid(i, j));
    mesh.features.push_back(std::move(feature));
  }

  // Region label per triangle: 1 + index of the closed feature containing its centroid, or 0.
  const int nt = mesh.num_triangles();
  std::vector<int> label(nt, 0);
  for (int t = 0; t < nt; ++t) {
    double cx = 0, cy = 0;
    for (int v : mesh.triangles[t]) {
      cx += (v % (nx + 1)) / 3.0;
      cy += (v / (nx + 1)) / 3.0;
    }
    for (size_t f = 0; f < chains.size(); ++f) {
      if (!closed[f]) continue;
      bool inside = false;  // even-odd rule
      const auto& c = chains[f];
      for (size_t k = 1; k < c.size(); ++k) {
        const double xa = c[k - 1][0], ya = c[k - 1][1], xb = c[k][0], yb = c[k][1];
        if ((ya > cy) != (yb > cy) && cx < xa + (cy - ya) * (xb - xa) / (yb - ya)) inside = !inside;
      }
      if (inside) label[t] = int(f) + 1;
    }
  }

  // Smooth fields: per channel a few random plane waves; per region a color offset.
  struct Wave {
    double kx, ky, phase, amplitude;
  };
  std::array<std::vector<Wave>, 3> waves;
  for (auto& w : waves) {
    for (int m = 0; m < 3; ++m) {
      w.push_back({rng.uniform(-2.5, 2.5), rng.uniform(-2.5, 2.5), rng.uniform(0, 6.3),
                   rng.uniform(15, 30)});
    }
  }
  std::vector<std::array<double, 3>> offsets(chains.size() + 1, {0, 0, 0});
  for (size_t r = 1; r < offsets.size(); ++r) {
    for (double& c : offsets[r])
      c = rng.uniform(0, 1) < 0.5 ? rng.uniform(-110, -60) : rng.uniform(60, 110);
  }
  auto field = [&](double x, double y, int region, double jump_weight,
                   const std::array<double, 3>& jump) {
    Color c;
    float* out[3] = {&c.r, &c.g, &c.b};
    for (int ch = 0; ch < 3; ++ch) {
      double v = 128 + offsets[region][ch] + jump_weight * jump[ch];
      for (const Wave& w : waves[ch]) {
        v += w.amplitude *
             std::sin(2 * std::numbers::pi * (w.kx * x / o.width + w.ky * y / o.height) + w.phase);
      }
      *out[ch] = static_cast<float>(std::clamp(v, 5.0, 250.0));
    }
    return c;
  };

  // Wedges: incident triangles of a vertex joined across non-tear edges.
  std::set<std::pair<int, int>> tear_edges;
  for (const auto& chain : chains) {
    for (size_t k = 1; k < chain.size(); ++k) {
      const int a = vid(chain[k - 1][0], chain[k - 1][1]), b = vid(chain[k][0], chain[k][1]);
      tear_edges.insert({std::min(a, b), std::max(a, b)});
    }
  }
  const int nv = mesh.num_vertices();
  std::vector<std::vector<int>> incident(nv);
  for (int t = 0; t < nt; ++t) {
    for (int v : mesh.triangles[t]) incident[v].push_back(t);
  }
  // Open features: the jump at an interior chain vertex, +jump on the side of the triangle holding
  // the directed edge (v, next), -jump on the other.
  std::vector<double> jump_weight(nv, 0);
  std::vector<int> jump_next(nv, -1), jump_feature(nv, -1);
  std::vector<std::array<double, 3>> jumps(chains.size(), {0, 0, 0});
  for (size_t f = 0; f < chains.size(); ++f) {
    if (closed[f]) continue;
    for (double& c : jumps[f])
      c = rng.uniform(0, 1) < 0.5 ? rng.uniform(-70, -40) : rng.uniform(40, 70);
    const auto& c = chains[f];
    for (size_t k = 1; k + 1 < c.size(); ++k) {
      const int v = vid(c[k][0], c[k][1]);
      jump_weight[v] = std::sin(std::numbers::pi * double(k) / double(c.size() - 1));
      jump_next[v] = vid(c[k + 1][0], c[k + 1][1]);
      jump_feature[v] = int(f);
    }
  }

  mesh.triangle_colors.assign(nt, Tri{-1, -1, -1});
  for (int v = 0; v < nv; ++v) {
    const auto& tris = incident[v];
    std::vector<int> parent(tris.size());
    std::iota(parent.begin(), parent.end(), 0);
    std::function<int(int)> find = [&](int a) {
      return parent[a] == a ? a : parent[a] = find(parent[a]);
    };
    auto others = [&](int t) {
      std::vector<int> r;
      for (int u : mesh.triangles[t]) {
        if (u != v) r.push_back(u);
      }
      return r;
    };
    for (size_t a = 0; a < tris.size(); ++a) {
      for (size_t b = a + 1; b < tris.size(); ++b) {
        for (int u : others(tris[a])) {
          const auto ob = others(tris[b]);
          if (std::find(ob.begin(), ob.end(), u) == ob.end()) continue;
          if (tear_edges.count({std::min(u, v), std::max(u, v)})) continue;
          parent[find(int(a))] = find(int(b));
        }
      }
    }
    int plus_root = -1;
    if (jump_next[v] >= 0) {
      for (size_t a = 0; a < tris.size(); ++a) {
        const Tri& t = mesh.triangles[tris[a]];
        for (int k = 0; k < 3; ++k) {
          if (t[k] == v && t[(k + 1) % 3] == jump_next[v]) plus_root = find(int(a));
        }
      }
    }
    std::map<int, int32_t> color_of_root;
    for (size_t a = 0; a < tris.size(); ++a) {
      const int root = find(int(a));
      auto [it, inserted] = color_of_root.try_emplace(root, mesh.num_colors());
      if (inserted) {
        const double side = jump_next[v] < 0 ? 0 : (root == plus_root ? 1.0 : -1.0);
        const std::array<double, 3> jump =
            jump_feature[v] < 0 ? std::array<double, 3>{0, 0, 0} : jumps[jump_feature[v]];
        mesh.colors.push_back(field(mesh.positions[v].x, mesh.positions[v].y, label[tris[a]],
                                    side * jump_weight[v], jump));
      }
      const Tri& t = mesh.triangles[tris[a]];
      for (int k = 0; k < 3; ++k) {
        if (t[k] == v) mesh.triangle_colors[tris[a]][k] = it->second;
      }
    }
  }

  // Jitter interior vertices that are not on a feature.
  for (int j = 1; j < ny; ++j) {
    for (int i = 1; i < nx; ++i) {
      if (on_feature[vid(i, j)] >= 0) continue;
      Vec2& p = mesh.positions[vid(i, j)];
      p.x += rng.uniform(-o.jitter, o.jitter) * hx;
      p.y += rng.uniform(-o.jitter, o.jitter) * hy;
    }
  }

  VectorImage image;
  image.width = o.width;
  image.height = o.height;
  image.levels.push_back(std::move(mesh));
  image.metadata.push_back({"generator", "subvec synthetic test image"});
  return image;
}

Image8 textured_disk(int w, int h) {
  Image8 img(w, h, 3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const bool inside = std::hypot(x + 0.5 - w / 2.0, y + 0.5 - h / 2.0) < h / 4.0;
      const double ripple = 40 * std::sin(0.35 * x + 0.2 * y) * std::cos(0.25 * y);
      uint8_t* p = img.row(y) + 3 * x;
      p[0] = static_cast<uint8_t>(std::lround(inside ? 220 : 90 + ripple));
      p[1] = static_cast<uint8_t>(std::lround(inside ? 150 + ripple / 2 : 120 + x));
      p[2] = static_cast<uint8_t>(std::lround(inside ? 40 : 160 - ripple));
    }
  }
  return img;
}

}  // namespace subvec::test
