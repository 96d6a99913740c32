// Rasterizer core on hand-made refined meshes: fill rule, shading, anti-aliasing, threads.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

#include "render/raster_p.h"

namespace subvec::detail {
namespace {

// A grid triangulation of [0, w] x [0, h] with the given vertex coordinates per column and row
// (first 0, last w / h), one color value per corner (colors filled by the caller).
RefinedMesh grid_mesh(const std::vector<double>& xs, const std::vector<double>& ys) {
  RefinedMesh m;
  const int nx = static_cast<int>(xs.size()), ny = static_cast<int>(ys.size());
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      m.positions.push_back(static_cast<float>(xs[i]));
      m.positions.push_back(static_cast<float>(ys[j]));
    }
  }
  for (int j = 0; j + 1 < ny; ++j) {
    for (int i = 0; i + 1 < nx; ++i) {
      const int a = j * nx + i, b = a + 1, c = a + nx, d = c + 1;
      if ((i + j) % 3 == 0) {  // mix both diagonals
        m.triangles.push_back({a, b, c});
        m.triangles.push_back({b, d, c});
      } else {
        m.triangles.push_back({a, b, d});
        m.triangles.push_back({a, d, c});
      }
    }
  }
  return m;
}

// Gives every triangle corner its own color value.
void corner_colors(RefinedMesh& m,
                   const std::function<std::array<float, 3>(int tri, int corner)>& color) {
  m.colors.clear();
  m.triangle_colors.clear();
  for (int t = 0; t < m.num_triangles(); ++t) {
    Tri tc;
    for (int k = 0; k < 3; ++k) {
      tc[k] = m.num_colors();
      const auto c = color(t, k);
      m.colors.insert(m.colors.end(), c.begin(), c.end());
    }
    m.triangle_colors.push_back(tc);
  }
}

ViewTransform identity_view(int w, int h) { return {0, 0, 1, 1, w, h}; }

RasterOptions opts(int channels, bool antialias, bool antialias_border, int threads) {
  RasterOptions o;
  o.channels = channels;
  o.antialias = antialias;
  o.antialias_border = antialias_border;
  o.threads = threads;
  return o;
}

// Vertices on awkward spots: pixel centres, subsample positions, whole pixels, and random points,
// with whole rows and columns of vertices on sample lines (edges running along samples).
RefinedMesh awkward_mesh(int size, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  std::vector<double> xs{0}, ys{0};
  for (double v = 2; v < size - 1; v += 2) {
    xs.push_back(v + 0.5);                                    // a pixel-centre column
    ys.push_back(v + 0.125 + (int(v) % 4 == 0 ? 0.0 : 0.5));  // subsample rows
  }
  xs.push_back(size);
  ys.push_back(size);
  RefinedMesh m = grid_mesh(xs, ys);
  // Move interior vertices, some to random points, some to pixel centres off the grid lines.
  const int nx = static_cast<int>(xs.size()), ny = static_cast<int>(ys.size());
  for (int j = 1; j + 1 < ny; ++j) {
    for (int i = 1; i + 1 < nx; ++i) {
      float* p = m.positions.data() + 2 * (j * nx + i);
      switch ((i * 7 + j * 3) % 4) {
        case 0:
          p[0] += static_cast<float>(u(rng));
          p[1] += static_cast<float>(u(rng));
          break;
        case 1:
          p[0] = std::floor(p[0]) + 0.5f;
          p[1] = std::floor(p[1]) + 0.5f;
          break;
        default:
          break;
      }
    }
  }
  corner_colors(m, [](int t, int) { return std::array<float, 3>{float(t % 256), 0, 0}; });
  return m;
}

