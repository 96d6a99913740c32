// New and deleted features (edit/feature_edit.h, issue 25): the drawn curve's C^2 fit, a tear cut
// along it that is exactly that curve and changes nothing else, a color edit that stops at it, and
// a deleted feature whose color crosses where it was without a step.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include "subvec/core/error.h"
#include "subvec/edit/feature_edit.h"
#include "subvec/edit/ops.h"
#include "subvec/edit/selection.h"
#include "subvec/io/image_io.h"
#include "subvec/io/svec.h"
#include "subvec/mesh/curves.h"
#include "subvec/mesh/topology.h"
#include "subvec/mesh/validate.h"
#include "subvec/render/renderer.h"
#include "subvec/subdiv/subdivision.h"
#include "subvec/vectorize/vectorize.h"
#include "support/shared_photos.h"
#include "support/synthetic.h"

namespace subvec {
namespace {

double distance_to_polyline(Vec2 p, const std::vector<Vec2>& line) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i + 1 < line.size(); ++i) {
    const Vec2 a = line[i], b = line[i + 1];
    const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
    const double t = len2 > 0 ? std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / len2, 0.0, 1.0) : 0;
    best = std::min(best, std::hypot(p.x - a.x - t * dx, p.y - a.y - t * dy));
  }
  return best;
}

std::vector<Vec2> wave(Vec2 from, Vec2 to, double amplitude, int count) {
  std::vector<Vec2> out;
  const double dx = to.x - from.x, dy = to.y - from.y, len = std::hypot(dx, dy);
  for (int i = 0; i < count; ++i) {
    const double t = double(i) / (count - 1), s = amplitude * std::sin(2 * M_PI * t);
    out.push_back({from.x + t * dx - s * dy / len, from.y + t * dy + s * dx / len});
  }
  return out;
}

std::vector<Vec2> circle(Vec2 c, double r, int count) {
  std::vector<Vec2> out;
  for (int i = 0; i <= count; ++i)
    out.push_back({c.x + r * std::cos(2 * M_PI * i / count), c.y + r * std::sin(2 * M_PI * i / count)});
  return out;
}

// Mean absolute difference over the pixels `keep` says, 0-255.
template <class Keep>
double mae_where(const Image8& a, const Image8& b, Keep keep) {
  double sum = 0;
  int64_t count = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      if (!keep(x, y)) continue;
      for (int c = 0; c < 3; ++c) {
        const size_t i = (size_t(y) * a.width + x) * a.channels + c;
        sum += std::abs(int(a.pixels[i]) - int(b.pixels[i]));
      }
      count += 3;
    }
  return count ? sum / double(count) : 0;
}

int channel_jump(const Image8& im, int x0, int y0, int x1, int y1) {
  int worst = 0;
  for (int c = 0; c < 3; ++c) {
    const int a = im.pixels[(size_t(y0) * im.width + x0) * im.channels + c];
    const int b = im.pixels[(size_t(y1) * im.width + x1) * im.channels + c];
    worst = std::max(worst, std::abs(a - b));
  }
  return worst;
}

// The largest jump between 4-adjacent pixels whose centres lie on either side of `curve`, near it,
// leaving out the pairs within 1.5 px of a curve in `others` (a tear that stays).
int largest_jump_across(const Image8& im, const std::vector<Vec2>& curve,
                        const std::vector<std::vector<Vec2>>& others) {
  int worst = 0;
  for (size_t i = 0; i + 1 < curve.size(); ++i) {
    const Vec2 a = curve[i], b = curve[i + 1];
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    if (len == 0) continue;
    const Vec2 n{-(b.y - a.y) / len, (b.x - a.x) / len};
    const Vec2 m{(a.x + b.x) / 2, (a.y + b.y) / 2};
    const int x = int(std::floor(m.x)), y = int(std::floor(m.y));
    for (const auto& [dx, dy] : {std::pair{1, 0}, std::pair{0, 1}, std::pair{-1, 0}, std::pair{0, -1}}) {
      const int x1 = x + dx, y1 = y + dy;
      if (x < 0 || y < 0 || x1 < 0 || y1 < 0 || x >= im.width || x1 >= im.width || y >= im.height || y1 >= im.height) continue;
      const double s0 = (x + 0.5 - m.x) * n.x + (y + 0.5 - m.y) * n.y;
      const double s1 = (x1 + 0.5 - m.x) * n.x + (y1 + 0.5 - m.y) * n.y;
      if (s0 * s1 >= 0) continue;
      const bool by_another = std::any_of(others.begin(), others.end(), [&](const std::vector<Vec2>& o) {
        return distance_to_polyline({x + 0.5, y + 0.5}, o) < 3 || distance_to_polyline({x1 + 0.5, y1 + 0.5}, o) < 3;
      });
      if (!by_another) {
        worst = std::max(worst, channel_jump(im, x, y, x1, y1));
      }
    }
  }
  return worst;
}

