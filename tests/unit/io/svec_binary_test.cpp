// The .svec binary reader and writer, version 1 (lossless): exact round trips, JSON <-> binary
// identity, the documented byte layout (crafted by hand here, in stored zstd blocks), and every way
// a file can be cut, corrupted or lie about its sizes. The compact version 2 is tested in
// svec_compact_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "subvec/io/svec.h"
#include "unit/io/svec_test_util.h"

namespace subvec {
namespace {

using namespace svec_test;

const SvecWriteOptions kLossless{.lossless = true};

void expect_binary_error(const std::vector<uint8_t>& bytes, ErrorCode code,
                         const std::vector<std::string>& parts) {
  expect_error([&] { (void)parse_svec_binary(bytes); }, code, parts);
}

uint64_t read_u64(const std::vector<uint8_t>& b, size_t at) {
  uint64_t v = 0;
  for (int k = 0; k < 8; ++k) v |= uint64_t{b[at + k]} << (8 * k);
  return v;
}

TEST(SvecBinary, RoundTripIsExact) {
  const VectorImage image = rich_image();
  const std::vector<uint8_t> bytes = to_svec_binary(image, kLossless);
  expect_same(parse_svec_binary(bytes), image);
  EXPECT_EQ(to_svec_binary(image, kLossless), bytes);  // deterministic
}

TEST(SvecBinary, HeaderIsAsDocumented) {
  const std::vector<uint8_t> bytes = to_svec_binary(square_image(), kLossless);
  ASSERT_GT(bytes.size(), 32u);
  const std::vector<uint8_t> magic(bytes.begin(), bytes.begin() + 8);
  EXPECT_EQ(magic, (std::vector<uint8_t>{0x53, 0x55, 0x42, 0x56, 0x45, 0x43, 0x00, 0x1A}));
  EXPECT_EQ(read_u64(bytes, 8), 1u);  // version 1, flags 0
  EXPECT_EQ(read_u64(bytes, 16), square_payload().b.size());
  EXPECT_EQ(read_u64(bytes, 24), bytes.size() - 32);
  // A zstd frame follows (its magic number, little-endian 0xFD2FB528).
  EXPECT_EQ(bytes[32], 0x28);
  EXPECT_EQ(bytes[35], 0xFD);
}

TEST(SvecBinary, HandCraftedFileFollowingTheDocsReads) {
  // The payload laid out field by field from docs/format.md, in stored (uncompressed) zstd blocks.
  expect_same(parse_svec_binary(svec_file(square_payload().b)), square_image());
}

TEST(SvecBinary, JsonAndBinaryConvertWithoutLoss) {
  const std::string text = to_svec_json(rich_image());
  const std::vector<uint8_t> bytes = to_svec_binary(parse_svec_json(text), kLossless);
  EXPECT_EQ(to_svec_json(parse_svec_binary(bytes)), text);
  EXPECT_EQ(to_svec_binary(parse_svec_json(to_svec_json(parse_svec_binary(bytes))), kLossless), bytes);
  for (const std::string& block : doc_examples()) {
    EXPECT_EQ(to_svec_json(parse_svec_binary(to_svec_binary(parse_svec_json(block), kLossless))), block);
  }
}

// ---- bad inputs --------------------------------------------------------------------------------

TEST(SvecBinaryErrors, WrongMagicVersionAndFlags) {
  std::vector<uint8_t> bytes = to_svec_binary(square_image(), kLossless);
  std::vector<uint8_t> bad = bytes;
  bad[1] = 'V';
  expect_binary_error(bad, ErrorCode::kBadFile, {"not a .svec file: wrong magic bytes (53 56"});
  expect_binary_error({}, ErrorCode::kBadFile, {"wrong magic bytes"});
  const std::string text = "{\"format\": \"subvec\"}";
  expect_binary_error(std::vector<uint8_t>(text.begin(), text.end()), ErrorCode::kBadFile,
                      {"wrong magic bytes (7b 22"});
  expect_binary_error(svec_file(square_payload().b, 7), ErrorCode::kBadFile,
                      {"unsupported .svec version 7 (this build reads 1, 2 and 3)"});
  expect_binary_error(svec_file(square_payload().b, 1, 4), ErrorCode::kBadFile,
                      {"unsupported .svec flags 4"});
}

TEST(SvecBinaryErrors, EveryTruncationIsReportedNeverCrashes) {
  const std::vector<uint8_t> bytes = to_svec_binary(rich_image(), kLossless);
  for (size_t n = 0; n < bytes.size(); ++n) {
    SCOPED_TRACE("first " + std::to_string(n) + " bytes");
    const std::vector<uint8_t> cut(bytes.begin(), bytes.begin() + long(n));
    const char* expected = n < 8 ? "" : n < 32 ? "truncated .svec header" : "truncated .svec file";
    expect_binary_error(cut, ErrorCode::kBadFile, {expected});
  }
}

TEST(SvecBinaryErrors, TruncatedOrCorruptZstdFrame) {
  // A frame cut short, with the header's frame size matching the cut: zstd itself must notice.
  std::vector<uint8_t> frame = raw_zstd_frame(square_payload().b);
  frame.resize(frame.size() - 10);
  Bytes file;
  file.raw({'S', 'U', 'B', 'V', 'E', 'C', 0x00, 0x1A}).u32(1).u32(0);
  file.u64(square_payload().b.size()).u64(frame.size()).raw(frame);
  expect_binary_error(file.b, ErrorCode::kBadFile, {"truncated zstd frame"});

  // A flipped bit in a compressed frame: the frame checksum (or the decoder) catches it.
  std::vector<uint8_t> bytes = to_svec_binary(rich_image(), kLossless);
  bytes[bytes.size() - 2] ^= 0x10;
  expect_binary_error(bytes, ErrorCode::kBadFile, {"corrupt zstd frame"});
}

TEST(SvecBinaryErrors, SizesThatLie) {
  const std::vector<uint8_t> good = svec_file(square_payload().b);
  std::vector<uint8_t> bad = good;
  bad[16 + 5] = 1;  // payload size 2^40
  expect_binary_error(bad, ErrorCode::kLimit,
                      {"declared payload of 1099511628052 bytes", "over the limit"});
  bad = good;
  bad[16] += 1;  // one byte more than the frame holds
  expect_binary_error(bad, ErrorCode::kBadFile, {"zstd frame holds", "header declares"});
  bad = good;
  bad[24] += 1;  // frame size past the end of the file
  expect_binary_error(bad, ErrorCode::kBadFile, {"truncated .svec file", "zstd frame"});
  bad = good;
  bad.push_back(0);
  expect_binary_error(bad, ErrorCode::kBadFile, {"1 unexpected bytes after the zstd frame"});
}

TEST(SvecBinaryErrors, PayloadCountsThatLie) {
  Bytes p;
  p.i32(4).i32(4).u32(1).u32(0xFFFFFFFF).u32(0).u32(0).u32(0).u32(0);  // 4 billion vertices
  expect_binary_error(svec_file(p.b), ErrorCode::kLimit,
                      {"level 0 vertices: count 4294967295 is over the limit of 67108864"});
  p = {};
  p.i32(4).i32(4).u32(1).u32(1000).u32(5).u32(4).u32(0).u32(0);  // 1000 vertices, few bytes
  expect_binary_error(svec_file(p.b), ErrorCode::kBadFile,
                      {"truncated payload while reading level 0 vertices", "1000 declared"});
  p = {};
  p.i32(4).i32(4).u32(65);  // levels
  expect_binary_error(svec_file(p.b), ErrorCode::kLimit,
                      {"levels: count 65 is over the limit of 64"});

  // The square payload cut inside its triangle colors.
  std::vector<uint8_t> cut = square_payload().b;
  cut.resize(cut.size() - 8 - 4 * 4);
  expect_binary_error(svec_file(cut), ErrorCode::kBadFile,
                      {"truncated payload while reading level 0 triangle colors"});
  std::vector<uint8_t> longer = square_payload().b;
  longer.push_back(0);
  expect_binary_error(svec_file(longer), ErrorCode::kBadFile,
                      {"1 unexpected bytes after the payload's metadata"});
}

TEST(SvecBinaryErrors, NonFiniteValuesAndBadIndices) {
  // Offsets into square_payload(): 12 bytes of size and level count, 20 of counts.
  const size_t positions = 32, colors = positions + 5 * 16, triangles = colors + 5 * 12;
  auto patched = [](size_t at, const std::vector<uint8_t>& value) {
    std::vector<uint8_t> p = square_payload().b;
    std::copy(value.begin(), value.end(), p.begin() + long(at));
    return svec_file(p);
  };
  expect_binary_error(patched(positions + 16, Bytes().f64(std::nan("")).b), ErrorCode::kInvalidMesh,
                      {"level 0: vertex 1 position (nan, 0) is not finite"});
  expect_binary_error(
      patched(colors + 2 * 12 + 4, Bytes().f32(std::numeric_limits<float>::infinity()).b),
      ErrorCode::kInvalidMesh, {"level 0: color 2 (0, inf, 255) is not finite"});
  expect_binary_error(patched(triangles + 2 * 12 + 8, Bytes().i32(99).b), ErrorCode::kInvalidMesh,
                      {"level 0: triangle 2 refers to vertex 99, out of range (5 vertices)"});
  expect_binary_error(patched(triangles + 4 * 12 + 4, Bytes().i32(-3).b), ErrorCode::kInvalidMesh,
                      {"level 0: triangle_colors 0 refers to color -3, out of range (5 colors)"});
}

}  // namespace
}  // namespace subvec
