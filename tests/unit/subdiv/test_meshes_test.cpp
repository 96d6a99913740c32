// The test meshes themselves: valid, and shaped as their documentation says.
#include <set>

#include <gtest/gtest.h>

#include "subvec/mesh/validate.h"
#include "support/test_meshes.h"

namespace subvec {
namespace {

using testing::TestMesh;

double signed_area(const ControlMesh& m, const Tri& t) {
  const Vec2 a = m.positions[t[0]], b = m.positions[t[1]], c = m.positions[t[2]];
  return 0.5 * ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
}

int count_colors_at(const ControlMesh& m, int v) {
  std::set<int> colors;
  for (int f = 0; f < m.num_triangles(); ++f)
    for (int k = 0; k < 3; ++k)
      if (m.triangles[f][k] == v) colors.insert(m.triangle_colors[f][k]);
  return static_cast<int>(colors.size());
}

TEST(TestMeshes, AreValidTilingsOfTheirImage) {
  for (const TestMesh& t : testing::all_test_meshes()) {
    SCOPED_TRACE(t.name);
    const ControlMesh& m = t.mesh;
    EXPECT_NO_THROW(validate_level(m, t.width, t.height)) << t.name;
    const MeshTopology topo = t.topology();
    double area = 0;
    for (const Tri& tri : m.triangles) {
      EXPECT_GT(signed_area(m, tri), 0.1);
      area += signed_area(m, tri);
    }
    EXPECT_NEAR(area, double(t.width) * t.height, 1e-9);
    // Border edges lie on the image border; the four corners are vertices.
    for (int e = 0; e < topo.num_edges(); ++e) {
      if (topo.edge_tags[e] != EdgeTag::kBorder) continue;
      const Vec2 a = m.positions[topo.edges[e][0]], b = m.positions[topo.edges[e][1]];
      const bool on_side = (a.x == b.x && (a.x == 0 || a.x == t.width)) ||
                           (a.y == b.y && (a.y == 0 || a.y == t.height));
      EXPECT_TRUE(on_side) << "border edge " << e;
    }
    int image_corners = 0;
    for (const Vec2& p : m.positions)
      image_corners += (p.x == 0 || p.x == t.width) && (p.y == 0 || p.y == t.height);
    EXPECT_EQ(image_corners, 4);
    // Corners across a non-tear edge share their color values.
    for (int e = 0; e < topo.num_edges(); ++e) {
      const auto [f, g] = topo.edge_faces[e];
      if (g < 0 || topo.edge_tags[e] == EdgeTag::kTear) continue;
      for (int v : topo.edges[e]) {
        int kf = 0, kg = 0;
        while (m.triangles[f][kf] != v) ++kf;
        while (m.triangles[g][kg] != v) ++kg;
        EXPECT_EQ(m.triangle_colors[f][kf], m.triangle_colors[g][kg]) << "edge " << e;
      }
    }
  }
}

TEST(TestMeshes, HaveTheDocumentedFeatures) {
  for (int n = 3; n <= 8; ++n) {
    const TestMesh t = testing::valence_mesh(n);
    const MeshTopology topo = t.topology();
    EXPECT_EQ(topo.vertex_tags[t.focus], VertexTag::kSmooth);
    auto [begin, end] = topo.faces_of(t.focus);
    EXPECT_EQ(end - begin, n);
  }

  const TestMesh disk = testing::torn_disk();
  const MeshTopology disk_topo = disk.topology();
  for (size_t i = 0; i + 1 < disk.mesh.features[0].vertices.size(); ++i) {
    const int v = disk.mesh.features[0].vertices[i];
    EXPECT_EQ(disk_topo.vertex_tags[v], VertexTag::kTear);
    EXPECT_EQ(count_colors_at(disk.mesh, v), 2);
  }

  const TestMesh open = testing::open_tear();
  const MeshTopology open_topo = open.topology();
  EXPECT_EQ(open_topo.vertex_tags[open.focus], VertexTag::kCorner);
  EXPECT_EQ(count_colors_at(open.mesh, open.focus), 1);
  EXPECT_EQ(count_colors_at(open.mesh, open.mesh.features[0].vertices[1]), 2);

  const TestMesh junction = testing::tear_junction();
  const MeshTopology junction_topo = junction.topology();
  EXPECT_EQ(junction_topo.vertex_tags[junction.focus], VertexTag::kCorner);
  EXPECT_EQ(count_colors_at(junction.mesh, junction.focus), 3);
  EXPECT_EQ(count_colors_at(junction.mesh, junction.mesh.features[2].vertices.back()), 2);

  const TestMesh crease = testing::interior_crease();
  const MeshTopology crease_topo = crease.topology();
  EXPECT_EQ(crease_topo.vertex_tags[crease.focus], VertexTag::kCorner);
  EXPECT_EQ(crease_topo.vertex_tags[crease.mesh.creases[0][0]],
            VertexTag::kCorner);  // on the border
  EXPECT_EQ(crease_topo.vertex_tags[crease.mesh.creases[1][0]], VertexTag::kCrease);
  EXPECT_EQ(count_colors_at(crease.mesh, crease.mesh.creases[1][0]), 1);
}

}  // namespace
}  // namespace subvec
