// The bad-file corpus tests/data/bad (written by tests/bad-input/make_files.py): every file must be
// rejected by read_svec with the listed error code and a one-line message naming the problem.
#include <gtest/gtest.h>

#include <set>

#include "subvec/io/svec.h"
#include "unit/io/svec_test_util.h"

namespace subvec {
namespace {

using namespace svec_test;

struct BadFile {
  const char* name;
  ErrorCode code;
  std::vector<std::string> message_parts;
};

const std::vector<BadFile>& corpus() {
  using E = ErrorCode;
  static const std::vector<BadFile> files = {
      // Indices out of range.
      {"index-triangle.svec.json",
       E::kInvalidMesh,
       {"level 0: triangle 1 refers to vertex 9, out of range (5 vertices)"}},
      {"index-triangle-colors.svec.json",
       E::kInvalidMesh,
       {"level 0: triangle_colors 2 refers to color 7, out of range (5 colors)"}},
      {"index-feature.svec.json",
       E::kInvalidMesh,
       {"level 0: feature 0 (id 3) refers to vertex 12, out of range (5 vertices)"}},
      {"index-out-of-range.svec",
       E::kInvalidMesh,
       {"level 0: triangle 2 refers to vertex -7, out of range"}},
      // NaN and infinity.
      {"nan.svec.json", E::kBadFile, {"invalid JSON", "levels[0].vertices[4]", "line 8"}},
      {"huge-number.svec.json", E::kBadFile, {"levels[0].vertices[4][1]", "1e400"}},
      {"nan-position.svec", E::kInvalidMesh, {"level 0: vertex 1 position (nan, 0) is not finite"}},
      // Meshes that do not tile the image.
      {"gap.svec.json",
       E::kInvalidMesh,
       {"level 0: edge (1, 4)", "does not lie on the image border", "gap"}},
      {"overlap.svec.json",
       E::kInvalidMesh,
       {"level 0: triangles overlap around vertex 0 (2, 2)", "4*pi", "needs 2*pi"}},
      {"double-cover.svec.json",
       E::kInvalidMesh,
       {"level 0: the triangles cover an area of 32 but the image has 16"}},
      {"flipped.svec.json",
       E::kInvalidMesh,
       {"level 0: triangle 1 (1, 4, 5) is flipped or degenerate (signed area -1)"}},
      {"inconsistent-orientation.svec.json",
       E::kInvalidMesh,
       {"level 0: triangles 0 and 1 are oriented inconsistently across edge (1, 4)"}},
      {"outside.svec.json",
       E::kInvalidMesh,
       {"level 0: vertex 4 position (2, 4.5) is outside the image [0, 4] x [0, 4]"}},
      {"unused-vertex.svec.json",
       E::kInvalidMesh,
       {"level 0: vertex 5 (1, 1) is used by no triangle"}},
      // Features and colors.
      {"not-a-chain.svec.json",
       E::kInvalidMesh,
       {"level 0: feature 0 (id 0): (1, 3) is not an edge of the mesh"}},
      {"feature-on-border.svec.json",
       E::kInvalidMesh,
       {"level 0: feature 0 (id 0): (0, 1) lies on the image border"}},
      {"color-jump-without-tear.svec.json",
       E::kInvalidMesh,
       {"level 0: edge (0, 4) is not a tear but triangles 0 and 3 use different colors at vertex "
        "0"}},
      // Structure.
      {"unknown-key.svec.json", E::kBadFile, {"levels[0]: unknown key \"triangle_color\""}},
      {"duplicate-key.svec.json", E::kBadFile, {"duplicate key \"height\""}},
      {"wrong-type.svec.json", E::kBadFile, {"width: expected an integer, got a string"}},
      {"absurd-size.svec.json", E::kLimit, {"width 100000000 is over the limit of 65536"}},
      {"wrong-version.svec.json",
       E::kBadFile,
       {"unsupported .svec.json version 3 (this build reads 1 and 2)"}},
      {"truncated.svec.json", E::kBadFile, {"invalid JSON", "line 9"}},
      // Binary containers.
      {"wrong-magic.svec", E::kBadFile, {"not a .svec file: wrong magic bytes (53 55 42 56 45 58"}},
      {"wrong-version.svec", E::kBadFile, {"unsupported .svec version 7 (this build reads 1, 2 and 3)"}},
      {"unknown-flags.svec", E::kBadFile, {"unsupported .svec flags 4"}},
      {"object-strokes-without-objects.svec", E::kBadFile, {"flag 2 (object strokes) is set without flag 1"}},
      {"truncated-header.svec",
       E::kBadFile,
       {"truncated .svec header: 20 bytes, the header needs 32"}},
      {"truncated.svec",
       E::kBadFile,
       {"truncated .svec file", "292-byte zstd frame", "262 bytes follow"}},
      {"truncated-zstd.svec", E::kBadFile, {"truncated zstd frame", "246 of 276 payload bytes"}},
      {"absurd-payload-size.svec",
       E::kLimit,
       {"declared payload of 1125899906842624 bytes", "limit"}},
      {"absurd-count.svec", E::kLimit, {"level 0 triangles: count 4294967280 is over the limit"}},
      {"truncated-payload.svec",
       E::kBadFile,
       {"truncated payload while reading level 0 triangle colors"}},
      {"trailing-payload-bytes.svec", E::kBadFile, {"2 unexpected bytes after the payload"}},
      {"trailing-file-bytes.svec", E::kBadFile, {"1 unexpected bytes after the zstd frame"}},
      // Compact (version 2) payloads.
      {"compact-bad-operations.svec",
       E::kBadFile,
       {"level 0 connectivity: byte 0 is not three operations"}},
      {"compact-bad-precision.svec", E::kBadFile, {"level 0 precision: position bits 13"}},
      {"compact-color-count.svec",
       E::kBadFile,
       {"level 0 colors: the tears give 5 color values, but 6 are declared"}},
      {"compact-trailing-section-bytes.svec",
       E::kBadFile,
       {"1 unexpected bytes at the end of level 0 positions"}},
  };
  return files;
}

std::filesystem::path bad_dir() { return source_dir() / "tests" / "data" / "bad"; }

TEST(BadFiles, EachIsRejectedWithAMessageNamingTheProblem) {
  for (const BadFile& file : corpus()) {
    SCOPED_TRACE(file.name);
    const std::filesystem::path path = bad_dir() / file.name;
    std::vector<std::string> parts = file.message_parts;
    parts.push_back(path.string() + ": ");  // read_svec names the file first
    expect_error([&] { (void)read_svec(path); }, file.code, parts);
  }
}

TEST(BadFiles, EveryFileInTheCorpusIsListed) {
  std::set<std::string> listed;
  for (const BadFile& file : corpus()) listed.insert(file.name);
  for (const auto& entry : std::filesystem::directory_iterator(bad_dir())) {
    const std::string name = entry.path().filename().string();
    if (!entry.is_regular_file() || entry.path().extension() == ".py") continue;
    EXPECT_TRUE(listed.count(name)) << name << " is in tests/data/bad but not in this test";
  }
}

}  // namespace
}  // namespace subvec
