// The parallel PNG encoder (io/png_encoder_p.h) against slow, obvious references: libpng decodes
// every file to the pixels given; the zlib stream inflates in one piece to filtered rows whose
// filter bytes are the ones a plain five-filter search picks, and which unfilter to the pixels;
// libpng's own writer, at the same level, makes a file of about the same size; and the bytes do not
// depend on the thread count or on how the rows are handed over.
#include "io/png_encoder_p.h"

#include <gtest/gtest.h>
#include <unistd.h>
#include <png.h>
#include <zlib.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "subvec/io/image_io.h"

namespace subvec {
namespace {

namespace fs = std::filesystem;

// A smooth gradient with a ripple and a sharp square, plus noise in one corner: every filter wins
// somewhere.
Image8 test_image(int w, int h, int channels, uint32_t seed = 7) {
  Image8 im(w, h, channels);
  std::mt19937 rng(seed);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      uint8_t* p = im.pixels.data() + (size_t(y) * w + x) * channels;
      const bool square = x > w / 3 && x < w / 2 && y > h / 3 && y < h / 2;
      const bool noisy = x < w / 8 && y < h / 8;
      for (int c = 0; c < channels; ++c) {
        int v = (x * (c + 1) + y * (3 - c)) % 256;
        v = (v + int(20 * std::sin(0.1 * x + c))) & 255;
        if (square) v = 255 - v;
        if (noisy) v = int(rng() & 255);
        p[c] = uint8_t(c == 3 ? (x + y) % 256 : v);
      }
    }
  }
  return im;
}

uint32_t get32(const uint8_t* p) {
  return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | uint32_t(p[3]);
}

// The chunks of a PNG, each CRC checked; returns the concatenated IDAT data.
std::vector<uint8_t> idat_of(const std::vector<uint8_t>& png) {
  static const uint8_t kSig[8] = {137, 'P', 'N', 'G', 13, 10, 26, 10};
  EXPECT_TRUE(png.size() > 8 && std::equal(kSig, kSig + 8, png.begin()));
  std::vector<uint8_t> idat;
  size_t i = 8;
  std::string last;
  while (i + 12 <= png.size()) {
    const uint32_t n = get32(&png[i]);
    const std::string type(png.begin() + ptrdiff_t(i + 4), png.begin() + ptrdiff_t(i + 8));
    EXPECT_LE(i + 12 + n, png.size());
    EXPECT_EQ(uint32_t(crc32(0, &png[i + 4], n + 4)), get32(&png[i + 8 + n])) << type;
    if (type == "IDAT") idat.insert(idat.end(), &png[i + 8], &png[i + 8 + n]);
    last = type;
    i += 12 + n;
  }
  EXPECT_EQ(i, png.size());
  EXPECT_EQ(last, "IEND");
  return idat;
}

std::vector<uint8_t> inflate_all(const std::vector<uint8_t>& z, size_t expect) {
  std::vector<uint8_t> out(expect + 1);
  uLongf n = uLongf(out.size());
  EXPECT_EQ(uncompress(out.data(), &n, z.data(), uLong(z.size())), Z_OK);  // Adler-32 checked
  out.resize(n);
  return out;
}

int plain_paeth(int a, int b, int c) {
  const int p = a + b - c;
  const int pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  if (pa <= pb && pa <= pc) return a;
  if (pb <= pc) return b;
  return c;
}

// The five filters of row y written out in full, and the type with the smallest sum of signed
// magnitudes (the first on ties).
int reference_filter(const Image8& im, int y) {
  const int n = im.width * im.channels, bpp = im.channels;
  long best = -1;
  int type = 0;
  for (int t = 0; t < 5; ++t) {
    long sum = 0;
    for (int i = 0; i < n; ++i) {
      const int x = im.row(y)[i];
      const int a = i >= bpp ? im.row(y)[i - bpp] : 0;
      const int b = y > 0 ? im.row(y - 1)[i] : 0;
      const int c = (i >= bpp && y > 0) ? im.row(y - 1)[i - bpp] : 0;
      const int pred = t == 0 ? 0 : t == 1 ? a : t == 2 ? b : t == 3 ? (a + b) / 2 : plain_paeth(a, b, c);
      sum += std::abs(int(int8_t(uint8_t(x - pred))));
    }
    if (best < 0 || sum < best) best = sum, type = t;
  }
  return type;
}

// Unfilters the inflated stream by the PNG specification's definitions.
std::vector<uint8_t> unfilter(const std::vector<uint8_t>& f, int w, int h, int bpp) {
  const size_t n = size_t(w) * bpp;
  std::vector<uint8_t> out(n * h);
  for (int y = 0; y < h; ++y) {
    const uint8_t type = f[y * (n + 1)];
    const uint8_t* in = &f[y * (n + 1) + 1];
    uint8_t* row = &out[y * n];
    for (size_t i = 0; i < n; ++i) {
      const int a = i >= size_t(bpp) ? row[i - bpp] : 0;
      const int b = y > 0 ? out[(y - 1) * n + i] : 0;
      const int c = (i >= size_t(bpp) && y > 0) ? out[(y - 1) * n + i - bpp] : 0;
      const int pred = type == 0 ? 0 : type == 1 ? a : type == 2 ? b : type == 3 ? (a + b) / 2 : plain_paeth(a, b, c);
      row[i] = uint8_t(in[i] + pred);
    }
  }
  return out;
}

