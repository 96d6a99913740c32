// The masks of paper Fig. 2, read off the stencils after one level (no limit push) and off the
// limit stencils at depth 0, for both the OpenSubdiv path and the reference implementation.
#include <cmath>
#include <initializer_list>
#include <map>
#include <ostream>
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
using Weights = std::map<int, double>;  // control index -> weight
using StencilFn = StencilMesh (*)(const ControlMesh&, const MeshTopology&, int, bool);

struct Implementation {
  const char* name;
  StencilFn stencils;
};

void PrintTo(const Implementation& implementation, std::ostream* os) { *os << implementation.name; }

class Masks : public ::testing::TestWithParam<Implementation> {
 protected:
  StencilMesh stencils(const TestMesh& t, int depth, bool limit) const {
    return GetParam().stencils(t.mesh, t.topology(), depth, limit);
  }
};

INSTANTIATE_TEST_SUITE_P(Both, Masks,
                         ::testing::Values(Implementation{"reference", testing::reference_stencils},
                                           Implementation{"opensubdiv",
                                                          testing::opensubdiv_stencils}),
                         [](const auto& param_info) { return std::string(param_info.param.name); });

Vec2 lerp(std::initializer_list<std::pair<double, Vec2>> terms) {
  Vec2 p;
  for (auto [w, q] : terms) p.x += w * q.x, p.y += w * q.y;
  return p;
}

// The refined vertex at `p` (exactly, up to rounding); fails the test when there is none.
int vertex_at(const StencilMesh& s, Vec2 p) {
  Eigen::MatrixXd q(1, 2);
  q << p.x, p.y;
  const int i = testing::match_points(q, s.positions, 1e-9)[0];
  EXPECT_GE(i, 0) << "no refined vertex at (" << p.x << ", " << p.y << ")";
  return i;
}

void expect_row(const Eigen::MatrixXd& stencils, int row, const Weights& expected,
                const std::string& what, double tolerance = 1e-12) {
  SCOPED_TRACE(what);
  ASSERT_GE(row, 0);
  for (int j = 0; j < stencils.cols(); ++j) {
    auto it = expected.find(j);
    EXPECT_NEAR(stencils(row, j), it == expected.end() ? 0.0 : it->second, tolerance)
        << "weight of control " << j;
  }
}

// The color value of control vertex v in face f, and of its neighbour w as seen from that value's
// fan (the face containing edge (v, w) whose corner at v uses the same value).
int color_in_face(const ControlMesh& m, int f, int v) {
  for (int k = 0; k < 3; ++k)
    if (m.triangles[f][k] == v) return m.triangle_colors[f][k];
  return -1;
}
int neighbour_color(const ControlMesh& m, int v, int value, int w) {
  for (int f = 0; f < m.num_triangles(); ++f) {
    if (color_in_face(m, f, v) == value && color_in_face(m, f, w) >= 0)
      return color_in_face(m, f, w);
  }
  return -1;
}

// Refined color values at refined vertex i, each with the control face its triangle lies in.
std::map<int, int> colors_at(const StencilMesh& s, int i) {
  std::map<int, int> colors;
  for (size_t t = 0; t < s.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k)
      if (s.triangles[t][k] == i) colors[s.triangle_colors[t][k]] = s.triangle_parent[t];
  return colors;
}

// The two sharp neighbours of a crease or tear vertex.
std::vector<int> sharp_neighbours(const MeshTopology& topo, int v) {
  std::vector<int> out;
  for (int e = 0; e < topo.num_edges(); ++e) {
    if (!is_sharp(topo.edge_tags[e])) continue;
    if (topo.edges[e][0] == v) out.push_back(topo.edges[e][1]);
    if (topo.edges[e][1] == v) out.push_back(topo.edges[e][0]);
  }
  return out;
}

TEST(LoopWeights, KnownValues) {
  EXPECT_DOUBLE_EQ(testing::loop_alpha(3), 7.0 / 16);      // (3/8 - 1/8)^2 + 3/8
  EXPECT_DOUBLE_EQ(testing::loop_alpha(4), 33.0 / 64);     // (3/8)^2 + 3/8
  EXPECT_DOUBLE_EQ(testing::loop_alpha(6), 5.0 / 8);       // regular: centre 5/8, neighbours 1/16
  EXPECT_DOUBLE_EQ(testing::loop_limit_chi(6), 1.0 / 12);  // regular limit: 1/2 and 1/12
  // The limit mask (l0 on the centre, chi on each of the n neighbours) is the left fixed point of
  // one refinement step restricted to the one-ring: the new centre is alpha c + beta sum n_i and
  // the new neighbour j is the edge point 3/8 c + 3/8 n_j + 1/8 (n_j-1 + n_j+1), so a neighbour's
  // limit weight must satisfy chi = l0 beta + (3/8 + 2/8) chi, with l0 + n chi = 1.
  for (int n = 3; n <= 12; ++n) {
    const double alpha = testing::loop_alpha(n), beta = (1 - alpha) / n;
    const double chi = testing::loop_limit_chi(n), centre = 1 - n * chi;
    EXPECT_NEAR(chi, centre * beta + 5.0 / 8 * chi, 1e-15) << "valence " << n;
    EXPECT_NEAR(centre, centre * alpha + n * chi * 3.0 / 8, 1e-15) << "valence " << n;
  }
}

