// Native files: `.svec.json` (documented JSON, writable by hand) and `.svec` (binary: magic,
// version, little-endian, zstd-compressed payload). docs/format.md is the contract for both.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "subvec/mesh/vector_image.h"

namespace subvec {

enum class SvecFormat { kJson, kBinary };

// How `.svec` (binary) files are written.
struct SvecWriteOptions {
  // Version 1: every value exactly as in memory, vertices, triangles and colors in their own
  // order. Otherwise the compact form: positions and colors rounded to the grids below and the
  // level renumbered in traversal order (the same picture; a second write is identical).
  bool lossless = false;
  // The compact form's version: 3 (range-coded, the default) or 2 (varints and zstd, the same
  // content in about 11 % more bytes; for readers that predate version 3).
  int compact_version = 3;
  // Compact: positions on multiples of 2^-position_bits pixels (0 to 12; finer where needed to
  // keep every triangle positive), colors on multiples of 2^-color_bits levels (-4 to 12) and at
  // most 2^(23 - color_bits) in magnitude, so that each is exact as a float (larger ones throw).
  // docs/format.md gives the measured effect of each choice.
  int position_bits = 2;
  int color_bits = -1;
};

// `.svec.json` or `.json` -> kJson, `.svec` -> kBinary; anything else throws kInvalidArgument.
SvecFormat svec_format_for(const std::filesystem::path& path);

// Parse and validate (mesh/validate.h). Throw Error(kBadFile) naming the field and index, or
// Error(kInvalidMesh) from validation; never read out of bounds.
VectorImage parse_svec_json(std::string_view text);
VectorImage parse_svec_binary(std::span<const uint8_t> bytes);

std::string to_svec_json(const VectorImage& image);
std::vector<uint8_t> to_svec_binary(const VectorImage& image,
                                    const SvecWriteOptions& options = {});

// Read by content (binary magic, else JSON); write by extension, atomically.
VectorImage read_svec(const std::filesystem::path& path);
void write_svec(const std::filesystem::path& path, const VectorImage& image,
                const SvecWriteOptions& options = {});

}  // namespace subvec
