// The .svec.json reader and writer: exact round trips, the documented layout, the worked examples
// of docs/format.md verbatim, and one test per kind of bad input, each checking that the message
// names the problem.
#include <gtest/gtest.h>
#include <unistd.h>

#include <bit>
#include <random>

#include "subvec/io/svec.h"
#include "subvec/mesh/validate.h"
#include "unit/io/svec_test_util.h"

namespace subvec {
namespace {

using namespace svec_test;

// The first worked example of docs/format.md (the 4 x 4 gradient), verbatim.
std::string square_text() {
  const auto blocks = doc_examples();
  return blocks.empty() ? std::string() : blocks[0];
}

// square_text() with `from` replaced by `to` (which must occur).
std::string edited(const std::string& from, const std::string& to) {
  std::string text = square_text();
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "\"" << from << "\" not in the example";
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

void expect_json_error(const std::string& text, ErrorCode code,
                       const std::vector<std::string>& parts) {
  expect_error([&] { (void)parse_svec_json(text); }, code, parts);
}

TEST(SvecJson, RoundTripIsExact) {
  const VectorImage image = rich_image();
  validate(image);
  const std::string text = to_svec_json(image);
  const VectorImage back = parse_svec_json(text);
  expect_same(image, back);
  EXPECT_EQ(to_svec_json(back), text);  // writing is deterministic
}

TEST(SvecJson, FloatsRoundTripBitForBit) {
  // Random finite colors over the whole float range and random positions in the domain.
  VectorImage image = square_image();
  std::mt19937 rng(12345);
  ControlMesh& m = image.levels[0];
  for (int round = 0; round < 200; ++round) {
    for (Color& c : m.colors) {
      for (float* v : {&c.r, &c.g, &c.b}) {
        do {
          *v = std::bit_cast<float>(static_cast<uint32_t>(rng()));
        } while (!std::isfinite(*v));
      }
    }
    m.positions[4] = {std::uniform_real_distribution<double>(1, 3)(rng),
                      std::uniform_real_distribution<double>(1, 3)(rng)};
    const VectorImage back = parse_svec_json(to_svec_json(image));
    for (int c = 0; c < m.num_colors(); ++c) {
      EXPECT_EQ(std::bit_cast<uint32_t>(back.levels[0].colors[c].r),
                std::bit_cast<uint32_t>(m.colors[c].r));
      EXPECT_EQ(std::bit_cast<uint32_t>(back.levels[0].colors[c].b),
                std::bit_cast<uint32_t>(m.colors[c].b));
    }
    EXPECT_EQ(back.levels[0].positions[4], m.positions[4]);
  }
}

TEST(SvecJson, ShortNumbersStayShort) {
  VectorImage image = square_image();
  image.levels[0].colors[4] = {0.1f, 12.3f, 1.0f / 3.0f};
  const std::string text = to_svec_json(image);
  EXPECT_NE(text.find("[0.1, 12.3, 0.33333334]"), std::string::npos) << text;
  EXPECT_NE(text.find("[[0, 0], [4, 0], [4, 4], [0, 4], [2, 2]]"), std::string::npos) << text;
}

TEST(SvecJson, TriangleColorsAreOmittedWhenTheyAreTheVertexIndices) {
  const std::string text = to_svec_json(square_image());
  EXPECT_EQ(text.find("triangle_colors"), std::string::npos);
  const VectorImage back = parse_svec_json(text);
  EXPECT_EQ(back.levels[0].triangle_colors, back.levels[0].triangles);

  VectorImage torn = square_image();
  torn.levels[0].triangle_colors[0] = {1, 0, 4};  // corners swap colors: not the identity
  torn.levels[0].colors[0] = torn.levels[0].colors[1];
  EXPECT_NE(to_svec_json(torn).find("triangle_colors"), std::string::npos);
}

TEST(SvecJson, DocExamplesParseVerbatimAndAreInTheWritersLayout) {
  const std::vector<std::string> blocks = doc_examples();
  ASSERT_EQ(blocks.size(), 2u) << "docs/format.md should hold two ```json svec-example blocks";
  const VectorImage gradient = parse_svec_json(blocks[0]);
  expect_same(gradient, square_image());
  EXPECT_EQ(to_svec_json(gradient), blocks[0]);

  const VectorImage tear = parse_svec_json(blocks[1]);
  EXPECT_EQ(to_svec_json(tear), blocks[1]);
  const ControlMesh& m = tear.levels.at(0);
  ASSERT_EQ(m.features.size(), 1u);
  EXPECT_EQ(m.features[0].vertices, (std::vector<int32_t>{4, 0}));
  EXPECT_EQ(m.num_colors(), 6);
  EXPECT_EQ(m.triangle_colors[3], (Tri{3, 5, 4}));
  // As the doc says: the tear edge (4, 0) separates two colors at vertex 0, one at vertex 4.
  const MeshTopology topo = validate_level(m, tear.width, tear.height);
  EXPECT_EQ(topo.edge_tags[topo.find_edge(4, 0)], EdgeTag::kTear);
  EXPECT_EQ(topo.vertex_tags[4], VertexTag::kCorner);
  EXPECT_EQ(tear.metadata.at(0).first, "title");
}

TEST(SvecJson, ExamplesAreValidAndCanonical) {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(source_dir() / "examples")) {
    const std::string name = entry.path().filename().string();
    if (name.size() < 10 || name.substr(name.size() - 10) != ".svec.json") continue;
    SCOPED_TRACE(name);
    ++count;
    const std::string text = read_text(entry.path());
    const VectorImage image = parse_svec_json(text);
    EXPECT_FALSE(image.levels[0].features.empty());
    // examples/make_examples.py writes subvec's own layout: re-writing changes nothing.
    EXPECT_EQ(to_svec_json(image), text);
    const VectorImage via_file = read_svec(entry.path());
    expect_same(image, via_file);
  }
  EXPECT_GE(count, 3);
}

TEST(SvecJson, OptionalKeysHaveTheirDefaults) {
  const VectorImage image = parse_svec_json(R"({"format":"subvec","version":1,"width":4,"height":4,
    "levels":[{"vertices":[[0,0],[4,0],[4,4],[0,4]],"colors":[[1,2,3],[1,2,3],[1,2,3],[1,2,3]],
    "triangles":[[0,1,2],[0,2,3]],"features":[]}],
    "strokes":[{"points":[[0,0],[1,1]],"width":1,"color":[0,0,0]}],"metadata":{}})");
  ASSERT_EQ(image.strokes.size(), 1u);
  EXPECT_EQ(image.strokes[0].level, 0);
  EXPECT_EQ(image.strokes[0].taper, 0.25f);
  EXPECT_TRUE(image.levels[0].creases.empty());
  EXPECT_TRUE(image.metadata.empty());
}

TEST(SvecJson, AcceptsAByteOrderMarkWhenReadFromAFile) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("subvec_bom_test_" + std::to_string(::getpid()) + ".svec.json");
  const std::string text = "\xEF\xBB\xBF" + square_text();
  {
    std::ofstream out(path, std::ios::binary);
    out << text;
  }
  expect_same(read_svec(path), square_image());
  std::filesystem::remove(path);
}