TEST_P(Masks, SmoothVertexIsAlphaOfValence) {
  for (int n = 3; n <= 8; ++n) {
    const TestMesh t = testing::valence_mesh(n);
    const StencilMesh s = stencils(t, 1, false);
    // By symmetry the centre's vertex point stays at the centre; ring vertices are 1..n.
    const int i = vertex_at(s, t.mesh.positions[0]);
    const double alpha = testing::loop_alpha(n);
    Weights position{{0, alpha}}, color{{color_in_face(t.mesh, 0, 0), alpha}};
    for (int k = 1; k <= n; ++k) {
      position[k] = (1 - alpha) / n;
      color[color_in_face(t.mesh, k - 1, k)] = (1 - alpha) / n;
    }
    expect_row(s.position_stencils, i, position, "valence " + std::to_string(n) + " position");
    const auto colors = colors_at(s, i);
    ASSERT_EQ(colors.size(), 1u);
    expect_row(s.color_stencils, colors.begin()->first, color,
               "valence " + std::to_string(n) + " color");
  }
}

// The same mask through Subdivision::evaluate() (OpenSubdiv's PrimvarRefiner, not its stencil
// tables): an impulse on the centre's color refines to alpha(n) at the centre, an impulse on a ring
// vertex's color to (1 - alpha(n)) / n.
TEST(MaskImpulse, SmoothVertexThroughEvaluate) {
  for (int n = 3; n <= 8; ++n) {
    const TestMesh t = testing::valence_mesh(n);
    const Subdivision subdivision(t.mesh, t.topology(), 1, {}, false);
    RefinedMesh out;
    for (int impulse_vertex : {0, 1}) {
      std::vector<Color> colors(t.mesh.num_colors());
      colors[color_in_face(t.mesh, 0, impulse_vertex)] = {1, 0, 0};
      subdivision.evaluate(t.mesh.positions, colors, out, 1);
      int centre = -1;
      for (int i = 0; i < out.num_vertices(); ++i) {
        if (std::hypot(out.positions[2 * i] - t.mesh.positions[0].x,
                       out.positions[2 * i + 1] - t.mesh.positions[0].y) < 1e-5)
          centre = i;
      }
      ASSERT_GE(centre, 0);
      int color = -1;
      for (int tri = 0; tri < out.num_triangles(); ++tri)
        for (int k = 0; k < 3; ++k)
          if (out.triangles[tri][k] == centre) color = out.triangle_colors[tri][k];
      const double alpha = testing::loop_alpha(n);
      EXPECT_NEAR(out.colors[3 * color], impulse_vertex == 0 ? alpha : (1 - alpha) / n, 1e-7)
          << "valence " << n;
      EXPECT_EQ(out.colors[3 * color + 1], 0.0f);
    }
  }
}

TEST_P(Masks, SmoothLimitOfValence) {
  for (int n = 3; n <= 8; ++n) {
    const TestMesh t = testing::valence_mesh(n);
    const StencilMesh s = stencils(t, 0, true);
    const int i = vertex_at(s, t.mesh.positions[0]);
    const double chi = testing::loop_limit_chi(n);
    Weights position{{0, 1 - n * chi}};
    for (int k = 1; k <= n; ++k) position[k] = chi;
    expect_row(s.position_stencils, i, position, "valence " + std::to_string(n) + " limit");
  }
}

TEST_P(Masks, SmoothEdgeIsThreeEighthsOneEighth) {
  for (int n = 3; n <= 8; ++n) {
    const TestMesh t = testing::valence_mesh(n);
    const StencilMesh s = stencils(t, 1, false);
    const auto& p = t.mesh.positions;
    for (int k = 1; k <= n; ++k) {  // the spoke (0, k) between faces with ring vertices k-1, k+1
      const int prev = k == 1 ? n : k - 1, next = k == n ? 1 : k + 1;
      const int i =
          vertex_at(s, lerp({{0.375, p[0]}, {0.375, p[k]}, {0.125, p[prev]}, {0.125, p[next]}}));
      expect_row(s.position_stencils, i, {{0, 0.375}, {k, 0.375}, {prev, 0.125}, {next, 0.125}},
                 "valence " + std::to_string(n) + " spoke " + std::to_string(k));
    }
  }
}

