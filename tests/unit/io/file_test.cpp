// Whole-file reads, atomic writes, and reading/writing .svec files by path.
#include "subvec/io/file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "subvec/io/image_io.h"
#include "subvec/io/svec.h"
#include "unit/io/svec_test_util.h"

namespace subvec {
namespace {

namespace fs = std::filesystem;
using namespace svec_test;

class FileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("subvec_file_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Names in the test directory, sorted (temporary files would show up here).
  std::vector<std::string> files() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_))
      names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
  void write(const fs::path& p, const std::string& text) {
    write_file_atomic(p, std::span(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
  }
  std::string read(const fs::path& p) {
    const std::vector<uint8_t> b = read_file(p);
    return std::string(b.begin(), b.end());
  }

  fs::path dir_;
};

TEST_F(FileTest, WriteCreatesAndReplacesLeavingNoTemporaryFile) {
  write(dir_ / "a.txt", "first");
  EXPECT_EQ(read(dir_ / "a.txt"), "first");
  write(dir_ / "a.txt", "second, longer");
  EXPECT_EQ(read(dir_ / "a.txt"), "second, longer");
  write(dir_ / "empty", "");
  EXPECT_EQ(read(dir_ / "empty"), "");
  EXPECT_EQ(files(), (std::vector<std::string>{"a.txt", "empty"}));
}

TEST_F(FileTest, FailedWriteLeavesNothingBehindAndClobbersNothing) {
  fs::create_directory(dir_ / "target");  // rename() onto a directory fails
  fs::path inside = dir_ / "target" / "keep.txt";
  write(inside, "precious");
  expect_error([&] { write(dir_ / "target", "new"); }, ErrorCode::kIo, {"target", "cannot rename"});
  EXPECT_EQ(files(), (std::vector<std::string>{"target"}));
  EXPECT_EQ(read(inside), "precious");

  expect_error([&] { write(dir_ / "missing" / "x.txt", "new"); }, ErrorCode::kIo,
               {"missing/x.txt", "cannot create a temporary file"});
  EXPECT_EQ(files(), (std::vector<std::string>{"target"}));
}

TEST_F(FileTest, ReadErrorsNameThePath) {
  expect_error([&] { (void)read_file(dir_ / "nope.svec"); }, ErrorCode::kIo,
               {(dir_ / "nope.svec").string() + ": no such file"});
  expect_error([&] { (void)read_file(dir_); }, ErrorCode::kIo, {"is a directory"});
  write(dir_ / "big", std::string(100, 'x'));
  EXPECT_EQ(read_file(dir_ / "big", 100).size(), 100u);
  expect_error([&] { (void)read_file(dir_ / "big", 99); }, ErrorCode::kLimit,
               {"big", "100 bytes, over the limit of 99"});
}

TEST_F(FileTest, ReadsFilesWhoseSizeIsNotKnownInAdvance) {
  // /proc files report size 0; pipes and devices have no size at all.
  EXPECT_GT(read_file("/proc/self/status").size(), 0u);
  EXPECT_EQ(read_file("/dev/null").size(), 0u);
  expect_error([&] { (void)read_file("/dev/zero", 1000); }, ErrorCode::kLimit,
               {"/dev/zero", "over the limit of 1000"});
}

TEST(SvecFormatFor, ByExtension) {
  EXPECT_EQ(svec_format_for("a/b.svec.json"), SvecFormat::kJson);
  EXPECT_EQ(svec_format_for("b.json"), SvecFormat::kJson);
  EXPECT_EQ(svec_format_for("B.SVEC"), SvecFormat::kBinary);
  EXPECT_EQ(svec_format_for("x.y.svec"), SvecFormat::kBinary);
  expect_error([] { (void)svec_format_for("out.png"); }, ErrorCode::kInvalidArgument,
               {"out.png", "unknown extension \".png\"", ".svec or .svec.json"});
  expect_error([] { (void)svec_format_for("noext"); }, ErrorCode::kInvalidArgument,
               {"unknown extension (none)"});
}

TEST_F(FileTest, ReadAndWriteSvecByPath) {
  const VectorImage image = rich_image();
  write_svec(dir_ / "a.svec", image, SvecWriteOptions{.lossless = true});
  write_svec(dir_ / "a.svec.json", image);
  expect_same(read_svec(dir_ / "a.svec"), image);
  expect_same(read_svec(dir_ / "a.svec.json"), image);
  EXPECT_EQ(read(dir_ / "a.svec.json"), to_svec_json(image));
  // Content decides when reading, not the extension.
  fs::copy_file(dir_ / "a.svec", dir_ / "binary.json");
  expect_same(read_svec(dir_ / "binary.json"), image);
  EXPECT_EQ(files(), (std::vector<std::string>{"a.svec", "a.svec.json", "binary.json"}));
}

TEST_F(FileTest, SvecErrorsArePrefixedWithThePath) {
  write(dir_ / "junk.svec", "this is not a vector image");
  expect_error([&] { (void)read_svec(dir_ / "junk.svec"); }, ErrorCode::kBadFile,
               {(dir_ / "junk.svec").string() + ": not a .svec file: wrong magic bytes"});
  write(dir_ / "cut.svec.json", "{\"format\": \"subvec\", ");
  expect_error([&] { (void)read_svec(dir_ / "cut.svec.json"); }, ErrorCode::kBadFile,
               {"cut.svec.json: invalid JSON"});
  write(dir_ / "empty.svec", "");
  expect_error([&] { (void)read_svec(dir_ / "empty.svec"); }, ErrorCode::kBadFile,
               {"empty.svec: file is empty"});
  expect_error([&] { (void)read_svec(dir_ / "none.svec"); }, ErrorCode::kIo,
               {(dir_ / "none.svec").string() + ": no such file"});
}

// One wording for a missing file, whichever reader meets it.
TEST_F(FileTest, MissingFilesReadTheSameEverywhere) {
  for (const char* name : {"none.svec", "none.png", "none.svec.json"}) {
    const std::string expected = (dir_ / name).string() + ": no such file";
    for (int reader = 0; reader < 3; ++reader) {
      try {
        if (reader == 0) (void)read_file(dir_ / name);
        if (reader == 1) (void)read_svec(dir_ / name);
        if (reader == 2) (void)read_image(dir_ / name);
        ADD_FAILURE() << name << ": no error from reader " << reader;
      } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::kIo);
        EXPECT_EQ(std::string(e.what()), expected) << "reader " << reader;
      }
    }
  }
}