// ---- bad inputs --------------------------------------------------------------------------------

TEST(SvecJsonErrors, SyntaxErrorsNameThePlace) {
  expect_json_error(edited("[2, 2]]", "[NaN, 2]]"), ErrorCode::kBadFile,
                    {"invalid JSON", "levels[0].vertices[4]", "line 8"});
  expect_json_error(square_text().substr(0, 80), ErrorCode::kBadFile,
                    {"invalid JSON", "unexpected end of input"});
  expect_json_error("", ErrorCode::kBadFile, {"invalid JSON"});
  expect_json_error(edited("[4, 4]", "[1e400, 4]"), ErrorCode::kBadFile,
                    {"levels[0].vertices[2][0]", "1e400"});
}

TEST(SvecJsonErrors, UnknownAndDuplicateKeys) {
  expect_json_error(edited("\"height\"", "\"heigth\""), ErrorCode::kBadFile,
                    {"unknown key \"heigth\""});
  expect_json_error(edited("\"triangles\"", "\"triangle_color\": [], \"triangles\""),
                    ErrorCode::kBadFile, {"levels[0]", "unknown key \"triangle_color\""});
  expect_json_error(edited("\"width\": 4,", "\"width\": 4, \"width\": 5,"), ErrorCode::kBadFile,
                    {"duplicate key \"width\""});
  expect_json_error(edited("\"triangles\"", "\"colors\": [], \"triangles\""), ErrorCode::kBadFile,
                    {"levels[0]", "duplicate key \"colors\""});
  // Keys are quoted into messages with control characters escaped: messages stay one line.
  expect_json_error(edited("\"height\"", "\"hei\\nght\""), ErrorCode::kBadFile,
                    {"unknown key \"hei\\x0aght\""});
}