// A fan of 16 triangles around a vertex on a pixel centre, spokes along axes and diagonals
// through sample points.
RefinedMesh fan_mesh() {
  RefinedMesh m;
  auto add = [&](float x, float y) {
    m.positions.push_back(x);
    m.positions.push_back(y);
    return m.num_vertices() - 1;
  };
  const int centre = add(16.5f, 16.5f);
  // Ring around the square [0, 33]^2, clockwise in y-down coordinates so that (centre, r_k, r_k+1)
  // has positive area.
  std::vector<std::array<float, 2>> ring = {{0, 0},      {16.5f, 0},  {33, 0},      {33, 8.25f},
                                            {33, 16.5f}, {33, 33},    {24.75f, 33}, {16.5f, 33},
                                            {0, 33},     {0, 24.75f}, {0, 16.5f},   {0, 4.125f}};
  std::vector<int> ids;
  for (auto [x, y] : ring) ids.push_back(add(x, y));
  for (size_t k = 0; k < ids.size(); ++k)
    m.triangles.push_back({centre, ids[k], ids[(k + 1) % ids.size()]});
  corner_colors(m, [](int t, int) { return std::array<float, 3>{float(t), 0, 0}; });
  return m;
}

TEST(RasterFillRule, EveryCentreSampleIsDrawnExactlyOnce) {
  for (uint32_t seed : {1u, 2u, 3u}) {
    const RefinedMesh m = awkward_mesh(40, seed);
    const auto counts = sample_coverage(m, identity_view(40, 40), false);
    for (size_t i = 0; i < counts.size(); ++i) {
      ASSERT_EQ(counts[i], 1) << "pixel " << i % 40 << "," << i / 40 << " seed " << seed;
    }
  }
}

// Scaled views exercise every traversal path: single candidate samples (triangles under a pixel),
// the vectorized test of small triangles, and the general one for large triangles.
TEST(RasterFillRule, ExactlyOnceAtEveryScale) {
  const RefinedMesh m = awkward_mesh(40, 4);
  for (double s : {0.25, 0.4, 0.5, 1.5, 2.0, 3.0, 5.0, 12.0}) {
    const int n = static_cast<int>(40 * s);
    for (bool sub : {false, true}) {
      const auto counts = sample_coverage(m, {0, 0, s, s, n, n}, sub);
      for (size_t i = 0; i < counts.size(); ++i) {
        ASSERT_EQ(counts[i], 1) << "sample " << i << " scale " << s << " subsamples " << sub;
      }
    }
  }
}

TEST(RasterFillRule, EverySubsampleIsDrawnExactlyOnce) {
  const RefinedMesh m = awkward_mesh(40, 7);
  const auto counts = sample_coverage(m, identity_view(40, 40), true);
  for (size_t i = 0; i < counts.size(); ++i) ASSERT_EQ(counts[i], 1) << "subsample " << i;
}

TEST(RasterFillRule, FanAroundASampleVertex) {
  const RefinedMesh m = fan_mesh();
  for (bool sub : {false, true}) {
    const auto counts = sample_coverage(m, identity_view(33, 33), sub);
    for (size_t i = 0; i < counts.size(); ++i)
      ASSERT_EQ(counts[i], 1) << "sample " << i << " sub " << sub;
  }
  // Scaled views put the vertex and the spokes on other sample positions.
  for (double s : {2.0, 0.5, 3.0}) {
    const int n = static_cast<int>(33 * s);
    const auto counts = sample_coverage(m, {0, 0, s, s, n, n}, false);
    for (size_t i = 0; i < counts.size(); ++i)
      ASSERT_EQ(counts[i], 1) << "sample " << i << " scale " << s;
  }
}

TEST(RasterFillRule, BackFacingAndDegenerateTrianglesDrawNothing) {
  RefinedMesh m;
  m.positions = {0, 0, 10, 0, 10, 10, 5, 5};
  m.triangles = {{0, 2, 1},
                 {0, 1, 3}};         // clockwise in y-down terms: negative area; then a valid one
  m.triangles.push_back({0, 3, 2});  // collinear: zero area... (0,0),(5,5),(10,10)
  const auto counts = sample_coverage(m, identity_view(10, 10), false);
  int total = 0;
  for (int c : counts) total += c;
  // Only triangle (0, 1, 3) with vertices (0,0), (10,0), (5,5) draws: 25 pixel centres.
  EXPECT_EQ(total, 25);
}