// The limit curves of a feature (its pieces between corners), sampled.
std::vector<std::vector<Vec2>> feature_curves(const ControlMesh& mesh, const MeshTopology& topology, const Feature& f) {
  std::vector<std::vector<Vec2>> out;
  for (const CurvePiece& piece : feature_pieces(topology, f))
    out.push_back(sample_bspline(piece_points(mesh, piece), piece.closed, 16));
  return out;
}

// The refined tear edges' vertices of the level, as points.
std::vector<Vec2> refined_tear_points(const ControlMesh& mesh, int width, int height) {
  const MeshTopology topology = validate_level(mesh, width, height);
  const Subdivision sub(mesh, topology, 4);
  RefinedMesh refined;
  sub.evaluate(mesh.positions, mesh.colors, refined, 1);
  std::vector<Vec2> out;
  for (const EdgeVerts& e : refined.tear_edges)
    for (const int v : e) out.push_back({refined.positions[2 * size_t(v)], refined.positions[2 * size_t(v) + 1]});
  return out;
}

// 160 x 128, about 900 vertices; with the synthetic features (two circles, an arc, a segment) or
// without.
VectorImage small_image(bool features) {
  test::SyntheticOptions o;
  o.width = 160;
  o.height = 128;
  o.vertices = 900;
  o.features = features;
  return test::make_synthetic_image(o);
}
VectorImage smooth_image() { return small_image(false); }

// A piece too short for more control points ends its fit with the deviation it has (a bent piece
// 2.9 px long between two junctions once looped forever: one point more was over the cap of
// one every kMinSpacing).
TEST(FeatureEdit, AShortBentPieceEndsItsFit) {
  const std::vector<Vec2> bent = {{0, 0}, {1.2, 0.8}, {2.4, 0}};
  const CurveFit fit = fit_curve(bent, 3.0, 0.5, false);
  EXPECT_EQ(fit.points.size(), 2u);
  EXPECT_GT(fit.deviation, 0.5);
  EXPECT_LT(fit.deviation, 0.9);
}

TEST(FeatureEdit, TheFitFollowsTheDrawnCurve) {
  const std::vector<Vec2> drawn = wave({10, 60}, {150, 70}, 12, 200);
  const CurveFit fit = fit_curve(drawn, 8);
  EXPECT_FALSE(fit.closed);
  EXPECT_LE(fit.deviation, 0.5);
  EXPECT_EQ(fit.points.front().x, drawn.front().x);
  EXPECT_EQ(fit.points.back().y, drawn.back().y);
  // The reported deviation is the distance from the polyline to the curve.
  const std::vector<Vec2> curve = sample_bspline(fit.points, false, 64);
  double worst = 0;
  for (const Vec2& p : drawn) worst = std::max(worst, distance_to_polyline(p, curve));
  EXPECT_NEAR(worst, fit.deviation, 0.05);
  // A closed drawing: a periodic spline through none of its points twice.
  const CurveFit ring = fit_curve(circle({80, 64}, 30, 90), 8);
  EXPECT_TRUE(ring.closed);
  EXPECT_LE(ring.deviation, 0.5);
  const std::vector<Vec2> round = sample_bspline(ring.points, true, 32);
  for (const Vec2& p : round) EXPECT_NEAR(std::hypot(p.x - 80, p.y - 64), 30, 0.5);
  // Bad drawings.
  const std::vector<Vec2> dot{{5, 5}, {5, 5}};
  EXPECT_THROW(fit_curve(dot, 8), Error);
  const std::vector<Vec2> tiny{{5, 5}, {5.5, 5}};
  EXPECT_THROW(fit_curve(tiny, 8), Error);
  const std::vector<Vec2> nan{{5, 5}, {std::nan(""), 5}};
  EXPECT_THROW(fit_curve(nan, 8), Error);
}