// Crease and tear vertex points 1/8-6/8-1/8 and edge points 1/2-1/2, for positions and for each
// side's colors, on every crease, tear and border vertex of every test mesh; with `limit`, the
// limit masks 1/6-4/6-1/6 at depth 0.
void expect_sharp_masks(const TestMesh& t, const StencilMesh& s, bool limit) {
  SCOPED_TRACE(t.name);
  const MeshTopology topo = t.topology();
  const ControlMesh& m = t.mesh;
  const double side = limit ? 1.0 / 6 : 1.0 / 8;
  for (int v = 0; v < m.num_vertices(); ++v) {
    const VertexTag tag = topo.vertex_tags[v];
    if (tag != VertexTag::kCrease && tag != VertexTag::kTear) continue;
    const std::vector<int> ab = sharp_neighbours(topo, v);
    ASSERT_EQ(ab.size(), 2u);
    const auto& p = m.positions;
    const int i = vertex_at(s, lerp({{1 - 2 * side, p[v]}, {side, p[ab[0]]}, {side, p[ab[1]]}}));
    const std::string what = "vertex " + std::to_string(v);
    expect_row(s.position_stencils, i, {{v, 1 - 2 * side}, {ab[0], side}, {ab[1], side}}, what);
    const auto colors = colors_at(s, i);
    EXPECT_EQ(colors.size(), tag == VertexTag::kTear ? 2u : 1u) << what;
    // OpenSubdiv's limit mask for colors on a tear uses float weights (1.0f/6.0f, 2.0f/3.0f in
    // Far::PrimvarRefiner::limitFVar): 2e-8 off.
    const double color_tolerance = limit && tag == VertexTag::kTear ? 1e-7 : 1e-12;
    for (auto [color, face] : colors) {
      const int c = color_in_face(m, face, v);
      expect_row(s.color_stencils, color,
                 {{c, 1 - 2 * side},
                  {neighbour_color(m, v, c, ab[0]), side},
                  {neighbour_color(m, v, c, ab[1]), side}},
                 what + " color " + std::to_string(c), color_tolerance);
    }
    if (limit) continue;
    for (int w : ab) {  // edge points, each side's colors from its own face
      const int e = vertex_at(s, lerp({{0.5, p[v]}, {0.5, p[w]}}));
      expect_row(s.position_stencils, e, {{v, 0.5}, {w, 0.5}},
                 what + " edge to " + std::to_string(w));
      const auto edge_colors = colors_at(s, e);
      EXPECT_EQ(edge_colors.size(),
                topo.edge_tags[topo.find_edge(v, w)] == EdgeTag::kTear ? 2u : 1u);
      for (auto [color, face] : edge_colors) {
        expect_row(s.color_stencils, color,
                   {{color_in_face(m, face, v), 0.5}, {color_in_face(m, face, w), 0.5}},
                   what + " edge color");
      }
    }
  }
}

TEST_P(Masks, CreaseAndTearVerticesAndEdges) {
  for (const TestMesh& t : testing::all_test_meshes())
    expect_sharp_masks(t, stencils(t, 1, false), false);
}

TEST_P(Masks, CreaseAndTearLimit) {
  for (const TestMesh& t : testing::all_test_meshes())
    expect_sharp_masks(t, stencils(t, 0, true), true);
}

// Corner vertices (image corners, feature endpoints, junctions, crease endpoints) keep their
// position and every color value at every level, with and without the limit push.
TEST_P(Masks, CornersAreFixed) {
  const int max_depth = std::string(GetParam().name) == "reference" ? 3 : 4;
  for (const TestMesh& t : testing::all_test_meshes()) {
    const MeshTopology topo = t.topology();
    for (int depth = 1; depth <= max_depth; ++depth) {
      for (bool limit : {false, true}) {
        SCOPED_TRACE(t.name + " depth " + std::to_string(depth) + (limit ? " limit" : ""));
        const StencilMesh s = stencils(t, depth, limit);
        for (int v = 0; v < t.mesh.num_vertices(); ++v) {
          if (topo.vertex_tags[v] != VertexTag::kCorner) continue;
          const int i = vertex_at(s, t.mesh.positions[v]);
          expect_row(s.position_stencils, i, {{v, 1.0}}, "corner " + std::to_string(v));
          for (auto [color, face] : colors_at(s, i)) {
            const double tol = limit ? 1e-7 : 1e-12;  // see reference_match_test.cpp
            const int c = color_in_face(t.mesh, face, v);
            EXPECT_NEAR(s.color_stencils(color, c), 1.0, tol) << "corner " << v << " color " << c;
            EXPECT_NEAR(s.color_stencils.row(color).cwiseAbs().sum(), 1.0, tol);
          }
        }
      }
    }
  }
}

}  // namespace
}  // namespace subvec