TEST(Raster, ConstantColorIsExactEverywhere) {
  RefinedMesh m = awkward_mesh(48, 5);
  corner_colors(m, [](int, int) { return std::array<float, 3>{37.f, 142.f, 201.f}; });
  // Mark every edge as a tear so that every pixel is supersampled too.
  for (const Tri& t : m.triangles) {
    for (int k = 0; k < 3; ++k) m.tear_edges.push_back({t[k], t[(k + 1) % 3]});
  }
  for (bool aa : {false, true}) {
    const Image8 img = rasterize(m, identity_view(48, 48), opts(3, aa, false, 2));
    ASSERT_EQ(img.channels, 3);
    for (size_t i = 0; i < img.pixels.size(); i += 3) {
      ASSERT_EQ(img.pixels[i], 37);
      ASSERT_EQ(img.pixels[i + 1], 142);
      ASSERT_EQ(img.pixels[i + 2], 201);
    }
  }
}

TEST(Raster, GouraudReproducesAnAffineField) {
  RefinedMesh m = awkward_mesh(48, 9);
  auto f = [](double x, double y) {
    return std::array<double, 3>{20 + 4 * x, 250 - 3.5 * y, 10 + 2 * x + 2 * y};
  };
  corner_colors(m, [&](int t, int k) {
    const int v = m.triangles[t][k];
    const auto c = f(m.positions[2 * v], m.positions[2 * v + 1]);
    return std::array<float, 3>{float(c[0]), float(c[1]), float(c[2])};
  });
  const Image8 img = rasterize(m, identity_view(48, 48), opts(3, false, false, 1));
  for (int y = 0; y < 48; ++y) {
    for (int x = 0; x < 48; ++x) {
      const auto c = f(x + 0.5, y + 0.5);
      for (int ch = 0; ch < 3; ++ch) {
        ASSERT_NEAR(img.row(y)[3 * x + ch], std::clamp(c[ch], 0.0, 255.0), 0.51) << x << "," << y;
      }
    }
  }
}

// Two flat halves meeting along a tear at x = 10.3.
RefinedMesh split_mesh() {
  RefinedMesh m = grid_mesh({0, 4, 10.3, 15, 24}, {0, 6, 12.25, 24});
  corner_colors(m, [&](int t, int) {
    double cx = 0;
    for (int v : m.triangles[t]) cx += m.positions[2 * v] / 3.0;
    return cx < 10.3 ? std::array<float, 3>{200, 40, 10} : std::array<float, 3>{20, 60, 240};
  });
  for (int j = 0; j + 1 < 4; ++j) m.tear_edges.push_back({j * 5 + 2, (j + 1) * 5 + 2});
  return m;
}

TEST(Raster, TearIsAntialiasedOnlyWhereItCrosses) {
  const RefinedMesh m = split_mesh();
  const Image8 aa = rasterize(m, identity_view(24, 24), opts(3, true, false, 1));
  const Image8 plain = rasterize(m, identity_view(24, 24), opts(3, false, false, 1));
  for (int y = 0; y < 24; ++y) {
    for (int x = 0; x < 24; ++x) {
      const uint8_t* p = aa.row(y) + 3 * x;
      const uint8_t* q = plain.row(y) + 3 * x;
      if (x < 10) {
        EXPECT_EQ(p[0], 200);
        EXPECT_EQ(q[0], 200);
      } else if (x > 10) {
        EXPECT_EQ(p[2], 240);
        EXPECT_EQ(q[2], 240);
      } else {
        // Column 10 is crossed at x = 10.3: one of the four subsample columns lies left of it.
        EXPECT_EQ(p[0], (200 + 3 * 20 + 2) / 4);
        EXPECT_EQ(p[2], (240 * 3 + 10 + 2) / 4);
        EXPECT_EQ(q[0], 20);  // the centre 10.5 is on the right
      }
    }
  }
}