// libpng's writer at the encoder's level (the reference for size).
std::vector<uint8_t> libpng_encode(const Image8& im) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  std::vector<uint8_t> out;
  png_set_write_fn(
      png, &out,
      [](png_structp p, png_bytep d, png_size_t n) {
        auto* o = static_cast<std::vector<uint8_t>*>(png_get_io_ptr(p));
        o->insert(o->end(), d, d + n);
      },
      [](png_structp) {});
  png_set_IHDR(png, info, im.width, im.height, 8, im.channels == 4 ? PNG_COLOR_TYPE_RGB_ALPHA : PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, 1);
  png_write_info(png, info);
  for (int y = 0; y < im.height; ++y) png_write_row(png, im.row(y));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return out;
}

struct Size {
  int w, h, channels;
};

class PngEncoderSizes : public ::testing::TestWithParam<Size> {};

TEST_P(PngEncoderSizes, MatchesTheReferences) {
  const Size s = GetParam();
  const Image8 im = test_image(s.w, s.h, s.channels);
  const std::vector<uint8_t> png = encode_png(im, 1);
  // Several pieces in most sizes here: the dictionary and the Adler-32 combination are exercised.
  const std::vector<uint8_t> filtered =
      inflate_all(idat_of(png), size_t(s.h) * (size_t(s.w) * s.channels + 1));
  ASSERT_EQ(filtered.size(), size_t(s.h) * (size_t(s.w) * s.channels + 1));
  for (int y = 0; y < s.h; ++y) {
    ASSERT_EQ(filtered[size_t(y) * (size_t(s.w) * s.channels + 1)], reference_filter(im, y))
        << "row " << y;
  }
  EXPECT_EQ(unfilter(filtered, s.w, s.h, s.channels), im.pixels);
  // libpng decodes it to the same pixels (read_image composites RGBA over black: compare the
  // encoder's file with libpng's own file of the same pixels instead).
  // One folder per case and process: ctest runs the cases at once, and 1x1x3 and 1x1x4 share a width.
  const fs::path dir = fs::temp_directory_path() /
                       ("subvec_png_encoder_" + std::to_string(s.w) + "x" + std::to_string(s.h) + "x" +
                        std::to_string(s.channels) + "_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  auto write = [&](const std::string& name, const std::vector<uint8_t>& bytes) {
    FILE* f = std::fopen((dir / name).c_str(), "wb");
    std::fwrite(bytes.data(), 1, bytes.size(), f);
    std::fclose(f);
  };
  const std::vector<uint8_t> reference = libpng_encode(im);
  write("ours.png", png);
  write("libpng.png", reference);
  EXPECT_EQ(read_image(dir / "ours.png").pixels, read_image(dir / "libpng.png").pixels);
  fs::remove_all(dir);
  // About libpng's size: the pieces restart their Huffman tables but keep the 32 KiB window.
  EXPECT_LE(double(png.size()), 1.02 * double(reference.size()) + 64)
      << png.size() << " against libpng's " << reference.size();
  // The same bytes on any number of threads.
  for (const int threads : {2, 3, 8}) EXPECT_EQ(encode_png(im, threads), png) << threads;
}

INSTANTIATE_TEST_SUITE_P(Shapes, PngEncoderSizes,
                         ::testing::Values(Size{1, 1, 3}, Size{1, 1, 4}, Size{7, 3, 3},
                                           Size{640, 480, 3}, Size{600, 500, 4},
                                           Size{3, 20000, 3},        // many pieces of many rows
                                           Size{180000, 3, 3}),      // one row a piece
                         [](const auto& p) {
                           return std::to_string(p.param.w) + "x" +
                                  std::to_string(p.param.h) + "x" +
                                  std::to_string(p.param.channels);
                         });

TEST(PngEncoder, RowsInAnyBatchesGiveTheSameBytes) {
  const Image8 im = test_image(700, 900, 3, 11);
  const std::vector<uint8_t> whole = encode_png(im, 2);
  const int piece = detail::PngEncoder::piece_rows(im.width, im.channels);
  for (const int batch : {1, 7, piece, piece + 1, 256}) {
    detail::PngEncoder encoder(im.width, im.height, im.channels, 2);
    std::vector<uint8_t> out;
    encoder.begin(out);
    for (int y = 0; y < im.height; y += batch)
      encoder.rows(im.row(y), std::min(batch, im.height - y), out);
    encoder.end(out);
    EXPECT_EQ(out, whole) << "batches of " << batch;
  }
}

// Two rows of noise, repeated: each piece's first rows match the 32 KiB before it, which only the
// dictionary shows deflate. 59 KB with it (the first rows, unique, and level 1's misses); 174 KB
// without, each of the ten pieces paying for its first two rows again.
TEST(PngEncoder, PiecesSeeTheWindowBeforeThem) {
  const int w = 2000, h = 870;
  Image8 im(w, h, 3);
  std::mt19937 rng(3);
  for (int x = 0; x < 2 * w * 3; ++x) im.pixels[size_t(x)] = uint8_t(rng());
  for (int y = 2; y < h; ++y) std::memcpy(im.row(y), im.row(y - 2), size_t(w) * 3);
  ASSERT_GE(h / detail::PngEncoder::piece_rows(w, 3), 9);
  const size_t size = encode_png(im, 2).size();
  EXPECT_LT(size, size_t{100000}) << size;
}

}  // namespace
}  // namespace subvec
