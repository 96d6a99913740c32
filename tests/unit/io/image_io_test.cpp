#include "subvec/io/image_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
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
                     "': not a PNG, JPEG, WebP, TIFF or BMP file");
  // Formats OpenCV could decode but subvec does not take (a binary PPM here).
  const std::string ppm = "P6\n2 2\n255\n" + std::string(12, 'x');
  write_bytes(dir_ / "a.ppm", std::vector<uint8_t>(ppm.begin(), ppm.end()));
  EXPECT_EQ(error_of([&] { read_image(dir_ / "a.ppm"); }), ErrorCode::kBadFile);
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

// ---- every format, through OpenCV's encoders ---------------------------------------------------

// Encodes a BGR(A) / gray OpenCV image with imencode (extension picks the format).
std::vector<uint8_t> encode(const std::string& ext, const cv::Mat& m,
                            const std::vector<int>& params = {}) {
  std::vector<uint8_t> bytes;
  EXPECT_TRUE(cv::imencode(ext, m, bytes, params)) << ext;
  return bytes;
}

// A smooth 24 x 16 BGR picture (JPEG keeps it close).
cv::Mat3b smooth_bgr() {
  cv::Mat3b m(16, 24);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 24; ++x)
      m(y, x) = cv::Vec3b(uint8_t(40 + 6 * y), uint8_t(200 - 5 * x), uint8_t(60 + 3 * (x + y)));
  return m;
}

// The same picture as we read it: RGB.
std::vector<uint8_t> rgb_of(const cv::Mat3b& m) {
  std::vector<uint8_t> out;
  for (int y = 0; y < m.rows; ++y)
    for (int x = 0; x < m.cols; ++x) out.insert(out.end(), {m(y, x)[2], m(y, x)[1], m(y, x)[0]});
  return out;
}

TEST_F(ImageIo, EveryFormatReadsAsRgb) {
  const cv::Mat3b bgr = smooth_bgr();
  const std::vector<uint8_t> expected = rgb_of(bgr);
  struct Case {
    const char* name;
    std::vector<uint8_t> bytes;
    double max_error;  // largest sample difference
  };
  const Case cases[] = {
      {"a.png", encode(".png", bgr), 0},
      {"a.bmp", encode(".bmp", bgr), 0},
      {"a.tif", encode(".tiff", bgr), 0},
      {"a.webp", encode(".webp", bgr, {cv::IMWRITE_WEBP_QUALITY, 101}), 0},  // > 100: lossless
      {"a.jpg", encode(".jpg", bgr, {cv::IMWRITE_JPEG_QUALITY, 98}), 12},
  };
  for (const Case& c : cases) {
    write_bytes(dir_ / c.name, c.bytes);
    const Image8 back = read_image(dir_ / c.name);
    ASSERT_EQ(back.width, 24) << c.name;
    ASSERT_EQ(back.height, 16) << c.name;
    ASSERT_EQ(back.channels, 3) << c.name;
    double worst = 0;
    for (size_t i = 0; i < expected.size(); ++i)
      worst = std::max(worst, std::abs(double(back.pixels[i]) - expected[i]));
    EXPECT_LE(worst, c.max_error) << c.name;
  }
}

TEST_F(ImageIo, GrayJpegBmpAndTiffAreExpanded) {
  cv::Mat1b gray(8, 8, uint8_t{90});
  for (const char* ext : {".jpg", ".bmp", ".tiff", ".webp"}) {
    const std::string name = std::string("g") + ext;
    write_bytes(dir_ / name, encode(ext, gray, {cv::IMWRITE_WEBP_QUALITY, 101}));
    const Image8 back = read_image(dir_ / name);
    ASSERT_EQ(back.pixels.size(), 8u * 8 * 3) << ext;
    for (uint8_t v : back.pixels) EXPECT_NEAR(v, 90, 1) << ext;
  }
}

TEST_F(ImageIo, SixteenBitTiffIsRoundedNotTruncated) {
  // B, G, R = 1000, 32768, 65535: 3.89, 127.5 and 255 on the 8-bit scale.
  const cv::Mat color(3, 2, CV_16UC3, cv::Scalar(1000, 32768, 65535));
  write_bytes(dir_ / "c.tif", encode(".tiff", color));
  const Image8 back = read_image(dir_ / "c.tif");
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(back.pixels[size_t(i) * 3 + 0], 255);
    EXPECT_EQ(back.pixels[size_t(i) * 3 + 1], 128);
    EXPECT_EQ(back.pixels[size_t(i) * 3 + 2], 4);
  }
  const cv::Mat gray(2, 2, CV_16UC1, cv::Scalar(40000));  // 155.65
  write_bytes(dir_ / "g.tif", encode(".tiff", gray));
  for (uint8_t v : read_image(dir_ / "g.tif").pixels) EXPECT_EQ(v, 156);
}

TEST_F(ImageIo, FloatTiffIsTakenAsZeroToOne) {
  // One channel: OpenCV stores 3-channel float TIFFs with lossy LogLuv compression.
  cv::Mat1f gray(2, 2);
  gray << 0.25f, 0.4f, 1.0f, 2.0f;  // 63.75, 102, 255, and over-range clamped to 255
  write_bytes(dir_ / "f.tif", encode(".tiff", gray));
  const Image8 back = read_image(dir_ / "f.tif");
  EXPECT_EQ(back.pixels,
            (std::vector<uint8_t>{64, 64, 64, 102, 102, 102, 255, 255, 255, 255, 255, 255}));
}

