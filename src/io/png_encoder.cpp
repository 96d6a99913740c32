// The parallel PNG encoder (png_encoder_p.h says why and how).
#include "io/png_encoder_p.h"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <cstring>
#include <new>

#include "core/parallel_p.h"
#include "subvec/core/error.h"

namespace subvec::detail {
namespace {

constexpr size_t kWindow = 32768;            // deflate's window: the dictionary of a piece
constexpr size_t kPieceBytes = size_t(1) << 19;  // filtered bytes a piece holds, about

void put32(std::vector<uint8_t>& out, uint32_t v) {
  out.insert(out.end(), {uint8_t(v >> 24), uint8_t(v >> 16), uint8_t(v >> 8), uint8_t(v)});
}

void chunk(std::vector<uint8_t>& out, const char type[4], const uint8_t* data, size_t n) {
  put32(out, uint32_t(n));
  const size_t at = out.size();
  out.insert(out.end(), type, type + 4);
  if (n) out.insert(out.end(), data, data + n);
  put32(out, uint32_t(crc32(0, out.data() + at, uInt(n + 4))));
}

int paeth(int a, int b, int c) {
  const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}

// Filters one row (n bytes, bpp bytes a pixel, `up` the raw row above, zeros for the first) into
// out[0] (the filter type) and out[1..n]: the filter whose bytes, read as signed, have the smallest
// sum of magnitudes (libpng's heuristic), the lowest type on ties. Bytes left of the row read as 0.
void filter_row(const uint8_t* row, const uint8_t* up, size_t n, size_t bpp, uint8_t* out) {
  auto mag = [](int v) { return uint32_t(std::abs(int(int8_t(uint8_t(v))))); };
  auto left = [&](size_t i) { return i >= bpp ? int(row[i - bpp]) : 0; };
  auto corner = [&](size_t i) { return i >= bpp ? int(up[i - bpp]) : 0; };
  std::array<uint32_t, 5> sum{};
  for (size_t i = 0; i < n; ++i) {
    const int x = row[i], a = left(i), b = up[i], c = corner(i);
    sum[0] += mag(x);
    sum[1] += mag(x - a);
    sum[2] += mag(x - b);
    sum[3] += mag(x - ((a + b) >> 1));
    sum[4] += mag(x - paeth(a, b, c));
  }
  const int type = int(std::min_element(sum.begin(), sum.end()) - sum.begin());
  out[0] = uint8_t(type);
  uint8_t* f = out + 1;
  switch (type) {
    case 0: std::memcpy(f, row, n); break;
    case 1: for (size_t i = 0; i < n; ++i) f[i] = uint8_t(row[i] - left(i)); break;
    case 2: for (size_t i = 0; i < n; ++i) f[i] = uint8_t(row[i] - up[i]); break;
    case 3: for (size_t i = 0; i < n; ++i) f[i] = uint8_t(row[i] - ((left(i) + up[i]) >> 1)); break;
    default:
      for (size_t i = 0; i < n; ++i) f[i] = uint8_t(row[i] - paeth(left(i), up[i], corner(i)));
  }
}

// One piece deflated as raw deflate (no zlib header), primed with `dict`, ended with Z_FINISH
// when it is the last and Z_SYNC_FLUSH (a byte boundary, no final block) otherwise.
std::vector<uint8_t> deflate_piece(const uint8_t* data, size_t n, const uint8_t* dict,
                                   size_t dict_n, bool last) {
  z_stream z{};
  if (deflateInit2(&z, 1, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY) != Z_OK) throw std::bad_alloc();
  struct End {
    z_stream* z;
    ~End() { deflateEnd(z); }
  } end{&z};
  if (dict_n && deflateSetDictionary(&z, dict, uInt(dict_n)) != Z_OK) throw std::bad_alloc();
  std::vector<uint8_t> out(deflateBound(&z, uLong(n)) + 16);
  z.next_in = const_cast<Bytef*>(data);
  z.avail_in = uInt(n);
  z.next_out = out.data();
  z.avail_out = uInt(out.size());
  const int r = deflate(&z, last ? Z_FINISH : Z_SYNC_FLUSH);
  if (r != (last ? Z_STREAM_END : Z_OK) || z.avail_in != 0) {
    throw Error(ErrorCode::kIo, "PNG encoding failed (deflate " + std::to_string(r) + ")");
  }
  out.resize(out.size() - z.avail_out);
  out.shrink_to_fit();  // the bound is about the input's size; a piece held is its packed size
  return out;
}

}  // namespace

int PngEncoder::piece_rows(int width, int channels) {
  const size_t stride = size_t(width) * size_t(channels) + 1;
  return int(std::max<size_t>(1, kPieceBytes / stride));
}

PngEncoder::PngEncoder(int width, int height, int channels, int threads)
    : width_(width),
      height_(height),
      channels_(channels),
      threads_(threads),
      stride_(size_t(width) * size_t(channels) + 1),
      previous_(stride_ - 1, 0) {}

void PngEncoder::begin(std::vector<uint8_t>& out) {
  static constexpr uint8_t kSignature[8] = {137, 'P', 'N', 'G', 13, 10, 26, 10};
  out.insert(out.end(), kSignature, kSignature + 8);
  std::vector<uint8_t> ihdr;
  put32(ihdr, uint32_t(width_));
  put32(ihdr, uint32_t(height_));
  // 8 bits, RGB (2) or RGBA (6), deflate, adaptive filtering, no interlace.
  ihdr.insert(ihdr.end(), {8, uint8_t(channels_ == 4 ? 6 : 2), 0, 0, 0});
  chunk(out, "IHDR", ihdr.data(), ihdr.size());
}

void PngEncoder::rows(const uint8_t* pixels, int count, std::vector<uint8_t>& out) {
  if (count <= 0) return;
  const size_t n = stride_ - 1;
  const size_t at = pending_.size();
  pending_.resize(at + size_t(count) * stride_);
  // Rows filter independently given the raw row above: in groups of 16 on the threads.
  constexpr int kGroup = 16;
  parallel_for((count + kGroup - 1) / kGroup, threads_, [&](int g) {
    for (int y = g * kGroup; y < std::min(count, (g + 1) * kGroup); ++y) {
      const uint8_t* row = pixels + size_t(y) * n;
      const uint8_t* up = y == 0 ? previous_.data() : row - n;
      filter_row(row, up, n, size_t(channels_), pending_.data() + at + size_t(y) * stride_);
    }
  });
  std::memcpy(previous_.data(), pixels + size_t(count - 1) * n, n);
  rows_in_ += count;
  compress_pieces(rows_in_ == height_, out);
}

void PngEncoder::compress_pieces(bool last, std::vector<uint8_t>& out) {
  // pending_ holds window_ bytes already compressed (the dictionary of what follows), then the
  // filtered rows not yet compressed: piece i is [window_ + i * piece, ... + piece), cut short at
  // the end, and its dictionary the 32 KiB before it.
  const size_t piece = size_t(piece_rows(width_, channels_)) * stride_;
  const size_t base = window_, have = pending_.size() - base;
  size_t pieces = have / piece;
  if (last && have % piece) ++pieces;
  if (pieces == 0) return;
  const size_t used = std::min(have, pieces * piece);
  std::vector<std::vector<uint8_t>> packed(pieces);
  std::vector<uint32_t> adlers(pieces);
  parallel_for(int(pieces), threads_, [&](int i) {
    const size_t begin = base + size_t(i) * piece, end = std::min(base + used, begin + piece);
    const size_t dict = std::min(begin, kWindow);
    const bool final_piece = last && size_t(i) + 1 == pieces;
    packed[i] = deflate_piece(pending_.data() + begin, end - begin, pending_.data() + begin - dict,
                              dict, final_piece);
    adlers[i] = uint32_t(adler32(1, pending_.data() + begin, uInt(end - begin)));
  });
  for (size_t i = 0; i < pieces; ++i) {
    const size_t len = std::min(used - i * piece, piece);
    adler_ = uint32_t(adler32_combine(adler_, adlers[i], z_off_t(len)));
    std::vector<uint8_t>& data = packed[i];
    if (!started_) {
      data.insert(data.begin(), {0x78, 0x01});  // zlib header: deflate, 32 KiB window, fastest
      started_ = true;
    }
    if (last && i + 1 == pieces) put32(data, adler_);
    chunk(out, "IDAT", data.data(), data.size());
  }
  // Keep the last 32 KiB compressed, as the next piece's dictionary, and what is left.
  const size_t keep = std::min(kWindow, base + used);
  pending_.erase(pending_.begin(), pending_.begin() + ptrdiff_t(base + used - keep));
  window_ = keep;
}

void PngEncoder::end(std::vector<uint8_t>& out) { chunk(out, "IEND", nullptr, 0); }

}  // namespace subvec::detail
