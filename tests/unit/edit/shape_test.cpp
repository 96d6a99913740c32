// Shape editing (edit/shape.h): drags meet their constraints, beat the Gaussian falloff alone in
// rigidity, keep the image frame and the feature curves, and never fold the mesh (issue 25).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <limits>
#include <vector>

#include "subvec/core/error.h"
#include "subvec/edit/arap.h"
#include "subvec/edit/ops.h"
#include "subvec/edit/selection.h"
#include "subvec/edit/shape.h"
#include "subvec/mesh/curves.h"
#include "subvec/mesh/validate.h"
#include "subvec/subdiv/subdivision.h"
#include "subvec/io/image_io.h"
#include "subvec/render/renderer.h"
#include "subvec/vectorize/vectorize.h"
#include "support/shared_photos.h"
#include "support/synthetic.h"

namespace subvec {
namespace {

VectorImage image_with_features() {
  test::SyntheticOptions o;
  o.width = 160;
  o.height = 128;
  o.vertices = 900;
  return test::make_synthetic_image(o);
}

double segment_distance(Vec2 p, Vec2 a, Vec2 b) {
  const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
  const double u = len2 > 0 ? std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / len2, 0.0, 1.0) : 0;
  return std::hypot(p.x - a.x - u * dx, p.y - a.y - u * dy);
}

// Every refined tear vertex of the limit surface lies on the B-spline of its feature's chain
// (mesh/curves.h): the feature curves are the C^2 cubic B-splines of the edited control chains.
void expect_feature_curves_are_bsplines(const VectorImage& image) {
  const ControlMesh& mesh = image.levels[0];
  const MeshTopology topology = validate_level(mesh, image.width, image.height);
  std::vector<std::vector<Vec2>> curves;
  for (const Feature& f : mesh.features)
    for (const CurvePiece& piece : feature_pieces(topology, f))
      curves.push_back(sample_bspline(piece_points(mesh, piece), piece.closed, 64));
  const Subdivision subdivision(mesh, topology, 3);
  RefinedMesh refined;
  subdivision.evaluate(mesh.positions, mesh.colors, refined, 1);
  ASSERT_FALSE(refined.tear_edges.empty());
  double worst = 0;
  for (const EdgeVerts& e : refined.tear_edges) {
    for (const int v : e) {
      const Vec2 p{refined.positions[2 * size_t(v)], refined.positions[2 * size_t(v) + 1]};
      double d = std::numeric_limits<double>::infinity();
      for (const auto& c : curves)
        for (size_t i = 0; i + 1 < c.size(); ++i) d = std::min(d, segment_distance(p, c[i], c[i + 1]));
      worst = std::max(worst, d);
    }
  }
  EXPECT_LT(worst, 2e-3);
}

// transport_points against the obvious reference: every triangle tried in order, the first that
// holds the point (to 1e-12) gives its barycentric coordinates.
TEST(Shape, TransportPointsMatchesABruteForceSearch) {
  const VectorImage img = image_with_features();
  const ControlMesh& mesh = img.levels[0];
  ShapeEditor editor(mesh, img.width, img.height);
  const FeaturePick pick = nearest_feature(mesh, validate_level(mesh, img.width, img.height), {80, 64});
  ASSERT_GE(pick.feature, 0);
  const std::vector<Vec2> moved = editor.deform(drag_feature(mesh, mesh.features[pick.feature], {80, 64}, {6, -4}, 20));
  std::vector<Vec2> points;
  for (int i = 0; i <= 40; ++i)
    for (int j = 0; j <= 32; ++j) points.push_back({i * 4.0, j * 4.0});  // the border and corners too
  std::vector<Vec2> fast = points;
  transport_points(mesh.positions, moved, mesh.triangles, fast);
  double worst = 0;
  for (size_t k = 0; k < points.size(); ++k) {
    const Vec2 p = points[k];
    bool found = false;
    for (const Tri& t : mesh.triangles) {
      const Vec2 a = mesh.positions[t[0]], b = mesh.positions[t[1]], c = mesh.positions[t[2]];
      const double d = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
      const double la = ((b.x - p.x) * (c.y - p.y) - (b.y - p.y) * (c.x - p.x)) / d;
      const double lb = ((c.x - p.x) * (a.y - p.y) - (c.y - p.y) * (a.x - p.x)) / d;
      const double lc = 1 - la - lb;
      if (la < -1e-12 || lb < -1e-12 || lc < -1e-12) continue;
      const Vec2 q{la * moved[t[0]].x + lb * moved[t[1]].x + lc * moved[t[2]].x,
                   la * moved[t[0]].y + lb * moved[t[1]].y + lc * moved[t[2]].y};
      worst = std::max(worst, std::hypot(q.x - fast[k].x, q.y - fast[k].y));
      found = true;
      break;
    }
    EXPECT_TRUE(found) << "no triangle holds (" << p.x << ", " << p.y << ")";
  }
  EXPECT_LT(worst, 1e-9);
  // Nothing moved: the identity; a translation of everything: exact.
  std::vector<Vec2> same = points;
  transport_points(mesh.positions, mesh.positions, mesh.triangles, same);
  std::vector<Vec2> shifted_positions = mesh.positions;
  for (Vec2& v : shifted_positions) v = {v.x + 3.5, v.y - 2};
  std::vector<Vec2> shifted = points;
  transport_points(mesh.positions, shifted_positions, mesh.triangles, shifted);
  for (size_t k = 0; k < points.size(); ++k) {
    EXPECT_NEAR(same[k].x, points[k].x, 1e-9);
    EXPECT_NEAR(same[k].y, points[k].y, 1e-9);
    EXPECT_NEAR(shifted[k].x, points[k].x + 3.5, 1e-9);
    EXPECT_NEAR(shifted[k].y, points[k].y - 2, 1e-9);
  }
}

// The editor's "auto" extent: local to what is grabbed.
TEST(Shape, SuggestedDragExtentFollowsTheGrabbedSize) {
  ControlMesh mesh = image_with_features().levels[0];
  for (size_t f = 0; f < mesh.features.size(); ++f) {
    const Feature& feature = mesh.features[f];
    double length = 0, x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
    for (size_t i = 0; i < feature.vertices.size(); ++i) {
      const Vec2 p = mesh.positions[feature.vertices[i]];
      x0 = std::min(x0, p.x), x1 = std::max(x1, p.x), y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
      if (i > 0) {
        const Vec2 q = mesh.positions[feature.vertices[i - 1]];
        length += std::hypot(p.x - q.x, p.y - q.y);
      }
    }
    const double diagonal = std::hypot(x1 - x0, y1 - y0);
    const DragExtent e = suggested_drag_extent(mesh, static_cast<int>(f), -1);
    const double sigma = feature.closed() && diagonal <= 60 ? std::max(2 * diagonal, 8.0)
                                                            : std::clamp(length / 4, 8.0, 60.0);
    EXPECT_DOUBLE_EQ(e.sigma, sigma) << "feature " << f;
    EXPECT_DOUBLE_EQ(e.region, std::max(3 * sigma, 30.0)) << "feature " << f;
  }
  // A vertex: four times its longest edge, at least 30 px.
  const DragExtent v = suggested_drag_extent(mesh, -1, 0);
  EXPECT_GE(v.region, 30);
  EXPECT_THROW(suggested_drag_extent(mesh, static_cast<int>(mesh.features.size()), -1), Error);
  EXPECT_THROW(suggested_drag_extent(mesh, -1, mesh.num_vertices()), Error);
}

// A shape edit carries the level's strokes along (apply_edit_ops); a color edit and another
// level's strokes leave them where they are.
TEST(Shape, StrokesFollowShapeEdits) {
  VectorImage img = image_with_features();
  const ControlMesh before = img.levels[0];
  const Feature& f = before.features[0];
  Stroke along;  // on the feature's control points, as stylize's strokes run along features
  for (int32_t v : f.vertices) along.points.push_back(before.positions[v]);
  Stroke elsewhere = along;
  elsewhere.level = 1;
  Stroke second;  // another stroke on the level, off the feature
  for (int i = 0; i < 5; ++i) second.points.push_back({10.0 + 7 * i, 12.0 + 3 * i});
  img.levels.push_back(before);
  img.strokes = {along, elsewhere, second};
  EditOp op;
  op.kind = EditOp::Kind::kMoveFeature;
  op.at = before.positions[f.vertices[f.vertices.size() / 2]];
  op.translate = {3, 2};
  const std::vector<std::string> log = apply_edit_ops(img, std::span(&op, 1));
  EXPECT_NE(log[0].find("2 strokes carried along"), std::string::npos) << log[0];
  std::vector<Vec2> expected = along.points, expected_second = second.points;
  transport_points(before.positions, img.levels[0].positions, before.triangles, expected);
  transport_points(before.positions, img.levels[0].positions, before.triangles, expected_second);
  EXPECT_EQ(img.strokes[0].points, expected);
  EXPECT_EQ(img.strokes[2].points, expected_second);
  // The feature's own vertices moved by the translation, and so did the stroke over them.
  for (size_t i = 0; i < f.vertices.size(); ++i) {
    EXPECT_NEAR(img.strokes[0].points[i].x, along.points[i].x + 3, 1e-6);
    EXPECT_NEAR(img.strokes[0].points[i].y, along.points[i].y + 2, 1e-6);
  }
  EXPECT_EQ(img.strokes[1].points, elsewhere.points);
  EditOp color;
  color.kind = EditOp::Kind::kColor;
  color.at = {20, 20};
  color.color = {255, 0, 0};
  const std::vector<Vec2> moved = img.strokes[0].points;
  apply_edit_ops(img, std::span(&color, 1));
  EXPECT_EQ(img.strokes[0].points, moved);
}

// The ops file's region fill: "select": "region" is uncapped unless a radius is given, takes a
// "tolerance", and does what select_region_colors selects. A tolerance elsewhere, a drag of a
// region and a negative tolerance are refused, naming the key.
TEST(EditOps, RegionFillsParseAndApply) {
  const std::vector<EditOp> ops = parse_edit_ops(
      R"([{"op":"color","mode":"blend","at":[20,20],"select":"region","tolerance":12,"color":[255,0,0],"amount":1},
          {"op":"color","mode":"blend","at":[20,20],"select":"region","radius":5,"color":[0,0,255]}])");
  ASSERT_EQ(ops.size(), 2u);
  EXPECT_EQ(ops[0].select, EditSelect::kRegion);
  EXPECT_EQ(ops[0].radius, std::numeric_limits<double>::infinity());
  EXPECT_EQ(ops[0].tolerance, 12);
  EXPECT_EQ(ops[1].radius, 5);
  EXPECT_EQ(ops[1].tolerance, kDefaultRegionTolerance);
  VectorImage img = image_with_features();
  const ColorSelection expected = select_region_colors(img.levels[0], {20, 20}, ops[0].radius, 12);
  EXPECT_GT(expected.colors.size(), 1u);
  EXPECT_LT(expected.colors.size(), size_t(img.levels[0].num_colors()));
  apply_edit_ops(img, std::span(ops.data(), 1));
  for (int c = 0; c < img.levels[0].num_colors(); ++c) {
    const bool in = std::binary_search(expected.colors.begin(), expected.colors.end(), c);
    EXPECT_EQ(img.levels[0].colors[c] == (Color{255, 0, 0}), in) << c;
  }
  auto refused = [](const char* json, const char* part) {
    try {
      (void)parse_edit_ops(json);
      ADD_FAILURE() << json;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  refused(R"([{"op":"color","mode":"blend","at":[1,1],"select":"vertex","tolerance":3,"color":[0,0,0]}])",
          "\"tolerance\": applies to \"select\": \"region\" only");
  refused(R"([{"op":"color","mode":"blend","at":[1,1],"select":"region","tolerance":-1,"color":[0,0,0]}])",
          "expected a number >= 0, got -1");
  refused(R"([{"op":"drag","from":[1,1],"to":[2,2],"select":"region"}])",
          "expected \"vertex\" or \"feature\", got \"region\"");
  refused(R"([{"op":"color","mode":"blend","at":[1,1],"select":"blob","color":[0,0,0]}])",
          "expected \"vertex\", \"feature\", \"region\", \"vertices\" or \"all\", got \"blob\"");
}

// Direct handles: "move-vertices" moves the listed control points by exactly the translation
// (interior ones; border ones slide along their side), keeps the rest of the frame, and colors
// per control point take every side's value. Bad lists are refused naming the key.
TEST(EditOps, MoveVerticesAndColorPerControlPoint) {
  VectorImage img = image_with_features();
  const ControlMesh before = img.levels[0];
  std::vector<int32_t> interior;
  for (int v = 0; v < before.num_vertices() && interior.size() < 3; ++v) {
    const Vec2 p = before.positions[v];
    if (p.x > 10 && p.y > 10 && p.x < img.width - 10 && p.y < img.height - 10) interior.push_back(v);
  }
  ASSERT_EQ(interior.size(), 3u);
  const std::string list = "[" + std::to_string(interior[0]) + "," + std::to_string(interior[1]) + "," +
                           std::to_string(interior[2]) + "]";
  const std::vector<EditOp> ops = parse_edit_ops(
      R"([{"op":"move-vertices","vertices":)" + list + R"(,"translate":[1.5,-2],"region":40},
          {"op":"color","mode":"blend","select":"vertices","vertices":)" + list + R"(,"color":[0,255,0],"amount":1}])");
  const std::vector<std::string> log = apply_edit_ops(img, ops);
  EXPECT_NE(log[0].find("3 control points moved by [1.5, -2]"), std::string::npos) << log[0];
  const ControlMesh& after = img.levels[0];
  for (const int32_t v : interior) {
    EXPECT_DOUBLE_EQ(after.positions[v].x, before.positions[v].x + 1.5);
    EXPECT_DOUBLE_EQ(after.positions[v].y, before.positions[v].y - 2);
  }
  const ColorSelection s = select_vertices_colors(after, interior);
  for (int c = 0; c < after.num_colors(); ++c) {
    const bool in = std::binary_search(s.colors.begin(), s.colors.end(), c);
    EXPECT_EQ(after.colors[c] == (Color{0, 255, 0}), in) << c;
    if (!in) {
      EXPECT_EQ(after.colors[c], before.colors[c]);
    }
  }
  EXPECT_GE(s.colors.size(), 3u);
  auto refused = [](const std::string& json, const char* part) {
    try {
      (void)parse_edit_ops(json);
      ADD_FAILURE() << json;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  refused(R"([{"op":"move-vertices","vertices":[],"translate":[1,1]}])", "expected a non-empty array");
  refused(R"([{"op":"move-vertices","vertices":[2,2],"translate":[1,1]}])", "vertex 2 is listed twice");
  refused(R"([{"op":"move-vertices","vertices":[-1],"translate":[1,1]}])", "expected vertex indices");
  refused(R"([{"op":"move-vertices","vertices":[1]}])", "missing key \"translate\"");
  refused(R"([{"op":"color","mode":"blend","select":"vertices","color":[0,0,0]}])", "missing key \"vertices\"");
  const std::vector<EditOp> far = parse_edit_ops(R"([{"op":"move-vertices","vertices":[100000],"translate":[1,1]}])");
  EXPECT_THROW(apply_edit_ops(img, far), Error);
}

TEST(Shape, FeatureDragMeetsItsConstraintsAndIsMoreRigidThanTheFalloffAlone) {
  const VectorImage image = image_with_features();
  const ControlMesh& mesh = image.levels[0];
  const Feature& feature = mesh.features[0];
  const Vec2 click = mesh.positions[feature.vertices[2]];
  const Handles h = drag_feature(mesh, feature, click, {5, -4}, 10);
  ShapeEditor editor(mesh, image.width, image.height);
  const std::vector<Vec2> out = editor.deform(h);
  for (size_t i = 0; i < h.vertices.size(); ++i) {
    EXPECT_EQ(out[h.vertices[i]].x, h.targets[i].x);
    EXPECT_EQ(out[h.vertices[i]].y, h.targets[i].y);
  }
  // The clicked vertex moves by the whole displacement, far ones by almost nothing.
  EXPECT_EQ(out[feature.vertices[2]].x, click.x + 5);
  std::vector<Vec2> falloff = mesh.positions;
  for (size_t i = 0; i < h.vertices.size(); ++i) falloff[h.vertices[i]] = h.targets[i];
  const double arap = rigidity_energy(mesh.positions, out, mesh.triangles);
  const double alone = rigidity_energy(mesh.positions, falloff, mesh.triangles);
  EXPECT_GT(arap, 0);
  EXPECT_LT(arap, 0.5 * alone) << "ARAP " << arap << ", falloff alone " << alone;
}

TEST(Shape, TheImageFrameIsKept) {
  const VectorImage image = image_with_features();
  const ControlMesh& mesh = image.levels[0];
  ShapeEditor editor(mesh, image.width, image.height);
  const int v = nearest_vertex(mesh, {80, 64});
  const std::vector<Vec2> out = editor.deform(drag_vertex(mesh, v, {6, 3}));
  for (int u = 0; u < mesh.num_vertices(); ++u) {
    const Vec2 p = mesh.positions[u], q = out[u];
    if (p.x == 0 || p.x == image.width) {
      EXPECT_EQ(q.x, p.x) << "vertex " << u;
    }
    if (p.y == 0 || p.y == image.height) {
      EXPECT_EQ(q.y, p.y) << "vertex " << u;
    }
  }
  // A handle on the border slides along its side.
  int border = -1;
  for (int u = 0; u < mesh.num_vertices() && border < 0; ++u)
    if (mesh.positions[u].y == 0 && mesh.positions[u].x > 20 && mesh.positions[u].x < 140) border = u;
  ASSERT_GE(border, 0);
  const std::vector<Vec2> slid = editor.deform(drag_vertex(mesh, border, {2, 5}));
  EXPECT_EQ(slid[border].y, 0);
  EXPECT_EQ(slid[border].x, mesh.positions[border].x + 2);
}

TEST(Shape, FeatureCurvesStayBSplinesAndTopologyIsUntouchedAfterEveryEdit) {
  VectorImage image = image_with_features();
  const ControlMesh before = image.levels[0];
  const MeshTopology topology_before = validate_level(before, image.width, image.height);
  expect_feature_curves_are_bsplines(image);

  std::vector<Handles> edits;
  edits.push_back(drag_vertex(before, nearest_vertex(before, {50, 40}), {3, 2}));
  edits.push_back(drag_feature(before, before.features[1], before.positions[before.features[1].vertices[1]], {-3, 4}, 8));
  edits.push_back(move_feature(before, before.features[0], {2, -1}, 6));
  for (const Handles& h : edits) {
    ControlMesh& mesh = image.levels[0];
    ShapeEditor editor(mesh, image.width, image.height);
    mesh.positions = editor.deform(h);
    const MeshTopology topology = validate_level(mesh, image.width, image.height);
    EXPECT_EQ(mesh.triangles, before.triangles);
    EXPECT_EQ(mesh.triangle_colors, before.triangle_colors);
    EXPECT_EQ(mesh.creases, before.creases);
    ASSERT_EQ(mesh.features.size(), before.features.size());
    for (size_t f = 0; f < mesh.features.size(); ++f)
      EXPECT_EQ(mesh.features[f].vertices, before.features[f].vertices);
    EXPECT_EQ(topology.vertex_tags, topology_before.vertex_tags);
    EXPECT_EQ(topology.edge_tags, topology_before.edge_tags);
    expect_feature_curves_are_bsplines(image);
  }
  EXPECT_NE(image.levels[0].positions, before.positions);
}

TEST(Shape, MoveFeatureRotatesAndTranslatesTheWholeFeature) {
  const VectorImage image = image_with_features();
  const ControlMesh& mesh = image.levels[0];
  const Feature& feature = mesh.features[0];
  const Handles h = move_feature(mesh, feature, {3, 1}, 90);
  ASSERT_EQ(h.vertices.size(), feature.vertices.size() - (feature.closed() ? 1 : 0));
  double cx = 0, cy = 0;
  for (int32_t v : h.vertices) cx += mesh.positions[v].x, cy += mesh.positions[v].y;
  cx /= double(h.vertices.size()), cy /= double(h.vertices.size());
  for (size_t i = 0; i < h.vertices.size(); ++i) {
    const Vec2 p = mesh.positions[h.vertices[i]];
    // 90 degrees: (x, y) -> (-y, x) about the centroid, clockwise on screen.
    EXPECT_NEAR(h.targets[i].x, cx - (p.y - cy) + 3, 1e-9);
    EXPECT_NEAR(h.targets[i].y, cy + (p.x - cx) + 1, 1e-9);
  }
  ShapeEditor editor(mesh, image.width, image.height);
  const std::vector<Vec2> out = editor.deform(move_feature(mesh, feature, {3, 1}, 0));
  for (int32_t v : h.vertices) {
    EXPECT_DOUBLE_EQ(out[v].x, mesh.positions[v].x + 3);
    EXPECT_DOUBLE_EQ(out[v].y, mesh.positions[v].y + 1);
  }
}

TEST(Shape, ARegionPinsTheRestOfTheMesh) {
  const VectorImage image = image_with_features();
  const ControlMesh& mesh = image.levels[0];
  ShapeEditor editor(mesh, image.width, image.height);
  const int v = nearest_vertex(mesh, {80, 64});
  Handles h = drag_vertex(mesh, v, {3, 2});
  h.region = 25;
  const std::vector<Vec2> out = editor.deform(h);
  int moved = 0;
  for (int u = 0; u < mesh.num_vertices(); ++u) {
    const Vec2 p = mesh.positions[u];
    const double d = std::hypot(p.x - mesh.positions[v].x, p.y - mesh.positions[v].y);
    if (d > 25) {
      EXPECT_EQ(out[u], p) << "vertex " << u;
    } else {
      moved += out[u] != p;
    }
  }
  EXPECT_GT(moved, 5);
}

double smallest_area(const std::vector<Vec2>& p, const std::vector<Tri>& triangles) {
  double least = std::numeric_limits<double>::infinity();
  for (const Tri& t : triangles) {
    const Vec2 a = p[t[0]], b = p[t[1]], c = p[t[2]];
    least = std::min(least, (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
  }
  return least;
}

bool segments_cross(Vec2 a, Vec2 b, Vec2 c, Vec2 d) {
  const auto side = [](Vec2 p, Vec2 q, Vec2 r) { return (q.x - p.x) * (r.y - p.y) - (q.y - p.y) * (r.x - p.x); };
  return side(a, b, c) * side(a, b, d) < 0 && side(c, d, a) * side(c, d, b) < 0;
}

// Does feature f's chain with its handles at their targets cross itself, or another feature's
// chain as it is in `out`?
bool chain_crosses(const ControlMesh& mesh, size_t f, const Handles& h, const std::vector<Vec2>& out) {
  std::vector<Vec2> at = out;
  for (size_t i = 0; i < h.vertices.size(); ++i) at[h.vertices[i]] = h.targets[i];
  const std::vector<int32_t>& chain = mesh.features[f].vertices;
  for (size_t i = 0; i + 1 < chain.size(); ++i) {
    for (size_t g = 0; g < mesh.features.size(); ++g) {
      const std::vector<int32_t>& other = mesh.features[g].vertices;
      for (size_t j = 0; j + 1 < other.size(); ++j) {
        if (g == f && (j + 1 >= i && j <= i + 1)) continue;  // the same or a neighbouring segment
        if (segments_cross(at[chain[i]], at[chain[i + 1]], at[other[j]], at[other[j + 1]])) return true;
      }
    }
  }
  return false;
}

// Issue 25: no drag folds the mesh. Drags that fit in the frame arrive: the handles meet their
// targets exactly, and no control triangle is flipped or degenerate.
TEST(Shape, EveryResultIsFoldFreeAndDragsInsideTheFrameArrive) {
  const VectorImage image = image_with_features();
  const ControlMesh& mesh = image.levels[0];
  ShapeEditor editor(mesh, image.width, image.height);
  int fold_free = 0, repaired = 0, stopped = 0;
  for (const double size : {2.0, 8.0, 20.0, 40.0, 70.0}) {
    for (size_t f = 0; f < mesh.features.size(); ++f) {
      const Feature& feature = mesh.features[f];
      const Vec2 click = mesh.positions[feature.vertices[feature.vertices.size() / 2]];
      const Handles h = drag_feature(mesh, feature, click, {size, -0.5 * size}, 12);
      const std::vector<Vec2> out = editor.deform(h);
      ASSERT_GT(smallest_area(out, mesh.triangles), 0) << "size " << size << ", feature " << f;
      if (editor.reached() < 1) {
        // Only the frame or a crossing stops a drag: the dragged chain, at its targets, crosses
        // itself or another feature where it ended.
        EXPECT_TRUE(editor.framed() || chain_crosses(mesh, f, h, out))
            << "size " << size << ", feature " << f << " stopped at " << editor.reached();
        EXPECT_GT(size, 8);
        ++stopped;
        continue;
      }
      for (size_t i = 0; i < h.vertices.size(); ++i) {
        const Vec2 p = mesh.positions[h.vertices[i]], t = h.targets[i];
        if (p.x != 0 && p.x != image.width && p.y != 0 && p.y != image.height && t.x > 0.25 &&
            t.x < image.width - 0.25 && t.y > 0.25 && t.y < image.height - 0.25) {
          EXPECT_EQ(out[h.vertices[i]], t);
        }
      }
      repaired += editor.scale_fraction() < 1;
      fold_free += editor.scale_fraction() == 1 && smallest_area(out, mesh.triangles) > 0;
    }
  }
  // The large drags: before issue 25 these were refused ("the edit would flip ...").
  EXPECT_GT(fold_free, 0);
  RecordProperty("repaired", repaired);
  RecordProperty("stopped", stopped);
}

// A drag whose plain ARAP solve would flip triangles (the similarity step itself flips) arrives by
// the fold-free path: the handles meet their targets, nothing folds, and the result stays far
// more rigid than the falloff alone.
TEST(Shape, ADragThatWouldFlipArrivesWithoutFolding) {
  const VectorImage image = image_with_features();
  const ControlMesh& mesh = image.levels[0];
  ShapeEditor editor(mesh, image.width, image.height);
  int checked = 0;
  for (size_t f = 0; f < mesh.features.size() && checked < 3; ++f) {
    const Feature& feature = mesh.features[f];
    const Vec2 click = mesh.positions[feature.vertices[feature.vertices.size() / 2]];
    for (const double size : {20.0, 30.0, 40.0}) {
      const Handles h = drag_feature(mesh, feature, click, {size * 0.6, size * 0.8}, 12);
      bool inside = true;
      for (const Vec2 t : h.targets) inside &= t.x > 1 && t.x < image.width - 1 && t.y > 1 && t.y < image.height - 1;
      if (!inside) continue;
      // Would the plain solve flip? (ArapDeformer's similarity step, as ShapeEditor sets it up.)
      std::vector<FixedAxes> fixed(mesh.positions.size(), FixedAxes::kNone);
      std::vector<Vec2> targets = mesh.positions;
      for (size_t v = 0; v < mesh.positions.size(); ++v) {
        const Vec2 p = mesh.positions[v];
        fixed[v] = static_cast<FixedAxes>((p.x == 0 || p.x == image.width ? 1 : 0) |
                                          (p.y == 0 || p.y == image.height ? 2 : 0));
      }
      for (size_t i = 0; i < h.vertices.size(); ++i) fixed[h.vertices[i]] = FixedAxes::kXY, targets[h.vertices[i]] = h.targets[i];
      const ArapDeformer plain(mesh.positions, mesh.triangles, fixed);
      std::vector<Vec2> similarity(mesh.positions.size());
      plain.solve_similarity(targets, similarity);
      if (smallest_area(similarity, mesh.triangles) > 0) continue;
      const std::vector<Vec2> out = editor.deform(h);
      EXPECT_EQ(editor.reached(), 1) << "feature " << f << ", size " << size;
      EXPECT_GT(smallest_area(out, mesh.triangles), 0);
      for (size_t i = 0; i < h.vertices.size(); ++i) EXPECT_EQ(out[h.vertices[i]], h.targets[i]);
      std::vector<Vec2> falloff = mesh.positions;
      for (size_t i = 0; i < h.vertices.size(); ++i) falloff[h.vertices[i]] = h.targets[i];
      EXPECT_LT(rigidity_energy(mesh.positions, out, mesh.triangles),
                0.5 * rigidity_energy(mesh.positions, falloff, mesh.triangles));
      // The same edit gives the same bits.
      EXPECT_EQ(editor.deform(h), out);
      ++checked;
      break;
    }
  }
  EXPECT_GT(checked, 0) << "no drag of this image flips the plain solve: the test lost its subject";
}

// Issue 25's acceptance on real photographs (ratio 0.02): seeded random feature drags of 5-40 px
// (sigma 25, the editor's region of 3 sigma) never fold the mesh, stop short only where the image
// frame or a crossing holds them (at most 5 % of them, for either), and leave the pixels farther than
// 3 sigma from the drag within MAE 1.0. scripts/measure-drags runs all eight photographs, 50 drags
// each (docs/editing.md).
TEST(Shape, RandomFeatureDragsOnPhotographsNeverFold) {
  const std::filesystem::path dir = std::filesystem::path(SUBVEC_SOURCE_DIR) / ".." / "shared" / "images";
  if (const auto why = test::skip_shared_photos(dir)) GTEST_SKIP() << *why;
  std::mt19937_64 random(25);
  int drags = 0, crossings = 0, framed = 0;
  for (const char* name : {"butterfly", "rocket"}) {
    const Image8 photo = read_image(dir / (std::string(name) + ".png"));
    VectorizeOptions options;
    options.ratio = 0.02;
    options.levels.levels = 1;
    const VectorImage image = vectorize(photo, options);
    const ControlMesh& mesh = image.levels[0];
    ASSERT_FALSE(mesh.features.empty());
    const Image8 before = render(image, RenderOptions{});
    for (int k = 0; k < 25; ++k, ++drags) {
      const Feature& feature = mesh.features[random() % mesh.features.size()];
      const Vec2 from = mesh.positions[feature.vertices[random() % feature.vertices.size()]];
      const double length = 5 + 35 * std::uniform_real_distribution<double>()(random);
      const double angle = 2 * M_PI * std::uniform_real_distribution<double>()(random);
      EditOp op;
      op.kind = EditOp::Kind::kDrag;
      op.select = EditSelect::kFeature;
      op.from = from;
      op.to = {std::clamp(from.x + length * std::cos(angle), 0.0, double(image.width)),
               std::clamp(from.y + length * std::sin(angle), 0.0, double(image.height))};
      op.sigma = 25;
      op.region = 75;
      VectorImage edited = image;
      const std::vector<std::string> log = apply_edit_ops(edited, std::span(&op, 1));
      ASSERT_EQ(log.size(), 1u);
      EXPECT_GT(smallest_area(edited.levels[0].positions, mesh.triangles), 0) << name << " drag " << k;
      if (log[0].find("; stopped at ") != std::string::npos) {
        (log[0].find("the image frame stops it") != std::string::npos ? framed : crossings) += 1;
      }
      const Image8 after = render(edited, RenderOptions{});
      double sum = 0;
      int64_t count = 0;
      for (int y = 0; y < before.height; ++y) {
        for (int x = 0; x < before.width; ++x) {
          if (std::hypot(x + 0.5 - from.x, y + 0.5 - from.y) <= 3 * op.sigma) continue;
          for (int c = 0; c < 3; ++c) {
            const size_t i = (size_t(y) * before.width + x) * before.channels + c;
            sum += std::abs(int(after.pixels[i]) - int(before.pixels[i]));
          }
          count += 3;
        }
      }
      EXPECT_LE(sum / double(count), 1.0) << name << " drag " << k << ": " << log[0];
    }
  }
  RecordProperty("stopped_by_the_frame", framed);
  RecordProperty("stopped_by_a_crossing", crossings);
  EXPECT_LE(crossings + framed, drags / 20) << crossings << " stopped by a crossing and " << framed
                                            << " by the frame, of " << drags << " drags";
}

// The frame stops a drag: a vertex dragged far past the right border ends a margin inside it,
// the edit says so, and nothing folds. Bad handles are still errors.
TEST(Shape, ADragPastTheFrameStopsAtIt) {
  const VectorImage image = image_with_features();
  const ControlMesh& mesh = image.levels[0];
  ShapeEditor editor(mesh, image.width, image.height);
  const int v = nearest_vertex(mesh, {80, 64});
  Handles h = drag_vertex(mesh, v, {300, 0});
  const std::vector<Vec2> out = editor.deform(h);
  EXPECT_TRUE(editor.framed());
  EXPECT_GT(smallest_area(out, mesh.triangles), 0);
  EXPECT_LE(out[v].x, image.width - 0.25);
  EXPECT_GT(out[v].x, mesh.positions[v].x + 40);
  h.vertices.push_back(v);
  h.targets.push_back({1, 1});
  EXPECT_THROW(editor.deform(h), Error);
}


}  // namespace
}  // namespace subvec
