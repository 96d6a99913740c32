// Raster image files: PNG through libpng, the other formats through OpenCV's codecs.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "subvec/core/image.h"

namespace subvec {

// Reads PNG/JPEG/WebP/TIFF/BMP as 8-bit RGB: gray is expanded, 16-bit scaled down, alpha
// composited over black (a transparent pixel reads as black), CMYK JPEG converted and the JPEG
// EXIF orientation applied. Images over `max_pixels` are refused, from the header before decoding
// (PNG, JPEG, BMP, WebP, classic TIFF). Throws Error(kIo / kBadFile / kLimit) with the path in the message.
Image8 read_image(const std::filesystem::path& path, int64_t max_pixels = int64_t{1} << 28);

// What kind of image file `bytes` (its start is enough) holds, from its magic bytes: "PNG",
// "JPEG", "WebP", "TIFF", "BMP" (the formats read_image takes), "GIF", "PDF", "SVG", or "" for
// none of these. The vector image reader uses it to say what a wrong file is.
std::string image_format_name(const std::vector<uint8_t>& bytes);
// True for the five formats read_image (and so vectorize) takes.
bool is_raster_input(const std::string& format);

// The PNG file (8-bit RGB or RGBA) of an image, compressed on `threads` threads (<= 0: all cores;
// the bytes do not depend on it). Throws Error(kInvalidArgument) for an empty or malformed image,
// Error(kIo) if encoding fails.
std::vector<uint8_t> encode_png(const Image8& image, int threads = 0);

// Writes a PNG (RGB or RGBA) atomically: to a temporary file beside `path`, then renamed.
void write_png(const std::filesystem::path& path, const Image8& image);

// A PNG (8-bit RGB or RGBA) written row by row, for images that are drawn in strips and never
// held whole (render_strips): the rows are compressed (on `threads` threads, as encode_png) into a
// temporary file beside `path`,
// which finish() renames onto it; a writer destroyed unfinished removes its temporary file, so
// `path` is never left partial. The bytes are write_png()'s for the same pixels. Throws
// Error(kInvalidArgument) for a bad size or strip, Error(kIo) if writing fails.
class PngWriter {
 public:
  PngWriter(const std::filesystem::path& path, int width, int height, int channels,
            int threads = 0);
  ~PngWriter();
  PngWriter(const PngWriter&) = delete;
  PngWriter& operator=(const PngWriter&) = delete;
  // The next rows.height rows (rows.width and rows.channels as given to the constructor).
  void write_rows(const Image8& rows);
  // After the last row: completes the file and renames it onto `path`.
  void finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace subvec