TEST(Raster, UncoveredSamplesAreTransparentAndTheBorderIsAntialiased) {
  RefinedMesh m = grid_mesh({0, 8, 16}, {0, 8, 16});
  corner_colors(m, [](int, int) { return std::array<float, 3>{90, 90, 90}; });
  for (int k = 0; k < 2; ++k) {
    m.border_edges.push_back({k, k + 1});
    m.border_edges.push_back({6 + k, 6 + k + 1});
    m.border_edges.push_back({3 * k, 3 * (k + 1)});
    m.border_edges.push_back({3 * k + 2, 3 * (k + 1) + 2});
  }
  // The image [0,16]^2 seen through the window [-4.6, -4.6, 20.4, 20.4] at scale 1.
  const ViewTransform view{-4.6, -4.6, 1, 1, 25, 25};
  const Image8 aa = rasterize(m, view, opts(4, true, true, 1));
  const Image8 plain = rasterize(m, view, opts(4, false, false, 1));
  ASSERT_EQ(aa.channels, 4);
  for (int y = 0; y < 25; ++y) {
    for (int x = 0; x < 25; ++x) {
      const bool edge = x == 4 || y == 4 || x == 20 || y == 20;
      const bool inside = x >= 4 && x <= 20 && y >= 4 && y <= 20;
      const uint8_t a = aa.row(y)[4 * x + 3], b = plain.row(y)[4 * x + 3];
      if (!inside) {
        EXPECT_EQ(a, 0) << x << "," << y;
        EXPECT_EQ(b, 0) << x << "," << y;
      } else if (edge) {
        EXPECT_GT(a, 0) << x << "," << y;
        EXPECT_LT(a, 255) << x << "," << y;
        EXPECT_EQ(aa.row(y)[4 * x], 90);  // straight alpha: the color is the covered mean
      } else {
        EXPECT_EQ(a, 255);
        EXPECT_EQ(b, 255);
      }
    }
  }
  // Pixel (4, 10): the border x = 0 is at 4.6, so 2 of the 4 subsample columns are covered.
  EXPECT_EQ(aa.row(10)[4 * 4 + 3], 128);
  // Pixel (4, 10) without anti-aliasing: the centre 4.5 is outside.
  EXPECT_EQ(plain.row(10)[4 * 4 + 3], 0);
}

TEST(Raster, OutputIsIdenticalForAnyThreadCount) {
  RefinedMesh m = awkward_mesh(200, 11);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-20, 275);  // out of range too: clamped
  corner_colors(m, [&](int, int) { return std::array<float, 3>{u(rng), u(rng), u(rng)}; });
  for (const Tri& t : m.triangles) {
    if (t[0] % 3 == 0) m.tear_edges.push_back({t[0], t[1]});
  }
  const ViewTransform view{-3.3, 1.7, 2.7, 2.1, 517, 389};  // scaled, the mesh leaves the output
  std::vector<OverlayLayer> overlay(1);
  overlay[0].segments = {{0, 0, 517, 389}, {10, 300, 400, 12}};
  overlay[0].dots = {{100, 100, 3}};
  const Image8 one = rasterize(m, view, opts(4, true, true, 1), overlay);
  for (int threads : {2, 3, 8}) {
    const Image8 other = rasterize(m, view, opts(4, true, true, threads), overlay);
    EXPECT_EQ(one.pixels, other.pixels) << threads << " threads";
  }
}

