// validate_level() and validate(): valid meshes pass and return their topology; each rule, when
// broken, gives its own one-line message naming the level, the element and its index.
#include "subvec/mesh/validate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "support/synthetic.h"
#include "support/test_meshes.h"
#include "unit/io/svec_test_util.h"

namespace subvec {
namespace {

using svec_test::expect_error;
using svec_test::square_image;

void expect_level_error(const ControlMesh& m, ErrorCode code, const std::vector<std::string>& parts,
                        int width = 4, int height = 4) {
  expect_error([&] { (void)validate_level(m, width, height, 2); }, code, parts);
}

ControlMesh square() { return square_image().levels[0]; }

// The second worked example of docs/format.md: a tear from the center (4) to the corner (0).
ControlMesh torn_square() {
  ControlMesh m = square();
  m.colors.push_back({0, 60, 160});
  m.triangle_colors[3] = {3, 5, 4};
  m.features.push_back({0, {4, 0}, 0});
  return m;
}

TEST(Validate, AcceptsTheTestMeshesAndReturnsTheirTopology) {
  for (const testing::TestMesh& t : testing::all_test_meshes()) {
    SCOPED_TRACE(t.name);
    const MeshTopology topo = validate_level(t.mesh, t.width, t.height);
    const MeshTopology expected = t.topology();
    EXPECT_EQ(topo.edges, expected.edges);
    EXPECT_EQ(topo.edge_tags, expected.edge_tags);
    EXPECT_EQ(topo.vertex_tags, expected.vertex_tags);
  }
  test::SyntheticOptions options;
  options.width = 160;
  options.height = 120;
  options.vertices = 400;
  validate(test::make_synthetic_image(options));
}

TEST(Validate, TornSquareHasATearAndCorners) {
  const MeshTopology topo = validate_level(torn_square(), 4, 4);
  EXPECT_EQ(topo.edge_tags[topo.find_edge(0, 4)], EdgeTag::kTear);
  EXPECT_EQ(topo.edge_tags[topo.find_edge(0, 1)], EdgeTag::kBorder);
  EXPECT_EQ(topo.vertex_tags[4], VertexTag::kCorner);  // the tear's end inside the image
  EXPECT_EQ(topo.vertex_tags[0], VertexTag::kCorner);  // an image corner
}

TEST(Validate, ValuesAndRanges) {
  ControlMesh m = square();
  m.positions[4] = {2, std::numeric_limits<double>::quiet_NaN()};
  expect_level_error(m, ErrorCode::kInvalidMesh,
                     {"level 2: vertex 4 position (2, nan) is not finite"});
  m = square();
  m.positions[4] = {-0.001, 2};
  expect_level_error(
      m, ErrorCode::kInvalidMesh,
      {"level 2: vertex 4 position (-0.001, 2) is outside the image [0, 4] x [0, 4]"});
  m = square();
  m.colors[3].g = std::numeric_limits<float>::infinity();
  expect_level_error(m, ErrorCode::kInvalidMesh, {"level 2: color 3 (0, inf, 255) is not finite"});
  m = square();
  m.triangle_colors.pop_back();
  expect_level_error(m, ErrorCode::kInvalidMesh, {"4 triangles but 3 triangle_colors entries"});
  m = square();
  m.triangles[1] = {1, 1, 4};
  expect_level_error(m, ErrorCode::kInvalidMesh, {"level 2: triangle 1 repeats vertex 1"});
  m = square();
  m.triangles[3][0] = 5;
  expect_level_error(m, ErrorCode::kInvalidMesh,
                     {"level 2: triangle 3 refers to vertex 5, out of range (5 vertices)"});
}

TEST(Validate, TrianglesMustBePositive) {
  ControlMesh m = square();
  m.positions[4] = {2, 0};  // on the top edge: triangle 0 is degenerate
  expect_level_error(m, ErrorCode::kInvalidMesh,
                     {"level 2: triangle 0 (0, 1, 4) is flipped or degenerate (signed area 0)"});
  m = square();
  for (Tri& t : m.triangles) std::swap(t[1], t[2]);  // all flipped, consistently
  m.triangle_colors = m.triangles;
  expect_level_error(m, ErrorCode::kInvalidMesh,
                     {"level 2: triangle 0 (0, 4, 1) is flipped or degenerate (signed area -4)"});
}

TEST(Validate, TheMeshMustTileTheImage) {
  ControlMesh m = square();
  m.positions.push_back({3, 3});
  m.colors.push_back({});
  expect_level_error(m, ErrorCode::kInvalidMesh,
                     {"level 2: vertex 5 (3, 3) is used by no triangle"});

  // Vertex 1 pulled in from the corner: the right side of the mesh no longer lies on the border.
  m = square();
  m.positions[1] = {3.5, 0};
  expect_level_error(
      m, ErrorCode::kInvalidMesh,
      {"level 2: edge (1, 2) from (3.5, 0) to (4, 4) has a triangle on one side only"});

  // The image is larger than the mesh: the mesh's right side is not on the image border.
  expect_level_error(square(), ErrorCode::kInvalidMesh,
                     {"edge (1, 2)", "does not lie on the image border"}, 5, 4);
}

TEST(Validate, ColorRules) {
  ControlMesh m = square();
  m.triangle_colors[0] = {0, 1, 1};  // color 1 also used at vertex 4
  expect_level_error(
      m, ErrorCode::kInvalidMesh,
      {"level 2: color 1 is used at vertex 1 (triangle 0) and at vertex 4 (triangle 0)"});
  m = square();
  m.colors.push_back({1, 2, 3});
  expect_level_error(m, ErrorCode::kInvalidMesh,
                     {"level 2: color 5 is used by no triangle corner"});
  m = square();
  m.triangle_colors[1] = {1, 2, 3};  // not even the right vertex's color
  expect_level_error(m, ErrorCode::kInvalidMesh,
                     {"color 3 is used at vertex 4 (triangle 1) and at vertex 3 (triangle 2)"});

  // A tear that ends inside the image has one color at its end: a second one there is an error.
  m = torn_square();
  validate_level(m, 4, 4);
  m.colors.push_back({9, 9, 9});
  m.triangle_colors[0][2] = 6;
  expect_level_error(
      m, ErrorCode::kInvalidMesh,
      {"level 2: edge (1, 4) is not a tear but triangles 0 and 1 use different colors at "
       "vertex 4 (6 and 4)"});
  // Without the feature, the two colors at vertex 0 are a jump across a smooth edge.
  m = torn_square();
  m.features.clear();
  expect_level_error(m, ErrorCode::kInvalidMesh,
                     {"edge (0, 4) is not a tear", "vertex 0 (0 and 5)"});
}

TEST(Validate, FeaturesAndCreases) {
  ControlMesh m = torn_square();
  m.features.push_back({0, {4, 2}, 0});
  m.colors.push_back(m.colors[2]);  // (colors do not matter: ids are checked first)
  expect_level_error(m, ErrorCode::kInvalidMesh, {"level 2: feature 1 repeats id 0"});
  m = torn_square();
  m.features[0].saliency = std::nan("");
  expect_level_error(m, ErrorCode::kInvalidMesh, {"feature 0 (id 0) saliency nan is not finite"});
  m = torn_square();
  m.features[0].vertices = {4};
  expect_level_error(m, ErrorCode::kInvalidMesh, {"feature 0 (id 0) has fewer than two vertices"});
  m = torn_square();
  m.creases.push_back({0, 4});
  expect_level_error(m, ErrorCode::kInvalidMesh,
                     {"level 2: feature 0 (id 0): edge (4, 0) is already a crease"});
  m = square();
  m.creases.push_back({0, 2});
  expect_level_error(m, ErrorCode::kInvalidMesh,
                     {"level 2: crease 0: (0, 2) is not an edge of the mesh"});
  m = square();
  m.creases.push_back({1, 4});
  validate_level(m, 4, 4);  // an interior crease keeps colors continuous: valid
}

TEST(Validate, ImageSizeLevelsStrokesMetadata) {
  VectorImage image = square_image();
  validate(image);
  image.width = 0;
  expect_error([&] { validate(image); }, ErrorCode::kInvalidMesh, {"width 0 is not positive"});
  image.width = 70000;
  expect_error([&] { validate(image); }, ErrorCode::kLimit,
               {"width 70000 is over the limit of 65536"});
  image.width = 65536;
  image.height = 65536;
  expect_error([&] { validate(image); }, ErrorCode::kLimit,
               {"image size 65536 x 65536 is over the limit of 1073741824 pixels"});
  image = square_image();
  image.levels.clear();
  expect_error([&] { validate(image); }, ErrorCode::kInvalidMesh, {"the image has no levels"});
  image.levels.assign(65, square());
  expect_error([&] { validate(image); }, ErrorCode::kLimit, {"65 levels is over the limit of 64"});
  image.levels.assign(2, square());
  image.levels[1].positions[4] = {2, 0};
  expect_error([&] { validate(image); }, ErrorCode::kInvalidMesh, {"level 1: triangle 0"});

  image = square_image();
  Stroke s;
  s.points = {{0, 0}, {1, 1}};
  image.strokes = {s};
  validate(image);
  auto stroke_error = [&](auto change, const std::string& part) {
    VectorImage copy = image;
    change(copy.strokes[0]);
    expect_error([&] { validate(copy); }, ErrorCode::kInvalidMesh, {"stroke 0: " + part});
  };
  stroke_error([](Stroke& t) { t.level = 1; }, "level 1 is out of range (1 levels)");
  stroke_error([](Stroke& t) { t.points.pop_back(); }, "has fewer than two points");
  stroke_error([](Stroke& t) { t.points[1].x = INFINITY; }, "point 1 (inf, 1) is not finite");
  stroke_error([](Stroke& t) { t.width = 0; }, "width 0 is not a positive number");
  stroke_error([](Stroke& t) { t.color.b = NAN; }, "color (0, 0, nan) is not finite");
  stroke_error([](Stroke& t) { t.taper = 0.75f; }, "taper 0.75 is outside [0, 0.5]");

  image = square_image();
  image.metadata = {{"a", "1"}, {"b", "2"}, {"a", "3"}};
  expect_error([&] { validate(image); }, ErrorCode::kInvalidMesh,
               {"metadata entry 2: key \"a\" appears twice"});
  image.metadata = {{"a", "caf\xc3"}};
  expect_error([&] { validate(image); }, ErrorCode::kInvalidMesh,
               {"metadata entry 0 (\"a\"): value is not valid UTF-8"});
  image.metadata = {{"\xed\xa0\x80", "surrogate"}};
  expect_error([&] { validate(image); }, ErrorCode::kInvalidMesh, {"key is not valid UTF-8"});
}

}  // namespace
}  // namespace subvec
