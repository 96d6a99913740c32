#include "subvec/io/image_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "subvec/core/error.h"

namespace subvec {
namespace {

namespace fs = std::filesystem;

class ImageIo : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("subvec_image_io_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path dir_;
};

void write_bytes(const fs::path& path, const std::vector<uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

std::vector<uint8_t> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A minimal PNG encoder (deflate "stored" blocks, no compression), independent of OpenCV, to make
// inputs of every pixel layout: gray, gray + alpha, RGB, RGBA at 8 or 16 bits.
class PngWriter {
 public:
  static std::vector<uint8_t> encode(uint32_t width, uint32_t height, uint8_t bit_depth,
                                     uint8_t color_type, const std::vector<uint8_t>& rows) {
    std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    std::vector<uint8_t> ihdr;
    put32(ihdr, width);
    put32(ihdr, height);
    ihdr.insert(ihdr.end(), {bit_depth, color_type, 0, 0, 0});
    chunk(png, "IHDR", ihdr);
    chunk(png, "IDAT", zlib_stored(rows));
    chunk(png, "IEND", {});
    return png;
  }

 private:
  static void put32(std::vector<uint8_t>& out, uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8) out.push_back(uint8_t(v >> shift));
  }
  static uint32_t crc32(const uint8_t* data, size_t n, uint32_t crc = 0xffffffffu) {
    for (size_t i = 0; i < n; ++i) {
      crc ^= data[i];
      for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
    }
    return crc;
  }
  static void chunk(std::vector<uint8_t>& png, const char* type, const std::vector<uint8_t>& data) {
    put32(png, uint32_t(data.size()));
    std::vector<uint8_t> body(type, type + 4);
    body.insert(body.end(), data.begin(), data.end());
    png.insert(png.end(), body.begin(), body.end());
    put32(png, crc32(body.data(), body.size()) ^ 0xffffffffu);
  }
  static std::vector<uint8_t> zlib_stored(const std::vector<uint8_t>& raw) {
    std::vector<uint8_t> z = {0x78, 0x01};
    size_t pos = 0;
    do {
      const size_t n = std::min<size_t>(65535, raw.size() - pos);
      const bool last = pos + n == raw.size();
      z.push_back(last ? 1 : 0);
      z.push_back(uint8_t(n & 0xff));
      z.push_back(uint8_t(n >> 8));
      z.push_back(uint8_t(~n & 0xff));
      z.push_back(uint8_t((~n >> 8) & 0xff));
      z.insert(z.end(), raw.begin() + long(pos), raw.begin() + long(pos + n));
      pos += n;
    } while (pos < raw.size());
    uint32_t a = 1, b = 0;  // Adler-32
    for (uint8_t v : raw) {
      a = (a + v) % 65521;
      b = (b + a) % 65521;
    }
    put32(z, b << 16 | a);
    return z;
  }
};

// Rows with a leading filter byte 0 (none) each.
std::vector<uint8_t> rows_of(int width, int height, int bytes_per_pixel,
                             const std::vector<uint8_t>& pixel) {
  std::vector<uint8_t> rows;
  for (int y = 0; y < height; ++y) {
    rows.push_back(0);
    for (int x = 0; x < width; ++x)
      rows.insert(rows.end(), pixel.begin(), pixel.begin() + bytes_per_pixel);
  }
  return rows;
}

Image8 pattern(int w, int h, int channels) {
  Image8 img(w, h, channels);
  for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = uint8_t((i * 37) % 251);
  return img;
}

template <typename F>
ErrorCode error_of(F&& f, std::string* message = nullptr) {
  try {
    f();
  } catch (const Error& e) {
    if (message) *message = e.what();
    return e.code();
  }
  ADD_FAILURE() << "expected subvec::Error";
  return ErrorCode::kInvalidArgument;
}

TEST_F(ImageIo, RgbRoundTrip) {
  const Image8 img = pattern(13, 7, 3);
  write_png(dir_ / "a.png", img);
  const Image8 back = read_image(dir_ / "a.png");
  EXPECT_EQ(back.width, 13);
  EXPECT_EQ(back.height, 7);
  EXPECT_EQ(back.channels, 3);
  EXPECT_EQ(back.pixels, img.pixels);
}

TEST_F(ImageIo, RgbaIsWrittenWithAlphaAndReadOverBlack) {
  Image8 img(2, 1, 4);
  img.pixels = {200, 100, 50, 255, 200, 100, 50, 51};  // opaque, then alpha 0.2
  write_png(dir_ / "a.png", img);
  const std::vector<uint8_t> bytes = read_bytes(dir_ / "a.png");
  ASSERT_GT(bytes.size(), 26u);
  EXPECT_EQ(bytes[25], 6) << "PNG colour type should be RGBA";
  const Image8 back = read_image(dir_ / "a.png");
  EXPECT_EQ(back.channels, 3);
  EXPECT_EQ(back.pixels, (std::vector<uint8_t>{200, 100, 50, 40, 20, 10}));
}

TEST_F(ImageIo, RgbPngHasNoAlpha) {
  write_png(dir_ / "a.png", pattern(3, 3, 3));
  EXPECT_EQ(read_bytes(dir_ / "a.png")[25], 2) << "PNG colour type should be RGB";
}

TEST_F(ImageIo, GrayIsExpanded) {
  write_bytes(dir_ / "g.png", PngWriter::encode(3, 2, 8, 0, rows_of(3, 2, 1, {77})));
  const Image8 back = read_image(dir_ / "g.png");
  ASSERT_EQ(back.width, 3);
  ASSERT_EQ(back.height, 2);
  for (uint8_t v : back.pixels) EXPECT_EQ(v, 77);
}

TEST_F(ImageIo, GrayAlphaIsCompositedOverBlack) {
  write_bytes(dir_ / "ga.png", PngWriter::encode(2, 2, 8, 4, rows_of(2, 2, 2, {200, 128})));
  const Image8 back = read_image(dir_ / "ga.png");
  for (uint8_t v : back.pixels) EXPECT_EQ(v, 100);  // 200 * 128 / 255 = 100.4
}

TEST_F(ImageIo, SixteenBitIsScaledDown) {
  // RGB 16-bit big-endian: 65535, 32896 (= 128 * 257), 0.
  write_bytes(dir_ / "d.png",
              PngWriter::encode(2, 2, 16, 2, rows_of(2, 2, 6, {0xff, 0xff, 0x80, 0x80, 0, 0})));
  const Image8 back = read_image(dir_ / "d.png");
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(back.pixels[size_t(i) * 3 + 0], 255);
    EXPECT_EQ(back.pixels[size_t(i) * 3 + 1], 128);
    EXPECT_EQ(back.pixels[size_t(i) * 3 + 2], 0);
  }
}

TEST_F(ImageIo, SixteenBitRgbaIsCompositedOverBlack) {
  // R = G = B = 65535, alpha = 32896 (128/255 after scaling).
  write_bytes(dir_ / "d.png",
              PngWriter::encode(
                  1, 1, 16, 6, rows_of(1, 1, 8, {0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x80, 0x80})));
  const Image8 back = read_image(dir_ / "d.png");
  EXPECT_EQ(back.pixels, (std::vector<uint8_t>{128, 128, 128}));
}

TEST_F(ImageIo, MissingFile) {
  std::string msg;
  EXPECT_EQ(error_of([&] { read_image(dir_ / "nope.png"); }, &msg), ErrorCode::kIo);
  EXPECT_NE(msg.find("nope.png"), std::string::npos) << msg;
  EXPECT_NE(msg.find("no such file"), std::string::npos) << msg;
}

TEST_F(ImageIo, DirectoryIsRejected) {
  std::string msg;
  EXPECT_EQ(error_of([&] { read_image(dir_); }, &msg), ErrorCode::kIo);
  EXPECT_NE(msg.find("directory"), std::string::npos) << msg;
}

TEST_F(ImageIo, EmptyAndGarbageFiles) {
  write_bytes(dir_ / "empty.png", {});
  EXPECT_EQ(error_of([&] { read_image(dir_ / "empty.png"); }), ErrorCode::kBadFile);
  write_bytes(dir_ / "junk.png", {'h', 'e', 'l', 'l', 'o', ' ', 'w', 'o', 'r', 'l', 'd'});
  std::string msg;
  EXPECT_EQ(error_of([&] { read_image(dir_ / "junk.png"); }, &msg), ErrorCode::kBadFile);
  EXPECT_EQ(msg, "cannot read image '" + (dir_ / "junk.png").string() +
                     "': file is truncated or not an image");
}

TEST_F(ImageIo, TruncatedPng) {
  write_png(dir_ / "a.png", pattern(64, 64, 3));
  std::vector<uint8_t> bytes = read_bytes(dir_ / "a.png");
  bytes.resize(bytes.size() / 2);
  write_bytes(dir_ / "cut.png", bytes);
  std::string msg;
  EXPECT_EQ(error_of([&] { read_image(dir_ / "cut.png"); }, &msg), ErrorCode::kBadFile);
  EXPECT_NE(msg.find("truncated"), std::string::npos) << msg;
}

TEST_F(ImageIo, CorruptedPng) {
  write_png(dir_ / "a.png", pattern(64, 64, 3));
  std::vector<uint8_t> bytes = read_bytes(dir_ / "a.png");
  bytes[bytes.size() / 2] ^= 0x5a;  // inside IDAT: its CRC no longer matches
  write_bytes(dir_ / "flip.png", bytes);
  EXPECT_EQ(error_of([&] { read_image(dir_ / "flip.png"); }), ErrorCode::kBadFile);
}

TEST_F(ImageIo, TruncatedJpeg) {
  // SOI, a JFIF APP0, a baseline SOF0 for 8x8, then the stream stops before any scan.
  write_bytes(dir_ / "cut.jpg",
              {0xff, 0xd8, 0xff, 0xe0, 0x00, 0x10, 'J',  'F', 'I', 'F', 0, 1, 1, 0, 0,    1, 0,
               1,    0,    0,    0xff, 0xc0, 0x00, 0x0b, 8,   0,   8,   0, 8, 1, 1, 0x11, 0});
  EXPECT_EQ(error_of([&] { read_image(dir_ / "cut.jpg"); }), ErrorCode::kBadFile);
}

TEST_F(ImageIo, PixelLimitIsCheckedFromThePngHeader) {
  // Only a signature and an IHDR claiming 100000 x 100000: the limit must fire before decoding.
  std::vector<uint8_t> png = PngWriter::encode(100000, 100000, 8, 2, {});
  png.resize(33);
  write_bytes(dir_ / "huge.png", png);
  std::string msg;
  EXPECT_EQ(error_of([&] { read_image(dir_ / "huge.png"); }, &msg), ErrorCode::kLimit);
  EXPECT_NE(msg.find("100000x100000"), std::string::npos) << msg;
  // And a decoded image over a caller's limit.
  write_png(dir_ / "a.png", pattern(10, 10, 3));
  EXPECT_EQ(error_of([&] { read_image(dir_ / "a.png", 99); }), ErrorCode::kLimit);
  EXPECT_NO_THROW(read_image(dir_ / "a.png", 100));
}

TEST_F(ImageIo, PixelLimitIsCheckedFromTheJpegHeader) {
  write_bytes(dir_ / "huge.jpg", {0xff, 0xd8, 0xff, 0xc0, 0x00, 0x11, 8, 0xff, 0xff, 0xff, 0xff,
                                  3,    1,    0x11, 0,    2,    0x11, 0, 3,    0x11, 0});
  EXPECT_EQ(error_of([&] { read_image(dir_ / "huge.jpg"); }), ErrorCode::kLimit);
}

TEST_F(ImageIo, WriteRejectsMalformedImages) {
  Image8 bad(4, 4, 3);
  bad.pixels.resize(10);
  EXPECT_EQ(error_of([&] { write_png(dir_ / "bad.png", bad); }), ErrorCode::kInvalidArgument);
  EXPECT_EQ(error_of([&] { write_png(dir_ / "bad.png", Image8(2, 2, 2)); }),
            ErrorCode::kInvalidArgument);
  EXPECT_FALSE(fs::exists(dir_ / "bad.png"));
}

TEST_F(ImageIo, WriteIntoMissingDirectoryFails) {
  EXPECT_EQ(error_of([&] { write_png(dir_ / "no" / "such" / "a.png", pattern(2, 2, 3)); }),
            ErrorCode::kIo);
}

}  // namespace
}  // namespace subvec
