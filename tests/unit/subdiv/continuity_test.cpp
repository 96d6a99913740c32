// Continuity of the limit (paper §3.2): the color field is C^1 across smooth control edges, the
// feature curves are cubic B-splines (C^2), and LimitEvaluator agrees with the reference limit.
#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "subvec/subdiv/subdivision.h"
#include "support/reference_loop.h"
#include "support/test_meshes.h"

namespace subvec {
namespace {

using testing::StencilMesh;
using testing::TestMesh;

int corner_of(const ControlMesh& m, int f, int v) {
  for (int k = 0; k < 3; ++k)
    if (m.triangles[f][k] == v) return k;
  return -1;
}

// The point at fraction s along edge (a, b) of face f, in LimitEvaluator's (u, v): corner 0 at
// (0, 0), corner 1 at (1, 0), corner 2 at (0, 1).
LimitEvaluator::Sample sample_edge(const LimitEvaluator& eval, const ControlMesh& m, int f, int a,
                                   int b, double s) {
  const int ka = corner_of(m, f, a), kb = corner_of(m, f, b);
  const double corner_uv[3][2] = {{0, 0}, {1, 0}, {0, 1}};
  return eval.evaluate(f, (1 - s) * corner_uv[ka][0] + s * corner_uv[kb][0],
                       (1 - s) * corner_uv[ka][1] + s * corner_uv[kb][1]);
}

// Image-space gradient of color channel ch: [dC/du dC/dv] = g^T J with J = d(x, y)/d(u, v).
std::array<double, 2> color_gradient(const LimitEvaluator::Sample& s, int ch) {
  const double xu = s.position_du.x, xv = s.position_dv.x, yu = s.position_du.y,
               yv = s.position_dv.y;
  const double det = xu * yv - xv * yu;
  const double cu = s.color_du[ch], cv = s.color_dv[ch];
  return {(cu * yv - cv * yu) / det, (cv * xu - cu * xv) / det};
}

// Samples every smooth control edge from both of its faces: same position and color, and the
// same image-space color gradient (so the derivative across the edge is continuous too).
TEST(Continuity, ColorIsC1AcrossSmoothEdges) {
  std::vector<TestMesh> meshes{testing::grid_mesh(6, 5, 4, true), testing::torn_disk(),
                               testing::tear_junction(), testing::interior_crease()};
  for (int n = 3; n <= 8; ++n) meshes.push_back(testing::valence_mesh(n));
  for (const TestMesh& t : meshes) {
    SCOPED_TRACE(t.name);
    const MeshTopology topo = t.topology();
    const LimitEvaluator eval(t.mesh, topo);
    double largest_gradient = 0;
    for (int e = 0; e < topo.num_edges(); ++e) {
      if (topo.edge_tags[e] != EdgeTag::kSmooth) continue;
      const auto [a, b] = topo.edges[e];
      const auto [f, g] = topo.edge_faces[e];
      for (double s : {0.25, 0.5, 0.75}) {
        const auto x = sample_edge(eval, t.mesh, f, a, b, s),
                   y = sample_edge(eval, t.mesh, g, a, b, s);
        ASSERT_NEAR(x.position.x, y.position.x, 1e-9) << "edge " << a << "-" << b;
        ASSERT_NEAR(x.position.y, y.position.y, 1e-9) << "edge " << a << "-" << b;
        for (int ch = 0; ch < 3; ++ch) {
          EXPECT_NEAR(x.color[ch], y.color[ch], 1e-9) << "edge " << a << "-" << b << " s " << s;
          const auto gx = color_gradient(x, ch), gy = color_gradient(y, ch);
          const double scale = std::max(1.0, std::hypot(gx[0], gx[1]));
          EXPECT_NEAR(gx[0], gy[0], 1e-6 * scale) << "edge " << a << "-" << b << " s " << s;
          EXPECT_NEAR(gx[1], gy[1], 1e-6 * scale) << "edge " << a << "-" << b << " s " << s;
          largest_gradient = std::max(largest_gradient, std::hypot(gx[0], gx[1]));
        }
      }
    }
    EXPECT_GT(largest_gradient,
              1.0);  // the colors are not flat: the check has something to compare
  }
}

// The uniform periodic cubic B-spline of a closed control polygon P (n points) at t in [0, n).
template <class Point>
Point cubic_bspline(const std::vector<Point>& p, double t) {
  const int n = static_cast<int>(p.size());
  const int i = static_cast<int>(std::floor(t));
  const double u = t - i;
  const double w[4] = {(1 - u) * (1 - u) * (1 - u) / 6, (3 * u * u * u - 6 * u * u + 4) / 6,
                       (-3 * u * u * u + 3 * u * u + 3 * u + 1) / 6, u * u * u / 6};
  Point out = p[0] * 0.0;
  for (int j = 0; j < 4; ++j) out += w[j] * p[((i - 1 + j) % n + n) % n];
  return out;
}

// The closed tear of torn_disk, refined k levels and pushed to the limit, is exactly the uniform
// cubic B-spline of its control vertices sampled at t = j / 2^k, with consecutive refined tear
// edges joining consecutive samples. A C^0 or C^1 scheme (e.g. the tear as a polyline, or a
// quadratic curve) puts these points elsewhere.
TEST(Continuity, FeatureCurveIsTheCubicBSplineOfItsControlVertices) {
  const TestMesh t = testing::torn_disk();
  const MeshTopology topo = t.topology();
  std::vector<Eigen::RowVector2d> control;
  const auto& chain = t.mesh.features[0].vertices;
  for (size_t i = 0; i + 1 < chain.size(); ++i)
    control.emplace_back(t.mesh.positions[chain[i]].x, t.mesh.positions[chain[i]].y);
  const int n = static_cast<int>(control.size());
  for (int depth = 1; depth <= 4; ++depth) {
    const int samples = n << depth;
    Eigen::MatrixXd curve(samples, 2);
    for (int j = 0; j < samples; ++j)
      curve.row(j) = cubic_bspline(control, std::ldexp(double(j), -depth));
    for (const StencilMesh& s : {testing::reference_stencils(t.mesh, topo, depth, true),
                                 testing::opensubdiv_stencils(t.mesh, topo, depth, true)}) {
      SCOPED_TRACE("depth " + std::to_string(depth));
      std::set<int> tear_vertices;
      for (const EdgeVerts& e : s.tear_edges) tear_vertices.insert(e.begin(), e.end());
      ASSERT_EQ(static_cast<int>(tear_vertices.size()), samples);
      ASSERT_EQ(static_cast<int>(s.tear_edges.size()), samples);
      std::vector<int> on_curve(s.num_vertices(), -1);
      std::set<int> hit;
      for (int v : tear_vertices) {
        on_curve[v] = testing::match_points(s.positions.row(v), curve, 1e-9)[0];
        ASSERT_GE(on_curve[v], 0) << "refined tear vertex " << v << " is not on the B-spline";
        hit.insert(on_curve[v]);
      }
      EXPECT_EQ(static_cast<int>(hit.size()), samples);
      for (const EdgeVerts& e : s.tear_edges) {
        const int step = (on_curve[e[1]] - on_curve[e[0]] + samples) % samples;
        EXPECT_TRUE(step == 1 || step == samples - 1) << "tear edge skips along the curve";
      }
    }
  }
}

// LimitEvaluator along the tear, from either side: the same B-spline for positions, and each
// side's own B-spline of its colors.
TEST(Continuity, LimitEvaluatorFollowsTheFeatureCurve) {
  const TestMesh t = testing::torn_disk();
  const MeshTopology topo = t.topology();
  const LimitEvaluator eval(t.mesh, topo);
  const auto& chain = t.mesh.features[0].vertices;
  const int n = static_cast<int>(chain.size()) - 1;
  std::vector<Eigen::RowVector2d> control;
  std::vector<Eigen::RowVector3d> inside, outside;
  for (int i = 0; i < n; ++i) {
    control.emplace_back(t.mesh.positions[chain[i]].x, t.mesh.positions[chain[i]].y);
    for (bool in : {true, false}) {
      for (int f = 0; f < t.mesh.num_triangles(); ++f) {  // the side's color value at the vertex
        const int k = corner_of(t.mesh, f, chain[i]);
        if (k < 0 || (f < 8) != in) continue;
        const Color& c = t.mesh.colors[t.mesh.triangle_colors[f][k]];
        (in ? inside : outside).emplace_back(c.r, c.g, c.b);
        break;
      }
    }
  }
  for (int i = 0; i < n; ++i) {
    const int a = chain[i], b = chain[i + 1];
    for (int f : topo.edge_faces[topo.find_edge(a, b)]) {
      for (double s : {0.0, 0.125, 0.5, 0.8}) {
        const auto x = sample_edge(eval, t.mesh, f, a, b, s);
        const Eigen::RowVector2d p = cubic_bspline(control, i + s);
        const Eigen::RowVector3d c = cubic_bspline(f < 8 ? inside : outside, i + s);
        EXPECT_NEAR(x.position.x, p[0], 1e-9) << "edge " << i << " s " << s;
        EXPECT_NEAR(x.position.y, p[1], 1e-9) << "edge " << i << " s " << s;
        for (int ch = 0; ch < 3; ++ch)
          EXPECT_NEAR(x.color[ch], c[ch], 1e-9) << "edge " << i << " s " << s;
      }
    }
  }
}

// LimitEvaluator at the dyadic points of every control face equals the reference's limit of the
// refined vertices there (depth 2), positions and colors, on every test mesh.
TEST(Continuity, LimitEvaluatorMatchesTheReferenceLimit) {
  for (const TestMesh& t : testing::all_test_meshes()) {
    SCOPED_TRACE(t.name);
    const MeshTopology topo = t.topology();
    const LimitEvaluator eval(t.mesh, topo);
    const testing::ReferenceMesh ref = testing::reference_loop(t.mesh, topo, 2, true);
    double position_error = 0, color_error = 0;
    for (int tri = 0; tri < ref.num_triangles(); ++tri) {
      for (int k = 0; k < 3; ++k) {
        const auto [u, v] = ref.triangle_uv[tri][k];
        const auto x = eval.evaluate(ref.triangle_parent[tri], u, v);
        const auto p = ref.vertex_values.row(ref.triangles[tri][k]);
        const auto c = ref.color_values.row(ref.triangle_colors[tri][k]);
        position_error = std::max(
            {position_error, std::abs(x.position.x - p[0]), std::abs(x.position.y - p[1])});
        for (int ch = 0; ch < 3; ++ch)
          color_error = std::max(color_error, std::abs(x.color[ch] - c[ch]));
      }
    }
    EXPECT_LT(position_error, 1e-9);
    EXPECT_LT(color_error, 1e-9);
  }
}

}  // namespace
}  // namespace subvec