// A tear drawn over a smooth region: its chain is the fit's control polygon, its rendered curve is
// the fit, the image changes only along it, and a color edit on one side stops at it.
TEST(FeatureEdit, AnAddedTearIsTheFitAndChangesNothingElse) {
  VectorImage image = smooth_image();
  const ControlMesh before = image.levels[0];
  const Image8 rendered = render(image, RenderOptions{});
  const std::vector<Vec2> drawn = wave({20, 40}, {140, 90}, 10, 120);
  EditOp op;
  op.kind = EditOp::Kind::kAddFeature;
  op.points = drawn;
  const std::vector<std::string> log = apply_edit_ops(image, std::span(&op, 1));
  ASSERT_EQ(log.size(), 1u);
  EXPECT_NE(log[0].find("tear feature 0 (id 0) added"), std::string::npos) << log[0];
  const ControlMesh& mesh = image.levels[0];
  ASSERT_EQ(mesh.features.size(), 1u);
  const CurveFit fit = fit_curve(drawn, 1.0);  // only for its closedness
  EXPECT_FALSE(fit.closed);
  std::vector<Vec2> chain;
  for (const int v : mesh.features[0].vertices) chain.push_back(mesh.positions[v]);
  const std::vector<Vec2> curve = sample_bspline(chain, false, 64);
  // The fit is near the drawing, and the rendered tear is the fit.
  for (const Vec2& p : drawn) EXPECT_LE(distance_to_polyline(p, curve), 0.5);
  const std::vector<Vec2> tear = refined_tear_points(mesh, image.width, image.height);
  ASSERT_FALSE(tear.empty());
  double worst = 0;
  for (const Vec2& p : tear) worst = std::max(worst, distance_to_polyline(p, curve));
  EXPECT_LE(worst, 0.01);
  // Away from it (3 px), the picture is what it was.
  const Image8 after = render(image, RenderOptions{});
  const double away = mae_where(rendered, after, [&](int x, int y) {
    return distance_to_polyline({x + 0.5, y + 0.5}, curve) > 3;
  });
  EXPECT_LE(away, 0.5);
  const double all = mae_where(rendered, after, [](int, int) { return true; });
  EXPECT_LE(all, 0.5);
  RecordProperty("mae_away", std::to_string(away));
  // Vertices far from it kept their colors and positions exactly.
  for (int v = 0; v < before.num_vertices(); ++v) EXPECT_EQ(mesh.positions[v], before.positions[v]);

  // Paint one side red around the middle of the curve: the other side does not change.
  const Vec2 mid = curve[curve.size() / 2], next = curve[curve.size() / 2 + 1];
  const double len = std::hypot(next.x - mid.x, next.y - mid.y);
  const Vec2 n{-(next.y - mid.y) / len, (next.x - mid.x) / len};
  EditOp paint;
  paint.kind = EditOp::Kind::kColor;
  paint.select = EditSelect::kVertex;
  paint.at = {mid.x + 3 * n.x, mid.y + 3 * n.y};
  paint.radius = 15;
  paint.color = {255, 0, 0};
  paint.amount = 1;
  VectorImage painted = image;
  apply_edit_ops(painted, std::span(&paint, 1));
  const Image8 red = render(painted, RenderOptions{});
  const Vec2 here{mid.x + 4 * n.x, mid.y + 4 * n.y};
  auto pixel = [](const Image8& im, Vec2 p, int c) {
    return int(im.pixels[(size_t(p.y) * im.width + size_t(p.x)) * im.channels + c]);
  };
  EXPECT_GT(std::abs(pixel(red, here, 1) - pixel(after, here, 1)), 30);  // painted
  const double other = mae_where(after, red, [&](int x, int y) {
    const double side = (x + 0.5 - mid.x) * n.x + (y + 0.5 - mid.y) * n.y;
    return side < -1.5 && std::hypot(x + 0.5 - mid.x, y + 0.5 - mid.y) < 12;
  });
  EXPECT_LE(other, 0.5) << "the paint crossed the new tear";

  // The same edit twice gives the same bits.
  VectorImage again = smooth_image();
  apply_edit_ops(again, std::span(&op, 1));
  EXPECT_EQ(again.levels[0].positions, mesh.positions);
  EXPECT_EQ(again.levels[0].colors, mesh.colors);
  EXPECT_EQ(again.levels[0].triangles, mesh.triangles);
}