TEST_F(ImageIo, AlphaInTiffAndWebpIsCompositedOverBlack) {
  const cv::Mat4b bgra(4, 4, cv::Vec4b(50, 100, 200, 51));  // alpha 0.2
  for (const char* ext : {".tiff", ".webp", ".png"}) {
    const std::string name = std::string("a") + ext;
    write_bytes(dir_ / name, encode(ext, bgra, {cv::IMWRITE_WEBP_QUALITY, 101}));
    const Image8 back = read_image(dir_ / name);
    ASSERT_EQ(back.channels, 3);
    EXPECT_EQ(std::vector<uint8_t>(back.pixels.begin(), back.pixels.begin() + 3),
              (std::vector<uint8_t>{40, 20, 10}))
        << ext;
  }
}

// OpenCV cannot write CMYK JPEGs: tests/data/images/cmyk.jpg comes from make_cmyk_jpeg.c there
// (Adobe-style inverted CMYK, four flat 8 x 8 blocks).
TEST_F(ImageIo, CmykJpegIsConvertedToRgb) {
  const Image8 img =
      read_image(fs::path(SUBVEC_SOURCE_DIR) / "tests" / "data" / "images" / "cmyk.jpg");
  ASSERT_EQ(img.width, 16);
  ASSERT_EQ(img.height, 16);
  const struct {
    int x, y;
    std::array<int, 3> rgb;
  } blocks[] = {
      {4, 4, {255, 0, 0}}, {12, 4, {0, 255, 0}}, {4, 12, {0, 0, 255}}, {12, 12, {127, 127, 127}}};
  for (const auto& b : blocks) {
    const uint8_t* p = img.row(b.y) + 3 * b.x;
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(p[k], b.rgb[k], 4) << "block at " << b.x << "," << b.y << " channel " << k;
  }
}

TEST_F(ImageIo, TruncatedFilesInEveryFormat) {
  cv::Mat3b noise(64, 64);
  cv::RNG rng(5);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
  for (const char* ext : {".png", ".jpg", ".bmp", ".tiff", ".webp"}) {
    std::vector<uint8_t> bytes = encode(ext, noise);
    for (const double keep : {0.5, 0.95}) {
      std::vector<uint8_t> cut(bytes.begin(), bytes.begin() + long(double(bytes.size()) * keep));
      const std::string name = std::string("cut") + ext;
      write_bytes(dir_ / name, cut);
      std::string msg;
      EXPECT_EQ(error_of([&] { read_image(dir_ / name); }, &msg), ErrorCode::kBadFile)
          << ext << " " << keep;
      EXPECT_NE(msg.find("truncated"), std::string::npos) << msg;
    }
  }
}

TEST_F(ImageIo, PixelLimitIsCheckedFromBmpWebpAndTiffHeaders) {
  // Headers only, each claiming 100000 x 100000 (or 100000 x 70000): refused before decoding.
  const std::vector<uint8_t> bmp = {
      'B', 'M', 0, 0, 0,    0,    0,    0, 0,    0,    54,   0,   0, 0,  // file header
      40,  0,   0, 0, 0xa0, 0x86, 0x01, 0, 0x60, 0x79, 0xfe, 0xff};      // w, -h
  const std::vector<uint8_t> webp = {
      'R', 'I', 'F', 'F', 30, 0, 0, 0, 'W',  'E',  'B',  'P',  'V',  'P', '8', 'X',
      10,  0,   0,   0,   0,  0, 0, 0, 0x9f, 0x86, 0x01, 0x9f, 0x86, 0x01};  // (w-1, h-1) 24-bit
  const std::vector<uint8_t> tiff = {
      'M', 'M', 0, 42, 0, 0, 0, 8, 0, 2,               // big-endian, IFD at 8 with 2 entries
      1,   0,   0, 4,  0, 0, 0, 1, 0, 1, 0x86, 0xa0,   // ImageWidth LONG 100000
      1,   1,   0, 4,  0, 0, 0, 1, 0, 1, 0x11, 0x70};  // ImageLength LONG 70000
  for (const auto& [name, bytes] :
       {std::pair{"huge.bmp", bmp}, std::pair{"huge.webp", webp}, std::pair{"huge.tif", tiff}}) {
    write_bytes(dir_ / name, bytes);
    std::string msg;
    EXPECT_EQ(error_of([&] { read_image(dir_ / name); }, &msg), ErrorCode::kLimit) << name;
    EXPECT_NE(msg.find("100000x"), std::string::npos) << msg;
  }
  // Real files of 24 x 16 = 384 pixels against a limit of 383.
  const cv::Mat3b bgr = smooth_bgr();
  for (const char* ext : {".bmp", ".tiff", ".webp"}) {
    const std::string name = std::string("small") + ext;
    write_bytes(dir_ / name, encode(ext, bgr));
    EXPECT_EQ(error_of([&] { read_image(dir_ / name, 383); }), ErrorCode::kLimit) << ext;
    EXPECT_NO_THROW(read_image(dir_ / name, 384)) << ext;
  }
}

}  // namespace
}  // namespace subvec
