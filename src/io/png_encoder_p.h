// The PNG encoder of encode_png() and PngWriter: 8-bit RGB or RGBA, compressed on several threads
// with the same bytes whatever their number.
//
// Why not libpng's writer. libpng filters and deflates one row after another into one zlib
// stream, on one thread: for an 8192 x 8192 render that was 1.1 s of the 2 s the render may take
// (docs/performance.md). This encoder cuts the image into pieces of a fixed number of rows (from the
// width only, never from the thread count), filters each row with the filter libpng's heuristic
// would pick (the smallest sum of absolute filtered bytes over None, Sub, Up, Average and Paeth),
// and deflates the pieces in parallel with zlib (level 1, as before), each primed with the 32 KiB
// of filtered bytes before it (deflateSetDictionary) and ended on a byte boundary (Z_SYNC_FLUSH;
// the last one Z_FINISH). Concatenated, the pieces are one valid zlib stream, whose Adler-32 is
// combined from theirs (adler32_combine): the technique of pigz. libpng still reads every PNG, and
// the tests decode this encoder's files with it (tests/unit/io/png_encoder_test.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace subvec::detail {

class PngEncoder {
 public:
  // A width x height image of `channels` (3 or 4) 8-bit channels (checked by the caller).
  PngEncoder(int width, int height, int channels, int threads);

  // The signature and the IHDR chunk.
  void begin(std::vector<uint8_t>& out);
  // The next `count` rows (row-major, width * channels bytes each): IDAT chunks of the pieces they
  // complete. The caller keeps to the height.
  void rows(const uint8_t* pixels, int count, std::vector<uint8_t>& out);
  // After the last row: the IEND chunk.
  void end(std::vector<uint8_t>& out);

  int width() const { return width_; }
  int height() const { return height_; }
  int channels() const { return channels_; }
  int rows_given() const { return rows_in_; }

  // Rows a piece holds for this width (about 512 KiB of filtered bytes).
  static int piece_rows(int width, int channels);

 private:
  void compress_pieces(bool last, std::vector<uint8_t>& out);

  int width_, height_, channels_, threads_;
  size_t stride_;               // filtered bytes a row: the filter byte, then the row
  int rows_in_ = 0;             // rows given so far
  std::vector<uint8_t> previous_;  // the raw row before the next one (zeros before the first)
  std::vector<uint8_t> pending_;   // window_ bytes compressed, then filtered rows that are not
  size_t window_ = 0;              // the last 32 KiB (or less) compressed, kept as the dictionary
  uint32_t adler_ = 1;
  bool started_ = false;
};

}  // namespace subvec::detail
