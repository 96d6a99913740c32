// The compact `.svec` (versions 2 and 3: the same content as varints under zstd, or range-coded):
// the structure survives (matched vertex by vertex at fine grids), a second write is
// byte-identical, both versions read back alike, the default grids keep the picture and meet the
// size budget on a photograph, the documented worked examples, and corrupt or cut files are
// reported, never crash.
#include <gtest/gtest.h>
#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <sstream>

#include "subvec/core/metrics.h"
#include "subvec/io/image_io.h"
#include "subvec/io/svec.h"
#include "subvec/render/renderer.h"
#include "subvec/vectorize/vectorize.h"
#include "support/shared_photos.h"
#include "support/synthetic.h"
#include "support/test_meshes.h"
#include "unit/io/svec_test_util.h"

namespace subvec {
namespace {

using namespace svec_test;

uint32_t version_of(const std::vector<uint8_t>& file) {
  return uint32_t{file[8]} | uint32_t{file[9]} << 8 | uint32_t{file[10]} << 16 |
         uint32_t{file[11]} << 24;
}

// The uncompressed payload of a .svec file.
std::vector<uint8_t> payload_of(const std::vector<uint8_t>& file) {
  uint64_t size = 0;
  for (int k = 0; k < 8; ++k) size |= uint64_t{file[16 + k]} << (8 * k);
  std::vector<uint8_t> out(size);
  const size_t n = ZSTD_decompress(out.data(), out.size(), file.data() + 32, file.size() - 32);
  EXPECT_FALSE(ZSTD_isError(n));
  return out;
}

std::vector<VectorImage> images_to_test() {
  std::vector<VectorImage> images = {square_image(), rich_image()};
  for (const testing::TestMesh& t : testing::all_test_meshes()) {
    VectorImage image;
    image.width = t.width;
    image.height = t.height;
    image.levels.push_back(t.mesh);
    images.push_back(image);
  }
  test::SyntheticOptions synthetic;
  synthetic.width = 160;
  synthetic.height = 120;
  synthetic.vertices = 600;
  images.push_back(test::make_synthetic_image(synthetic));
  return images;
}

// Checks that `b` is `a` renumbered: vertices matched by position (within `tolerance`), the same
// triangles (up to rotation), creases, features and corner colors (within `color_tolerance`).
void expect_same_up_to_order(const ControlMesh& a, const ControlMesh& b, double tolerance,
                             double color_tolerance) {
  ASSERT_EQ(a.num_vertices(), b.num_vertices());
  ASSERT_EQ(a.num_triangles(), b.num_triangles());
  std::vector<int32_t> to_a(b.num_vertices(), -1);
  for (int32_t v = 0; v < b.num_vertices(); ++v) {
    for (int32_t u = 0; u < a.num_vertices(); ++u) {
      if (std::abs(a.positions[u].x - b.positions[v].x) <= tolerance &&
          std::abs(a.positions[u].y - b.positions[v].y) <= tolerance) {
        ASSERT_EQ(to_a[v], -1) << "two vertices match vertex " << v;
        to_a[v] = u;
      }
    }
    ASSERT_GE(to_a[v], 0) << "vertex " << v << " matches nothing";
  }
  // Triangles, each rotated to start at its smallest vertex, with their corner colors.
  auto canonical = [](Tri t, Tri c) {
    const int k = int(std::min_element(t.begin(), t.end()) - t.begin());
    std::rotate(t.begin(), t.begin() + k, t.end());
    std::rotate(c.begin(), c.begin() + k, c.end());
    return std::pair<Tri, Tri>(t, c);
  };
  std::map<Tri, Tri> corners_a;
  for (int f = 0; f < a.num_triangles(); ++f) {
    const auto [t, c] = canonical(a.triangles[f], a.triangle_colors[f]);
    corners_a[t] = c;
  }
  for (int f = 0; f < b.num_triangles(); ++f) {
    const Tri& t = b.triangles[f];
    const auto [key, c] = canonical({to_a[t[0]], to_a[t[1]], to_a[t[2]]}, b.triangle_colors[f]);
    const auto it = corners_a.find(key);
    ASSERT_NE(it, corners_a.end()) << "triangle " << f << " is not in the original";
    for (int k = 0; k < 3; ++k) {
      const Color &x = a.colors[it->second[k]], &y = b.colors[c[k]];
      EXPECT_NEAR(x.r, y.r, color_tolerance);
      EXPECT_NEAR(x.g, y.g, color_tolerance);
      EXPECT_NEAR(x.b, y.b, color_tolerance);
    }
  }
  ASSERT_EQ(a.creases.size(), b.creases.size());
  for (size_t i = 0; i < a.creases.size(); ++i) {
    EXPECT_EQ(a.creases[i], (EdgeVerts{to_a[b.creases[i][0]], to_a[b.creases[i][1]]}));
  }
  ASSERT_EQ(a.features.size(), b.features.size());
  for (size_t i = 0; i < a.features.size(); ++i) {
    EXPECT_EQ(a.features[i].id, b.features[i].id);
    EXPECT_EQ(a.features[i].saliency, b.features[i].saliency);
    std::vector<int32_t> chain;
    for (int32_t v : b.features[i].vertices) chain.push_back(to_a[v]);
    EXPECT_EQ(a.features[i].vertices, chain);
  }
}

constexpr int kCompactVersions[] = {2, 3};

TEST(SvecCompact, StructureSurvivesAtFineGrids) {
  for (const int version : kCompactVersions)
  for (const VectorImage& image : images_to_test()) {
    SCOPED_TRACE("version " + std::to_string(version));
    const SvecWriteOptions fine{.compact_version = version, .position_bits = 12, .color_bits = 12};
    const std::vector<uint8_t> bytes = to_svec_binary(image, fine);
    EXPECT_EQ(version_of(bytes), uint32_t(version));
    const VectorImage back = parse_svec_binary(bytes);
    ASSERT_EQ(back.levels.size(), image.levels.size());
    for (size_t l = 0; l < image.levels.size(); ++l) {
      SCOPED_TRACE("level " + std::to_string(l) + " of a " + std::to_string(image.width) + " x " +
                   std::to_string(image.height) + " image");
      expect_same_up_to_order(image.levels[l], back.levels[l], std::ldexp(1.0, -12),
                              std::ldexp(1.0, -11));
    }
    EXPECT_EQ(back.metadata, image.metadata);
    ASSERT_EQ(back.strokes.size(), image.strokes.size());
    for (size_t i = 0; i < image.strokes.size(); ++i)
      EXPECT_EQ(back.strokes[i].points, image.strokes[i].points);
  }
}

TEST(SvecCompact, SecondWriteIsIdenticalAndValuesLieOnTheGrids) {
  for (const SvecWriteOptions& options :
       {SvecWriteOptions{}, SvecWriteOptions{.position_bits = 0, .color_bits = -4},
        SvecWriteOptions{.position_bits = 7, .color_bits = 3},
        SvecWriteOptions{.compact_version = 2},
        SvecWriteOptions{.compact_version = 2, .position_bits = 7, .color_bits = 3}}) {
    for (const VectorImage& image : images_to_test()) {
      const std::vector<uint8_t> bytes = to_svec_binary(image, options);
      const VectorImage back = parse_svec_binary(bytes);
      EXPECT_EQ(to_svec_binary(back, options), bytes);
      EXPECT_EQ(to_svec_binary(image, options), bytes);  // deterministic
      // Through JSON too: grid values print and parse exactly.
      EXPECT_EQ(to_svec_binary(parse_svec_json(to_svec_json(back)), options), bytes);
      for (const Color& c : back.levels[0].colors) {
        for (const float v : {c.r, c.g, c.b}) {
          const double steps = std::ldexp(double(v), options.color_bits);
          EXPECT_EQ(steps, std::round(steps));
        }
      }
    }
  }
}

// Version 3 codes exactly version 2's content: either file reads back as the same image, and
// each writes the other's bytes.
TEST(SvecCompact, Versions2And3HoldTheSameImage) {
  for (const SvecWriteOptions& options :
       {SvecWriteOptions{}, SvecWriteOptions{.position_bits = 0, .color_bits = -4},
        SvecWriteOptions{.position_bits = 12, .color_bits = 12}}) {
    for (const VectorImage& image : images_to_test()) {
      SvecWriteOptions v2 = options;
      v2.compact_version = 2;
      const std::vector<uint8_t> a = to_svec_binary(image, v2), b = to_svec_binary(image, options);
      EXPECT_EQ(version_of(b), 3u);
      const VectorImage from_a = parse_svec_binary(a), from_b = parse_svec_binary(b);
      expect_same(from_a, from_b);
      EXPECT_EQ(to_svec_binary(from_b, v2), a);
      EXPECT_EQ(to_svec_binary(from_a, options), b);
    }
  }
  expect_error([] { (void)to_svec_binary(square_image(), {.compact_version = 4}); },
               ErrorCode::kInvalidArgument, {"compact .svec version 4"});
}

// Range coding makes the file smaller than version 2's varints and zstd (about 10 % on the
// photographs; docs/format.md).
TEST(SvecCompact, Version3IsSmaller) {
  test::SyntheticOptions synthetic;
  synthetic.width = 200;
  synthetic.height = 150;
  synthetic.vertices = 2000;
  const VectorImage image = test::make_synthetic_image(synthetic);
  const size_t v2 = to_svec_binary(image, {.compact_version = 2}).size();
  const size_t v3 = to_svec_binary(image).size();
  RecordProperty("v3_over_v2", std::to_string(double(v3) / double(v2)));
  EXPECT_LT(double(v3), 0.97 * double(v2));
}

TEST(SvecCompact, LosslessStillWritesVersion1) {
  const std::vector<uint8_t> bytes = to_svec_binary(rich_image(), {.lossless = true});
  EXPECT_EQ(version_of(bytes), 1u);
  expect_same(parse_svec_binary(bytes), rich_image());
}

TEST(SvecCompact, CoarseGridsThatWouldFoldTheMeshAreRepairedOrRefined) {
  // Vertices 0.01 px apart: a 1 px grid collapses them; the writer moves them apart or refines.
  VectorImage image = square_image();
  ControlMesh& m = image.levels[0];
  m.positions.push_back({2.01, 2.0});
  m.colors.push_back({1, 2, 3});
  m.triangles = {{0, 1, 5}, {1, 2, 5}, {2, 4, 5}, {2, 3, 4}, {3, 0, 4}, {0, 5, 4}};
  m.triangle_colors = m.triangles;
  const std::vector<uint8_t> bytes = to_svec_binary(image, {.position_bits = 0});
  EXPECT_EQ(version_of(bytes), 3u);
  const VectorImage back = parse_svec_binary(bytes);  // valid
  EXPECT_EQ(back.levels[0].num_triangles(), 6);
}

TEST(SvecCompact, RejectsBadOptions) {
  expect_error([] { (void)to_svec_binary(square_image(), {.position_bits = 13}); },
               ErrorCode::kInvalidArgument, {"position bits 13"});
  expect_error([] { (void)to_svec_binary(square_image(), {.color_bits = -5}); },
               ErrorCode::kInvalidArgument, {"color bits -5"});
}

// A vectorized synthetic image: the default grids change the 1x render by well under a level.
TEST(SvecCompact, DefaultGridsKeepThePicture) {
  test::SyntheticOptions synthetic;
  synthetic.width = 200;
  synthetic.height = 150;
  synthetic.vertices = 2000;
  const VectorImage image = test::make_synthetic_image(synthetic);
  const Image8 before = render(image, {});
  const std::vector<uint8_t> bytes = to_svec_binary(image);
  const Image8 after = render(parse_svec_binary(bytes), {});
  EXPECT_LT(compare(before, after).mae_mean, 0.5);
  int vertices = image.levels[0].num_vertices();
  EXPECT_LT(double(bytes.size()) / vertices, 8.0);
}

// The acceptance figure on a shared photograph (skipped when absent): at the default ratio,
// at most 6.5 bytes per control vertex with an MAE change of at most 0.05.
TEST(SvecCompact, SharedPhotographWithinBudget) {
  const std::filesystem::path path =
      std::filesystem::path(SUBVEC_SOURCE_DIR) / ".." / "shared" / "images" / "chelsea.png";
  if (const auto why = test::skip_shared_photos(path)) GTEST_SKIP() << *why;
  const Image8 photo = read_image(path);
  VectorizeOptions one_level;  // the budget is per vertex of one level
  one_level.levels.levels = 1;
  const VectorImage image = vectorize(photo, one_level);
  const std::vector<uint8_t> bytes = to_svec_binary(image);
  const double bytes_per_vertex = double(bytes.size()) / image.levels[0].num_vertices();
  const double before = compare(photo, render(image, {})).mae_mean;
  const double after = compare(photo, render(parse_svec_binary(bytes), {})).mae_mean;
  RecordProperty("bytes_per_vertex", std::to_string(bytes_per_vertex));
  EXPECT_LE(bytes_per_vertex, 6.5);
  EXPECT_LE(std::abs(after - before), 0.05);
}

// The bytes of a ```text BLOCK``` block of docs/format.md (hex, '#' starts a comment).
std::vector<uint8_t> documented_bytes(const std::string& block) {
  const std::string doc = read_text(source_dir() / "docs" / "format.md");
  const std::string open = "```text " + block + "\n";
  const size_t begin = doc.find(open);
  EXPECT_NE(begin, std::string::npos) << "docs/format.md has no " << block << " block";
  if (begin == std::string::npos) return {};
  const size_t end = doc.find("```", begin + open.size());
  std::vector<uint8_t> documented;
  std::istringstream in(doc.substr(begin + open.size(), end - begin - open.size()));
  std::string line;
  while (std::getline(in, line)) {
    line = line.substr(0, line.find('#'));  // comments
    std::istringstream words(line);
    std::string hex;
    while (words >> hex) documented.push_back(static_cast<uint8_t>(std::stoi(hex, nullptr, 16)));
  }
  return documented;
}

// docs/format.md lays out the compact payloads of its 4 x 4 worked example byte by byte.
TEST(SvecCompact, WorkedExampleMatchesTheDocs) {
  const std::vector<uint8_t> documented = documented_bytes("svec-compact-example");
  const std::vector<uint8_t> bytes = to_svec_binary(square_image(), {.compact_version = 2});
  EXPECT_EQ(payload_of(bytes), documented);
  // And the hand-made file of that payload reads as the documented image.
  const VectorImage back = parse_svec_binary(svec_file(documented, 2));
  expect_same_up_to_order(square_image().levels[0], back.levels[0], 0, 1);
}

TEST(SvecCompact, WorkedExampleVersion3MatchesTheDocs) {
  const std::vector<uint8_t> documented = documented_bytes("svec-coded-example");
  EXPECT_EQ(payload_of(to_svec_binary(square_image())), documented);
  const VectorImage back = parse_svec_binary(svec_file(documented, 3));
  expect_same_up_to_order(square_image().levels[0], back.levels[0], 0, 1);
  expect_same(back, parse_svec_binary(svec_file(documented_bytes("svec-compact-example"), 2)));
}

// ---- bad inputs --------------------------------------------------------------------------------

TEST(SvecCompactErrors, EveryTruncationIsReported) {
  for (const int version : kCompactVersions) {
    const std::vector<uint8_t> bytes = to_svec_binary(rich_image(), {.compact_version = version});
    const std::vector<uint8_t> payload = payload_of(bytes);
    for (size_t n = 0; n < payload.size(); ++n) {
      SCOPED_TRACE("version " + std::to_string(version) + ", first " + std::to_string(n) +
                   " payload bytes");
      const std::vector<uint8_t> cut(payload.begin(), payload.begin() + long(n));
      expect_error([&] { (void)parse_svec_binary(svec_file(cut, uint32_t(version))); },
                   ErrorCode::kBadFile, {""});
    }
  }
}

TEST(SvecCompactErrors, CorruptPayloadsThrowNeverCrash) {
  // Every byte of the payload replaced by a few values: the reader either reads a valid image or
  // throws subvec::Error; it never crashes, hangs or throws anything else.
  for (const int version : kCompactVersions)
  for (const VectorImage& image : {square_image(), rich_image()}) {
    const std::vector<uint8_t> payload =
        payload_of(to_svec_binary(image, {.compact_version = version}));
    int rejected = 0;
    for (size_t i = 0; i < payload.size(); ++i) {
      for (const int value : {0, 1, 0x7F, 0x80, 0xFF, payload[i] ^ 1, payload[i] ^ 0x40}) {
        std::vector<uint8_t> bad = payload;
        bad[i] = static_cast<uint8_t>(value);
        try {
          (void)parse_svec_binary(svec_file(bad, uint32_t(version)));
        } catch (const Error& e) {
          EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
          ++rejected;
        }
      }
    }
    EXPECT_GT(rejected, int(payload.size()));
  }
}

TEST(SvecCompactErrors, MessagesNameTheSection) {
  const SvecWriteOptions v2{.compact_version = 2};
  std::vector<uint8_t> payload = payload_of(to_svec_binary(square_image(), v2));
  // Counts at 12: vertex count 5 -> 9 makes the connectivity section the wrong length.
  payload[12] = 9;
  expect_error([&] { (void)parse_svec_binary(svec_file(payload, 2)); }, ErrorCode::kBadFile,
               {"level 0 connectivity", "for 9 vertices"});
  payload = payload_of(to_svec_binary(square_image(), v2));
  payload[32] = 13;  // position bits
  expect_error([&] { (void)parse_svec_binary(svec_file(payload, 2)); }, ErrorCode::kBadFile,
               {"level 0 precision", "position bits 13"});
}

TEST(SvecCompactErrors, Version3MessagesNameTheStream) {
  const std::vector<uint8_t> good = payload_of(to_svec_binary(rich_image()));
  // The level's stream length at 34 (after 12 bytes of size and level count, 20 of counts, 2 of
  // grids): one byte shorter cuts the stream, one longer takes a byte of the trailer.
  uint32_t n = 0;
  for (int k = 0; k < 4; ++k) n |= uint32_t{good[34 + k]} << (8 * k);
  auto set_length = [](std::vector<uint8_t>& p, uint32_t length) {
    for (int k = 0; k < 4; ++k) p[34 + k] = static_cast<uint8_t>(length >> (8 * k));
  };
  ASSERT_GT(n, 6u);
  std::vector<uint8_t> cut = good;
  cut.erase(cut.begin() + 38 + long(n) - 6, cut.begin() + 38 + long(n));
  set_length(cut, n - 6);
  expect_error([&] { (void)parse_svec_binary(svec_file(cut, 3)); }, ErrorCode::kBadFile,
               {"level 0 stream ", ": the coded data ends early"});
  // Five more bytes: the decoder reads at most four past the coded ones (the zeros the writer
  // may drop), so some are left over.
  std::vector<uint8_t> padded = good;
  padded.insert(padded.begin() + 38 + long(n), 5, uint8_t{0x5A});
  set_length(padded, n + 5);
  expect_error([&] { (void)parse_svec_binary(svec_file(padded, 3)); }, ErrorCode::kBadFile,
               {"unexpected bytes at the end of level 0 stream"});
  // A vertex count the stream does not hold.
  std::vector<uint8_t> counts = good;
  counts[12] = static_cast<uint8_t>(counts[12] + 1);
  expect_error([&] { (void)parse_svec_binary(svec_file(counts, 3)); }, ErrorCode::kBadFile,
               {"level 0 "});
}


// Colors are floats, so the compact form keeps them only while their grid values are exact in a
// float. The largest color it takes, beside fractional neighbors whose rounding error diffuses
// onto it, reads back exactly on the grid, and a second write gives the same bytes, at every
// color grid and in both versions. (The fuzzer found a 4x4 file whose color of 2^27 at steps of 2
// came back rounded and moved its neighbors: fuzz/corpus/svec_binary/roundtrip-large-color.svec.)
TEST(SvecCompact, LargestColorsRoundTripExactly) {
  for (const int color_bits : {-4, -1, 0, 8, 12}) {
    VectorImage image = square_image();
    std::vector<Color>& colors = image.levels[0].colors;
    const float largest = std::ldexp(1.0f, 23 - color_bits);
    colors[0] = {largest, -largest, 0.3f};
    for (size_t i = 1; i < colors.size(); ++i)
      colors[i] = {float(i) * 0.37f, 255.4f - float(i), 17.7f};
    for (const int version : {3, 2}) {
      const SvecWriteOptions options{.compact_version = version, .color_bits = color_bits};
      const std::vector<uint8_t> bytes = to_svec_binary(image, options);
      const VectorImage back = parse_svec_binary(bytes);
      EXPECT_EQ(to_svec_binary(back, options), bytes) << "color bits " << color_bits << ", version " << version;
      EXPECT_EQ(back.levels[0].colors[0].r, largest);
      for (const Color& c : back.levels[0].colors) {
        for (const float v : {c.r, c.g, c.b}) {
          const double steps = std::ldexp(double(v), color_bits);
          EXPECT_EQ(steps, std::round(steps));
        }
      }
    }
    // Twice that is refused, naming the limit.
    colors[0].r = 2 * largest;
    expect_error([&] { (void)to_svec_binary(image, {.color_bits = color_bits}); },
                 ErrorCode::kInvalidArgument,
                 {"is too large for the compact .svec form (at most " +
                  std::to_string(uint64_t(largest)) + " in magnitude"});
  }
  // The fuzzer's file: read, then refused by the compact writer (its color is 2^27 at steps of 2).
  std::ifstream in(source_dir() / "fuzz" / "corpus" / "svec_binary" / "roundtrip-large-color.svec",
                   std::ios::binary);
  const std::vector<uint8_t> file((std::istreambuf_iterator<char>(in)), {});
  ASSERT_FALSE(file.empty());
  const VectorImage found = parse_svec_binary(file);
  expect_error([&] { (void)to_svec_binary(found); }, ErrorCode::kInvalidArgument,
               {"color value 1.34218e+08 is too large"});
}

}  // namespace
}  // namespace subvec