TEST(FeatureEdit, ACreaseAndAClosedTear) {
  VectorImage image = smooth_image();
  const Image8 rendered = render(image, RenderOptions{});
  EditOp crease;
  crease.kind = EditOp::Kind::kAddFeature;
  crease.points = wave({10, 100}, {150, 110}, 5, 60);
  crease.feature_kind = FeatureKind::kCrease;
  EditOp ring;
  ring.kind = EditOp::Kind::kAddFeature;
  ring.points = circle({70, 50}, 25, 80);
  const std::vector<EditOp> ops{crease, ring};
  const std::vector<std::string> log = apply_edit_ops(image, ops);
  EXPECT_NE(log[0].find("crease added"), std::string::npos) << log[0];
  EXPECT_NE(log[1].find("closed tear feature 0"), std::string::npos) << log[1];
  const ControlMesh& mesh = image.levels[0];
  EXPECT_FALSE(mesh.creases.empty());
  ASSERT_EQ(mesh.features.size(), 1u);
  EXPECT_TRUE(mesh.features[0].closed());
  validate(image);
  const Image8 after = render(image, RenderOptions{});
  EXPECT_LE(mae_where(rendered, after, [](int, int) { return true; }), 0.5);
}

// A crease is picked, dragged, moved and deleted like a tear: as a chain of crease_chains().
TEST(FeatureEdit, ACreaseIsEditedLikeATear) {
  VectorImage image = smooth_image();
  EditOp add;
  add.kind = EditOp::Kind::kAddFeature;
  add.points = wave({20, 70}, {140, 60}, 8, 80);
  add.feature_kind = FeatureKind::kCrease;
  apply_edit_ops(image, std::span(&add, 1));
  const ControlMesh added = image.levels[0];
  const MeshTopology topology = validate_level(added, image.width, image.height);
  const std::vector<Feature> chains = crease_chains(added, topology);
  ASSERT_EQ(chains.size(), 1u);
  EXPECT_EQ(chains[0].id, -1);
  EXPECT_EQ(chains[0].vertices.size(), added.creases.size() + 1);
  // The chain runs along the creases in order, end to end.
  for (size_t i = 0; i + 1 < chains[0].vertices.size(); ++i) {
    const int a = chains[0].vertices[i], b = chains[0].vertices[i + 1];
    EXPECT_TRUE(std::any_of(added.creases.begin(), added.creases.end(), [&](const EdgeVerts& e) {
      return (e[0] == a && e[1] == b) || (e[0] == b && e[1] == a);
    })) << i;
  }
  // Drag it by its middle: its vertices there follow, and the creases stay.
  const Vec2 grab = added.positions[chains[0].vertices[chains[0].vertices.size() / 2]];
  EditOp drag;
  drag.kind = EditOp::Kind::kDrag;
  drag.select = EditSelect::kFeature;
  drag.from = grab;
  drag.to = {grab.x, grab.y + 6};
  drag.sigma = 20;
  drag.region = 60;
  const std::vector<std::string> log = apply_edit_ops(image, std::span(&drag, 1));
  EXPECT_NE(log[0].find("crease 0"), std::string::npos) << log[0];
  const int middle = chains[0].vertices[chains[0].vertices.size() / 2];
  EXPECT_NEAR(image.levels[0].positions[middle].y, grab.y + 6, 1e-9);
  EXPECT_EQ(image.levels[0].creases, added.creases);
  // Delete it: no crease left.
  EditOp del;
  del.kind = EditOp::Kind::kDeleteFeature;
  del.at = {grab.x, grab.y + 6};
  const std::vector<std::string> gone = apply_edit_ops(image, std::span(&del, 1));
  EXPECT_NE(gone[0].find("crease 0"), std::string::npos) << gone[0];
  EXPECT_TRUE(image.levels[0].creases.empty());
  validate(image);
  Feature bogus;
  bogus.vertices = {0, 1};
  EXPECT_THROW(delete_crease(image.levels[0], image.width, image.height, bogus), Error);
}