TEST(SvecJsonErrors, WrongTypesAndShapes) {
  expect_json_error(edited("\"width\": 4", "\"width\": \"4\""), ErrorCode::kBadFile,
                    {"width: expected an integer, got a string"});
  expect_json_error(edited("[3, 0, 4]", "[3, 0, 4.0]"), ErrorCode::kBadFile,
                    {"levels[0].triangles[3][2]", "expected an integer", "4.0"});
  expect_json_error(edited("[2, 2]]", "[2, 2, 2]]"), ErrorCode::kBadFile,
                    {"levels[0].vertices[4]", "expected [x, y]", "3 elements"});
  expect_json_error(edited("[0, 0, 255], [0, 0, 255]", "[0, 0, 255], [0, \"0\", 255]"),
                    ErrorCode::kBadFile, {"levels[0].colors[3][1]", "expected a number"});
  expect_json_error(R"({"format": "subvec", "version": 1, "width": 4, "height": 4, "levels": {}})",
                    ErrorCode::kBadFile, {"levels: expected an array, got an object"});
  expect_json_error("[1, 2]", ErrorCode::kBadFile, {"expected a JSON object, got an array"});
  expect_json_error(edited("\"version\": 1", "\"version\": 1, \"metadata\": {\"a\": 3}"),
                    ErrorCode::kBadFile, {"metadata.a: expected a string"});
  expect_json_error(edited("\"width\": 4", "\"width\": 99999999999"), ErrorCode::kBadFile,
                    {"width", "out of the 32-bit range"});
  expect_json_error(edited("[[0, 1, 4]", "[[0, 1, -1]"), ErrorCode::kInvalidMesh,
                    {"level 0: triangle 0 refers to vertex -1, out of range (5 vertices)"});
}

TEST(SvecJsonErrors, MissingKeys) {
  expect_json_error(edited(R"("format": "subvec",)", ""), ErrorCode::kBadFile,
                    {"missing key \"format\""});
  expect_json_error(edited("\"triangles\"", "\"triangles_\""), ErrorCode::kBadFile,
                    {"levels[0]", "unknown key \"triangles_\""});
  expect_json_error(
      edited(",\n      \"triangles\": [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]", ""),
      ErrorCode::kBadFile, {"levels[0]", "missing key \"triangles\""});
}

TEST(SvecJsonErrors, FormatAndVersion) {
  expect_json_error(edited("\"subvec\"", "\"svg\""), ErrorCode::kBadFile,
                    {"format", "expected \"subvec\""});
  expect_json_error(edited("\"version\": 1", "\"version\": 3"), ErrorCode::kBadFile,
                    {"unsupported .svec.json version 3 (this build reads 1 and 2)"});
}

TEST(SvecJsonErrors, TriangleColorsMustMatch) {
  expect_json_error(edited("[127.5, 0, 127.5]]", "[127.5, 0, 127.5], [1, 1, 1]]"),
                    ErrorCode::kBadFile,
                    {"triangle_colors\" is absent", "5 vertices and 6 colors"});
  expect_json_error(edited("[3, 0, 4]]\n",
                           "[3, 0, 4]],\n\"triangle_colors\": [[0, 1, 4], [1, 2, 4], [2, 3, 4]]\n"),
                    ErrorCode::kBadFile, {"levels[0].triangle_colors", "3 entries", "4 triangles"});
  expect_json_error(
      edited("[3, 0, 4]]\n",
             "[3, 0, 4]],\n\"triangle_colors\": [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 7]]\n"),
      ErrorCode::kInvalidMesh,
      {"level 0: triangle_colors 3 refers to color 7, out of range (5 colors)"});
}

TEST(SvecJsonErrors, AbsurdSizes) {
  expect_json_error(edited("\"width\": 4", "\"width\": 1000000"), ErrorCode::kLimit,
                    {"width 1000000 is over the limit of 65536"});
  expect_json_error(edited("\"height\": 4", "\"height\": 0"), ErrorCode::kInvalidMesh,
                    {"height 0 is not positive"});
  expect_json_error(
      edited("\"width\": 4,\n  \"height\": 4", "\"width\": 65536,\n  \"height\": 65536"),
      ErrorCode::kLimit, {"65536 x 65536", "pixels"});
  std::string deep = "{\"format\": \"subvec\", \"version\": 1, \"metadata\": ";
  for (int i = 0; i < 100; ++i) deep += "[";
  expect_json_error(deep, ErrorCode::kBadFile, {"nested deeper than 32"});
  expect_json_error(R"({"format": "subvec", "version": 1, "width": 4, "height": 4, "levels": []})",
                    ErrorCode::kInvalidMesh, {"the image has no levels"});
}

TEST(SvecJsonErrors, InvalidMeshesNameTheElement) {
  expect_json_error(edited("[2, 2]]", "[2, 5]]"), ErrorCode::kInvalidMesh,
                    {"level 0: vertex 4 position (2, 5) is outside the image [0, 4] x [0, 4]"});
  expect_json_error(edited("[2, 2]]", "[2, 0]]"), ErrorCode::kInvalidMesh,
                    {"level 0: triangle 0 (0, 1, 4) is flipped or degenerate (signed area 0)"});
}

}  // namespace
}  // namespace subvec
