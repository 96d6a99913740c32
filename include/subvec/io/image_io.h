// Raster image files: PNG through libpng, the other formats through OpenCV's codecs.
#pragma once

#include <cstdint>
#include <filesystem>
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

// The PNG file (8-bit RGB or RGBA) of an image. Throws Error(kInvalidArgument) for an empty or
// malformed image, Error(kIo) if encoding fails.
std::vector<uint8_t> encode_png(const Image8& image);

// Writes a PNG (RGB or RGBA) atomically: to a temporary file beside `path`, then renamed.
void write_png(const std::filesystem::path& path, const Image8& image);

}  // namespace subvec