TEST(FeatureEdit, BadCurvesAreRefusedByName) {
  VectorImage image = small_image(true);
  const VectorImage original = image;
  EditOp op;
  op.kind = EditOp::Kind::kAddFeature;
  op.points = {{20, 20}, {60, 60}, {60, 20}, {20, 60}};
  try {
    apply_edit_ops(image, std::span(&op, 1));
    FAIL() << "a self-crossing curve was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("crosses itself"), std::string::npos) << e.what();
  }
  op.points = {{20, 20}, {200, 20}};
  EXPECT_THROW(apply_edit_ops(image, std::span(&op, 1)), Error);
  EXPECT_EQ(image.levels[0].triangles, original.levels[0].triangles);
  EXPECT_THROW(delete_feature(image.levels[0], 160, 128, 99), Error);
}

// A curve across features meets them at junctions: it is split into pieces that end on corner
// vertices inserted on the features it crosses, whose chains now pass through them; an end drawn
// near a feature joins it.
TEST(FeatureEdit, ACurveAcrossFeaturesJoinsThem) {
  VectorImage image = small_image(true);
  const Image8 rendered = render(image, RenderOptions{});
  const size_t before = image.levels[0].features.size();
  EditOp op;
  op.kind = EditOp::Kind::kAddFeature;
  op.points = wave({3, 63.3}, {157, 60}, 4, 150);
  const std::vector<std::string> log = apply_edit_ops(image, std::span(&op, 1));
  EXPECT_NE(log[0].find("junctions with existing features"), std::string::npos) << log[0];
  validate(image);
  const ControlMesh& mesh = image.levels[0];
  ASSERT_GT(mesh.features.size(), before + 1);
  const MeshTopology topology = validate_level(mesh, image.width, image.height);
  // Every new piece ends on an old feature (a junction) or at the drawing's own ends.
  int junctions = 0;
  for (size_t f = before; f < mesh.features.size(); ++f) {
    for (const int v : {mesh.features[f].vertices.front(), mesh.features[f].vertices.back()}) {
      int on_old = 0;
      for (size_t g = 0; g < before; ++g) {
        const auto& c = mesh.features[g].vertices;
        on_old += std::find(c.begin(), c.end(), v) != c.end();
      }
      if (on_old > 0) {
        ++junctions;
        EXPECT_EQ(topology.vertex_tags[v], VertexTag::kCorner);
      }
    }
  }
  EXPECT_GE(junctions, 2);
  // The picture away from the new curve (and the old curves' small shifts at the junctions) holds.
  const Image8 after = render(image, RenderOptions{});
  EXPECT_LE(mae_where(rendered, after, [&](int, int y) { return std::abs(y + 0.5 - 62) > 8; }), 0.5);
  // An end drawn 1.5 px short of a feature joins it.
  VectorImage disk = small_image(true);
  const ControlMesh& m = disk.levels[0];
  const Vec2 a = m.positions[m.features[0].vertices[0]], b = m.positions[m.features[0].vertices[1]];
  const Vec2 mid{(a.x + b.x) / 2, (a.y + b.y) / 2};
  const double len = std::hypot(b.x - a.x, b.y - a.y);
  const Vec2 n{-(b.y - a.y) / len, (b.x - a.x) / len};
  EditOp reach;
  reach.kind = EditOp::Kind::kAddFeature;
  for (int i = 0; i <= 20; ++i) reach.points.push_back({mid.x + (1.5 + i) * n.x, mid.y + (1.5 + i) * n.y});
  std::reverse(reach.points.begin(), reach.points.end());
  const std::vector<std::string> joined = apply_edit_ops(disk, std::span(&reach, 1));
  EXPECT_NE(joined[0].find("1 junction with existing features"), std::string::npos) << joined[0];
  validate(disk);
}

// Ends within a pixel of the border go onto it: a cut from side to side.
TEST(FeatureEdit, ATearFromBorderToBorder) {
  VectorImage image = smooth_image();
  EditOp op;
  op.kind = EditOp::Kind::kAddFeature;
  op.points = wave({0.5, 20}, {159.6, 110}, 8, 80);
  apply_edit_ops(image, std::span(&op, 1));
  const ControlMesh& mesh = image.levels[0];
  ASSERT_EQ(mesh.features.size(), 1u);
  EXPECT_EQ(mesh.positions[mesh.features[0].vertices.front()].x, 0.0);
  EXPECT_EQ(mesh.positions[mesh.features[0].vertices.back()].x, 160.0);
  validate(image);
}