// An image in another format, given where a vector image belongs: named, with what to do.
TEST_F(FileTest, ReadSvecNamesOtherImageFormats) {
  Image8 pixels;
  pixels.width = 2, pixels.height = 1, pixels.channels = 3;
  pixels.pixels.assign(6, 200);
  write_png(dir_ / "photo.png", pixels);
  const std::string path = (dir_ / "photo.png").string();
  expect_error([&] { (void)read_svec(dir_ / "photo.png"); }, ErrorCode::kBadFile,
               {path + ": a PNG image, not a .svec or .svec.json file; vectorize it first: "
                       "subvec vectorize " + path + " -o photo.svec"});
  using namespace std::string_literals;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"\xff\xd8\xff\xe0 jfif"s, "a JPEG image, not a .svec or .svec.json file; vectorize it first"},
      {"RIFF\x10\0\0\0WEBPVP8 "s, "a WebP image"},
      {"II*\0\x08\0\0\0"s, "a TIFF image"},
      {"BM\x3a\0\0\0"s, "a BMP image"},
      {"GIF89a\x01\0"s, "a GIF image, not a .svec or .svec.json file"},
      {"%PDF-1.4\n"s, "a PDF file, not a .svec or .svec.json file; subvec writes PDF"},
      {"<?xml version=\"1.0\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\"/>"s,
       "an SVG file, not a .svec or .svec.json file; subvec writes SVG (render -o out.svg) but cannot "
       "read it"},
  };
  for (const auto& [bytes, expected] : cases) {
    write(dir_ / "x.svec", bytes);
    expect_error([&] { (void)read_svec(dir_ / "x.svec"); }, ErrorCode::kBadFile,
                 {(dir_ / "x.svec").string() + ": " + expected});
  }
  // GIF, PDF and SVG are no input of vectorize: no such suggestion.
  write(dir_ / "x.svec", "%PDF-1.4\n");
  try {
    (void)read_svec(dir_ / "x.svec");
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).find("vectorize"), std::string::npos) << e.what();
  }
}

TEST_F(FileTest, WriteSvecRefusesInvalidImagesAndUnknownExtensions) {
  VectorImage bad = square_image();
  bad.levels[0].positions[4] = {2, 9};
  expect_error([&] { write_svec(dir_ / "bad.svec", bad); }, ErrorCode::kInvalidMesh,
               {"bad.svec", "vertex 4", "outside the image"});
  expect_error([&] { write_svec(dir_ / "out.txt", square_image()); }, ErrorCode::kInvalidArgument,
               {"\".txt\""});
  EXPECT_TRUE(files().empty());
}

}  // namespace
}  // namespace subvec