// A slow, obvious reference for the pixel-centre pass: every triangle against every pixel centre
// of its bounding box, with int64 edge functions under the top-left rule on the same 24.8 snapped
// vertices, and Gouraud colors in double precision. RGBA: alpha 255 where a triangle owns the
// centre.
Image8 reference_centres(const RefinedMesh& m, const ViewTransform& view) {
  Image8 out(view.width, view.height, 4);
  auto snap = [](double v) { return static_cast<int64_t>(std::floor(v * 256 + 0.5)); };
  for (int t = 0; t < m.num_triangles(); ++t) {
    int64_t x[3], y[3];
    for (int k = 0; k < 3; ++k) {
      const int v = m.triangles[t][k];
      const auto o = view.to_output(m.positions[2 * v], m.positions[2 * v + 1]);
      x[k] = snap(o[0]);
      y[k] = snap(o[1]);
    }
    const int64_t area2 = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
    if (area2 <= 0) continue;
    const int64_t x0 = std::max<int64_t>(std::min({x[0], x[1], x[2]}) / 256 - 1, 0);
    const int64_t x1 = std::min<int64_t>(std::max({x[0], x[1], x[2]}) / 256 + 1, view.width - 1);
    const int64_t y0 = std::max<int64_t>(std::min({y[0], y[1], y[2]}) / 256 - 1, 0);
    const int64_t y1 = std::min<int64_t>(std::max({y[0], y[1], y[2]}) / 256 + 1, view.height - 1);
    for (int64_t py = y0; py <= y1; ++py) {
      for (int64_t px = x0; px <= x1; ++px) {
        const int64_t sx = px * 256 + 128, sy = py * 256 + 128;
        bool inside = true;
        double w[3];
        for (int k = 0; k < 3; ++k) {
          const int a = (k + 1) % 3, b = (k + 2) % 3;
          const int64_t dx = x[b] - x[a], dy = y[b] - y[a];
          const int64_t e = dx * (sy - y[a]) - dy * (sx - x[a]);
          inside = inside && (e > 0 || (e == 0 && (dy > 0 || (dy == 0 && dx > 0))));
          w[k] = double(e) / double(area2);
        }
        if (!inside) continue;
        uint8_t* p = out.row(static_cast<int>(py)) + 4 * px;
        for (int c = 0; c < 3; ++c) {
          double v = 0;
          for (int k = 0; k < 3; ++k) v += w[k] * m.colors[3 * m.triangle_colors[t][k] + c];
          p[c] = static_cast<uint8_t>(std::lround(std::clamp(v, 0.0, 255.0)));
        }
        p[3] = 255;
      }
    }
  }
  return out;
}

// The fast paths of the centre pass (several triangles at a time, clipped to the output and to
// bands) against the reference, at scales that make triangles from under a pixel to a few pixels.
TEST(Raster, CentresMatchTheReference) {
  RefinedMesh m = awkward_mesh(60, 13);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0, 255);
  corner_colors(m, [&](int, int) { return std::array<float, 3>{u(rng), u(rng), u(rng)}; });
  for (double s : {0.3, 0.7, 1.0, 1.6, 2.3, 3.1, 4.5}) {
    // The mesh leaves the output on every side.
    const int w = static_cast<int>(55 * s), h = static_cast<int>(50 * s);
    const ViewTransform view{2.3, 3.1, s, s * 0.85, w, h};
    const Image8 want = reference_centres(m, view);
    for (int threads : {1, 3}) {
      const Image8 got = rasterize(m, view, opts(4, false, false, threads));
      for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
          const uint8_t* a = got.row(y) + 4 * x;
          const uint8_t* b = want.row(y) + 4 * x;
          ASSERT_EQ(a[3], b[3]) << x << "," << y << " scale " << s << " threads " << threads;
          for (int c = 0; c < 3; ++c) {
            ASSERT_NEAR(a[c], b[c], 1) << x << "," << y << " scale " << s << " channel " << c;
          }
        }
      }
    }
  }
}

TEST(Raster, OverlayCoversItsLine) {
  RefinedMesh m = grid_mesh({0, 32}, {0, 32});
  corner_colors(m, [](int, int) { return std::array<float, 3>{0, 0, 0}; });
  OverlayLayer line{{255, 255, 255}, 1.f, 0.5f, {{{0, 16.5f, 32, 16.5f}}}, {}};
  const Image8 img =
      rasterize(m, identity_view(32, 32), opts(3, true, false, 1), std::span(&line, 1));
  for (int x = 0; x < 32; ++x) {
    EXPECT_EQ(img.row(16)[3 * x], 255);  // centre row of the line: fully covered
    EXPECT_EQ(img.row(14)[3 * x], 0);    // two rows away: untouched
  }
}

}  // namespace
}  // namespace subvec::detail