struct DeleteMeasure {
  int jump = 0;        // largest 4-neighbour jump across where the feature was
  double far = 0;      // MAE of the pixels more than 3 control rings from it
  int vertices_before = 0, vertices_after = 0;
};

DeleteMeasure measure_delete(VectorImage& image, int feature) {
  const ControlMesh before = image.levels[0];
  const MeshTopology topology = validate_level(before, image.width, image.height);
  const Image8 rendered = render(image, RenderOptions{});
  const std::vector<std::vector<Vec2>> curves = feature_curves(before, topology, before.features[feature]);
  // Triangles within 3 rings of the feature: a vertex of theirs is within 3 edges of it.
  std::vector<uint8_t> near(before.num_vertices(), 0);
  for (const int v : before.features[feature].vertices) near[v] = 1;
  for (int r = 0; r < 3; ++r) {
    std::vector<uint8_t> next = near;
    for (const EdgeVerts& e : topology.edges)
      if (near[e[0]] || near[e[1]]) next[e[0]] = next[e[1]] = 1;
    near = next;
  }
  std::vector<uint8_t> near_pixel(size_t(image.width) * image.height, 0);
  for (const Tri& t : before.triangles) {
    if (!near[t[0]] && !near[t[1]] && !near[t[2]]) continue;
    double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
    for (const int v : t) {
      x0 = std::min(x0, before.positions[v].x), x1 = std::max(x1, before.positions[v].x);
      y0 = std::min(y0, before.positions[v].y), y1 = std::max(y1, before.positions[v].y);
    }
    for (int y = std::max(0, int(y0) - 1); y <= std::min(image.height - 1, int(y1) + 1); ++y)
      for (int x = std::max(0, int(x0) - 1); x <= std::min(image.width - 1, int(x1) + 1); ++x)
        near_pixel[size_t(y) * image.width + x] = 1;
  }
  ControlMesh& mesh = image.levels[0];
  const FeatureEditResult r = delete_feature(mesh, image.width, image.height, feature);
  EXPECT_GT(r.colors_refit, 0);
  validate(image);
  const Image8 after = render(image, RenderOptions{});
  DeleteMeasure m;
  std::vector<std::vector<Vec2>> others;
  const MeshTopology now = validate_level(mesh, image.width, image.height);
  for (const Feature& f : mesh.features)
    for (auto& c : feature_curves(mesh, now, f)) others.push_back(std::move(c));
  for (const auto& c : curves) m.jump = std::max(m.jump, largest_jump_across(after, c, others));
  m.far = mae_where(rendered, after, [&](int x, int y) { return !near_pixel[size_t(y) * image.width + x]; });
  m.vertices_before = before.num_vertices();
  m.vertices_after = mesh.num_vertices();
  return m;
}

TEST(FeatureEdit, ADeletedFeatureLeavesNoStep) {
  for (int f = 0; f < 4; ++f) {
    VectorImage image = small_image(true);
    ASSERT_EQ(image.levels[0].features.size(), 4u);
    const int32_t id = image.levels[0].features[f].id;
    const DeleteMeasure m = measure_delete(image, f);
    // The bounds, on jumps of up to 150 levels: no step over 4 levels across where the
    // feature was, and the pixels past 3 control rings within MAE 0.5. (With unit membrane
    // weights instead of the cotangents the ramp bunched near the curve: a closed one reached 5.)
    EXPECT_LE(m.jump, 4) << "feature " << f;
    EXPECT_LE(m.far, 0.5) << "feature " << f;
    EXPECT_EQ(m.vertices_after, m.vertices_before);
    for (const Feature& g : image.levels[0].features) EXPECT_NE(g.id, id);
  }
}

