// Tears (paper §3.2): the two sides refine independently, the color jumps across a tear by what
// each side's control colors say, and a tear ending inside the image closes continuously.
#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "subvec/subdiv/subdivision.h"
#include "support/reference_loop.h"
#include "support/test_meshes.h"

namespace subvec {
namespace {

using testing::StencilMesh;
using testing::TestMesh;

// Parameters of the point at fraction s along edge k (from corner k to corner k+1) of a face, in
// LimitEvaluator's convention: corner 0 at (0, 0), corner 1 at (1, 0), corner 2 at (0, 1).
std::array<double, 2> edge_uv(int k, double s) {
  switch (k) {
    case 0:
      return {s, 0};
    case 1:
      return {1 - s, s};
    default:
      return {0, 1 - s};
  }
}

// The corner of face f at vertex v.
int corner_of(const ControlMesh& m, int f, int v) {
  for (int k = 0; k < 3; ++k)
    if (m.triangles[f][k] == v) return k;
  return -1;
}

// Samples edge (a, b) of face f at fraction s from a.
LimitEvaluator::Sample sample_edge(const LimitEvaluator& eval, const ControlMesh& m, int f, int a,
                                   int b, double s) {
  const int ka = corner_of(m, f, a);
  const bool forward = m.triangles[f][(ka + 1) % 3] == b;
  const auto uv = forward ? edge_uv(ka, s) : edge_uv((ka + 2) % 3, 1 - s);
  return eval.evaluate(f, uv[0], uv[1]);
}

double color_distance(const LimitEvaluator::Sample& x, const LimitEvaluator::Sample& y) {
  return std::hypot(x.color[0] - y.color[0], x.color[1] - y.color[1], x.color[2] - y.color[2]);
}

// Inside and outside color values of the torn disk (faces 0..7 are the inside).
std::set<int> side_colors(const ControlMesh& m, bool inside) {
  std::set<int> colors;
  for (int f = 0; f < m.num_triangles(); ++f)
    if ((f < 8) == inside) colors.insert(m.triangle_colors[f].begin(), m.triangle_colors[f].end());
  return colors;
}

class Tears : public ::testing::TestWithParam<bool> {};  // the parameter: with the limit push
INSTANTIATE_TEST_SUITE_P(LimitOrNot, Tears, ::testing::Bool(), [](const auto& param_info) {
  return std::string(param_info.param ? "Limit" : "Refined");
});

// Every refined color on one side of the closed tear depends on that side's control colors only,
// in both implementations.
TEST_P(Tears, SidesDependOnTheirOwnColorsOnly) {
  const TestMesh t = testing::torn_disk();
  const MeshTopology topo = t.topology();
  const std::set<int> inside = side_colors(t.mesh, true), outside = side_colors(t.mesh, false);
  for (int c : inside) ASSERT_EQ(outside.count(c), 0u) << "the sides share color value " << c;
  for (int depth = 1; depth <= 3; ++depth) {
    for (const StencilMesh& s : {testing::reference_stencils(t.mesh, topo, depth, GetParam()),
                                 testing::opensubdiv_stencils(t.mesh, topo, depth, GetParam())}) {
      for (size_t tri = 0; tri < s.triangles.size(); ++tri) {
        const std::set<int>& other = s.triangle_parent[tri] < 8 ? outside : inside;
        for (int color : s.triangle_colors[tri])
          for (int c : other) ASSERT_EQ(s.color_stencils(color, c), 0.0) << "depth " << depth;
      }
    }
  }
}

// Changing one color value on the inside of the tear changes inside colors along the tear and
// leaves every outside color exactly as it was.
TEST_P(Tears, ChangingOneSideLeavesTheOtherUnchanged) {
  TestMesh t = testing::torn_disk();
  const MeshTopology topo = t.topology();
  const Subdivision subdivision(t.mesh, topo, 2, {}, GetParam());
  RefinedMesh before, after;
  subdivision.evaluate(t.mesh.positions, t.mesh.colors, before, 1);
  const int tear_vertex = t.focus;
  const int inside_color = t.mesh.triangle_colors[0][corner_of(t.mesh, 0, tear_vertex)];
  t.mesh.colors[inside_color].g += 50;
  subdivision.evaluate(t.mesh.positions, t.mesh.colors, after, 1);
  int changed_inside = 0;
  for (int tri = 0; tri < before.num_triangles(); ++tri) {
    const bool is_inside = before.triangle_parent[tri] < 8;
    for (int color : before.triangle_colors[tri]) {
      for (int ch = 0; ch < 3; ++ch) {
        const float x = before.colors[3 * color + ch], y = after.colors[3 * color + ch];
        if (is_inside) {
          changed_inside += x != y;
        } else {
          ASSERT_EQ(x, y) << "outside color value " << color;
        }
      }
    }
  }
  EXPECT_GT(changed_inside, 0);
  EXPECT_EQ(before.positions, after.positions);
}

// With colors linear on each side (L_in, L_out) the limit reproduces them (affine invariance of
// the masks), so along the tear the two sides differ by exactly (L_in - L_out)(x) while the
// positions agree.
TEST(TearLimit, ColorJumpsByTheSidesDifference) {
  TestMesh t = testing::torn_disk();
  auto inside = [](Vec2 p) {
    return Color{float(10 + 2 * p.x), float(50 + 3 * p.y), float(100 - p.x + p.y)};
  };
  auto outside = [](Vec2 p) {
    return Color{float(200 - 3 * p.y), float(20 + p.x), float(240 - 2 * p.x)};
  };
  testing::assign_colors(t, [&](Vec2 p, int face) { return face < 8 ? inside(p) : outside(p); });
  const MeshTopology topo = t.topology();
  const LimitEvaluator eval(t.mesh, topo);
  const std::vector<int32_t>& chain = t.mesh.features[0].vertices;
  double smallest_jump = 1e9;
  for (size_t i = 0; i + 1 < chain.size(); ++i) {
    const int a = chain[i], b = chain[i + 1];
    const auto faces = topo.edge_faces[topo.find_edge(a, b)];
    const int in = faces[0] < 8 ? faces[0] : faces[1], out = faces[0] < 8 ? faces[1] : faces[0];
    ASSERT_LT(in, 8);
    ASSERT_GE(out, 8);
    for (double s : {0.0, 0.2, 0.5, 0.9}) {
      const auto x = sample_edge(eval, t.mesh, in, a, b, s),
                 y = sample_edge(eval, t.mesh, out, a, b, s);
      EXPECT_NEAR(x.position.x, y.position.x, 1e-9);
      EXPECT_NEAR(x.position.y, y.position.y, 1e-9);
      const Color li = inside(x.position), lo = outside(x.position);
      const double expected[3] = {li.r - lo.r, li.g - lo.g, li.b - lo.b};
      const double want_in[3] = {10 + 2 * x.position.x, 50 + 3 * x.position.y,
                                 100 - x.position.x + x.position.y};
      for (int ch = 0; ch < 3; ++ch) {
        // Control colors are floats: the linear field is stored to ~1e-5.
        EXPECT_NEAR(x.color[ch], want_in[ch], 1e-4) << "edge " << a << "-" << b << " s " << s;
        EXPECT_NEAR(x.color[ch] - y.color[ch], expected[ch], 1e-4)
            << "edge " << a << "-" << b << " s " << s;
      }
      smallest_jump = std::min(smallest_jump, color_distance(x, y));
    }
  }
  EXPECT_GT(smallest_jump, 10);  // a real discontinuity everywhere along the tear
}

// At the endpoint of a tear inside the image the two sides share one color value, which the corner
// mask holds fixed: approaching the endpoint along the tear, the difference between the sides'
// limit colors shrinks to zero (linearly: the sides are cubic curves with a common end), while it
// is clearly nonzero away from the endpoint.
TEST(TearLimit, ColorIsContinuousAtAnEndpointInsideTheImage) {
  const TestMesh t = testing::open_tear();
  const MeshTopology topo = t.topology();
  const LimitEvaluator eval(t.mesh, topo);
  const int end = t.focus, next = t.mesh.features[0].vertices[1];
  ASSERT_EQ(end, t.mesh.features[0].vertices[0]);
  const auto faces = topo.edge_faces[topo.find_edge(end, next)];
  const Color& end_color =
      t.mesh.colors[t.mesh.triangle_colors[faces[0]][corner_of(t.mesh, faces[0], end)]];
  double previous = 1e9;
  for (int level = 1; level <= 12; ++level) {
    const double s = std::ldexp(1.0, -level);
    const auto x = sample_edge(eval, t.mesh, faces[0], end, next, s);
    const auto y = sample_edge(eval, t.mesh, faces[1], end, next, s);
    const double d = color_distance(x, y);
    if (level == 1) {
      EXPECT_GT(d, 5.0);
    }
    EXPECT_LT(d, previous * 0.75) << "s = " << s;  // keeps shrinking
    EXPECT_LT(d, 200 * s) << "s = " << s;          // like O(s)
    previous = d;
  }
  const auto x = sample_edge(eval, t.mesh, faces[0], end, next, 0);
  const auto y = sample_edge(eval, t.mesh, faces[1], end, next, 0);
  EXPECT_NEAR(color_distance(x, y), 0, 1e-9);
  EXPECT_NEAR(x.color[0], end_color.r, 1e-4);
  EXPECT_NEAR(x.color[1], end_color.g, 1e-4);
  EXPECT_NEAR(x.color[2], end_color.b, 1e-4);
  EXPECT_NEAR(x.position.x, t.mesh.positions[end].x, 1e-9);  // the corner stays put
  EXPECT_NEAR(x.position.y, t.mesh.positions[end].y, 1e-9);
}

}  // namespace
}  // namespace subvec