TEST(FeatureEdit, DeletingTheOutlineOfASmallImageKeepsWhatItBounded) {
  // examples/01-disk: a red ball on grey, 96 x 96, its outline a jump of about 200 levels. The
  // band that ramps such a jump at 1.5 levels a pixel is wider than the image; capped, the ball
  // stays, its edge a soft ramp.
  VectorImage image = read_svec(std::filesystem::path(SUBVEC_SOURCE_DIR) / "examples" / "01-disk.svec.json");
  const Image8 before = render(image, RenderOptions{});
  delete_feature(image.levels[0], image.width, image.height, 0);
  const Image8 after = render(image, RenderOptions{});
  const auto at = [](const Image8& im, int x, int y) { return im.row(y) + size_t(x) * 3; };
  // The centre keeps its red, the corner its grey.
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(at(after, 48, 48)[c], at(before, 48, 48)[c], 25) << c;
    EXPECT_NEAR(at(after, 4, 4)[c], at(before, 4, 4)[c], 4) << c;
  }
  EXPECT_GT(at(after, 4, 4)[1] - at(after, 48, 48)[1], 40) << "the ball still shows";
}

// Not a test: with SUBVEC_MEASURE_DELETES set, deletes up to 12 features (seeded) of each shared
// photograph at ratio 0.02 and prints one line each (docs/editing.md's table comes from it).
TEST(FeatureEdit, MeasureDeletes) {
  if (!getenv("SUBVEC_MEASURE_DELETES")) GTEST_SKIP() << "set SUBVEC_MEASURE_DELETES to measure";
  const std::filesystem::path dir = test::shared_photos();
  if (const auto why = test::skip_shared_photos(dir)) GTEST_SKIP() << *why;
  for (const char* name : {"apple", "astronaut", "butterfly", "chelsea", "fruits", "home", "rocket", "squirrel"}) {
    const Image8 photo = read_image(dir / (std::string(name) + ".png"));
    VectorizeOptions options;
    options.ratio = 0.02;
    options.levels.levels = 1;
    const VectorImage image = vectorize(photo, options);
    const int count = static_cast<int>(image.levels[0].features.size());
    for (int k = 0; k < std::min(12, count); ++k) {
      const int f = static_cast<int>((uint64_t(k) * 2654435761u + 17) % uint64_t(count));
      VectorImage edited = image;
      const DeleteMeasure m = measure_delete(edited, f);
      std::printf("%s %d %zu %d %.3f\n", name, f, image.levels[0].features[f].vertices.size(), m.jump, m.far);
    }
  }
}

// A tear drawn in the smoothest free spot of a photograph: a wave of 60 px where the rendered image
// varies least and no feature passes within 30 px. Its rendered curve is the fit, the image away
// from it (3 px) changes by MAE <= 0.5, and a color edit on one side stops at it.
void expect_a_drawn_tear_changes_nothing(const VectorImage& image, const char* name) {
  const ControlMesh& mesh = image.levels[0];
  const MeshTopology topology = validate_level(mesh, image.width, image.height);
  std::vector<std::vector<Vec2>> curves;
  for (const Feature& f : mesh.features)
    for (auto& c : feature_curves(mesh, topology, f)) curves.push_back(std::move(c));
  const Image8 before = render(image, RenderOptions{});
  auto at = [&](int x, int y, int c) { return int(before.pixels[(size_t(y) * before.width + x) * before.channels + c]); };
  double best = std::numeric_limits<double>::infinity();
  Vec2 centre{};
  for (int cy = 40; cy + 40 < image.height; cy += 10)
    for (int cx = 40; cx + 40 < image.width; cx += 10) {
      const Vec2 c{double(cx), double(cy)};
      const bool clear = std::none_of(curves.begin(), curves.end(), [&](const std::vector<Vec2>& k) {
        return distance_to_polyline(c, k) < 40;
      });
      if (!clear) continue;
      double variation = 0;
      for (int y = cy - 30; y < cy + 30; ++y)
        for (int x = cx - 30; x < cx + 30; ++x)
          for (int k = 0; k < 3; ++k) variation += std::abs(at(x + 1, y, k) - at(x, y, k)) + std::abs(at(x, y + 1, k) - at(x, y, k));
      if (variation < best) best = variation, centre = c;
    }
  ASSERT_TRUE(std::isfinite(best)) << name << ": no free spot";
  VectorImage edited = image;
  EditOp op;
  op.kind = EditOp::Kind::kAddFeature;
  op.points = wave({centre.x - 30, centre.y - 5}, {centre.x + 30, centre.y + 5}, 6, 90);
  apply_edit_ops(edited, std::span(&op, 1));
  const ControlMesh& cut = edited.levels[0];
  std::vector<Vec2> chain;
  for (const int v : cut.features.back().vertices) chain.push_back(cut.positions[v]);
  const std::vector<Vec2> curve = sample_bspline(chain, false, 64);
  for (const Vec2& p : op.points) EXPECT_LE(distance_to_polyline(p, curve), 0.5) << name;
  // The new tear's refined vertices lie on the fit (the other tears pass at least 10 px away).
  double worst = 0;
  int near = 0;
  for (const Vec2& p : refined_tear_points(cut, edited.width, edited.height)) {
    const double d = distance_to_polyline(p, curve);
    if (d < 3) worst = std::max(worst, d), ++near;
  }
  EXPECT_GT(near, 60) << name;
  EXPECT_LE(worst, 0.01) << name;
  const Image8 after = render(edited, RenderOptions{});
  const double away = mae_where(before, after, [&](int x, int y) { return distance_to_polyline({x + 0.5, y + 0.5}, curve) > 3; });
  EXPECT_LE(away, 0.5) << name;
  // Paint the side left of the curve's middle: the right side does not change.
  const Vec2 mid = curve[curve.size() / 2], next = curve[curve.size() / 2 + 1];
  const double len = std::hypot(next.x - mid.x, next.y - mid.y);
  const Vec2 n{-(next.y - mid.y) / len, (next.x - mid.x) / len};
  EditOp paint;
  paint.kind = EditOp::Kind::kColor;
  paint.at = {mid.x + 3 * n.x, mid.y + 3 * n.y};
  paint.radius = 12;
  paint.color = {255, 0, 255};
  paint.amount = 1;
  apply_edit_ops(edited, std::span(&paint, 1));
  const Image8 painted = render(edited, RenderOptions{});
  EXPECT_GT(mae_where(after, painted, [&](int x, int y) {
              return std::hypot(x + 0.5 - mid.x - 4 * n.x, y + 0.5 - mid.y - 4 * n.y) < 2;
            }), 20) << name << ": nothing was painted";
  EXPECT_LE(mae_where(after, painted, [&](int x, int y) {
              const double side = (x + 0.5 - mid.x) * n.x + (y + 0.5 - mid.y) * n.y;
              return side < -1.5 && std::hypot(x + 0.5 - mid.x, y + 0.5 - mid.y) < 10;
            }), 0.5) << name << ": the paint crossed the new tear";
  ::testing::Test::RecordProperty(std::string(name) + "_away_mae", std::to_string(away));
}

// The acceptance on photographs: a tear drawn in a smooth spot (above), and detected
// features deleted, the five longest of three photographs (the hardest: long outlines with jumps
// of up to 200 levels, pinched by the tears that stay). Every deletion is within the issue's
// bounds: no step over 4 levels across where the feature was, and the pixels past 3 control rings
// within MAE 0.5 (docs/editing.md has the table over 96 features).
TEST(FeatureEdit, OnPhotographs) {
  const std::filesystem::path dir = test::shared_photos();
  if (const auto why = test::skip_shared_photos(dir)) GTEST_SKIP() << *why;
  for (const char* name : {"butterfly", "rocket", "chelsea"}) {
    const Image8 photo = read_image(dir / (std::string(name) + ".png"));
    VectorizeOptions options;
    options.ratio = 0.02;
    options.levels.levels = 1;
    const VectorImage image = vectorize(photo, options);
    expect_a_drawn_tear_changes_nothing(image, name);
    std::vector<int> order(image.levels[0].features.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
      return image.levels[0].features[a].vertices.size() > image.levels[0].features[b].vertices.size();
    });
    for (size_t k = 0; k < std::min<size_t>(5, order.size()); ++k) {
      VectorImage edited = image;
      const DeleteMeasure m = measure_delete(edited, order[k]);
      EXPECT_LE(m.jump, 4) << name << " feature " << order[k];
      EXPECT_LE(m.far, 0.5) << name << " feature " << order[k];
      EXPECT_EQ(m.vertices_after, m.vertices_before);
    }
  }
}

}  // namespace
}  // namespace subvec
