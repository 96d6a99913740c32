// The compact level layouts of `.svec` versions 2 and 3 (docs/format.md, "Compact levels"): quantized
// positions and colors, predicted along a traversal of the mesh, and connectivity coded as one
// operation per triangle. Private to the binary reader and writer (svec_binary.cpp).
#pragma once

#include <cstddef>
#include <vector>

#include "io/svec_bytes_p.h"
#include "subvec/mesh/vector_image.h"

namespace subvec::svec_detail {

// Bounds of the quantization grids: positions on multiples of 2^-position_bits pixels, colors on
// multiples of 2^-color_bits levels. kMaxPositionBits keeps every integer product of the coder
// within 64 bits for images up to 65536 pixels a side.
inline constexpr int kMaxPositionBits = 12;
inline constexpr int kMinColorBits = -4;  // steps of up to 16 levels
inline constexpr int kMaxColorBits = 12;

// `mesh` with its positions on the 2^-position_bits grid: each vertex at the nearest grid point,
// or another one nearby where that would flip or collapse a triangle. The result may still fail
// validation (then try a finer grid). Colors are rounded by the encoder, in coding order.
ControlMesh quantize_positions(const ControlMesh& mesh, int width, int height, int position_bits);

// Appends one level, valid and with positions already on the grid, in the compact layout. The
// level is stored in traversal order: the decoder gets the same image with its vertices,
// triangles and color values renumbered (canonical order; a second encoding is identical).
// Appends to `block_ends` the offsets in `out` after which the writer should start a new zstd
// block (each section gets its own entropy tables).
// `vertex_order`, when given, receives each vertex's number in the stored order.
// `version` 2 writes six varint sections, 3 one range-coded stream (svec_range_p.h).
void encode_compact_level(const ControlMesh& mesh, int width, int height, int position_bits,
                          int color_bits, int version, ByteWriter& out,
                          std::vector<size_t>& block_ends,
                          std::vector<int32_t>* vertex_order = nullptr);

// Reads one compact level; throws Error(kBadFile) (or kLimit, kInvalidMesh) naming `level`.
// The result is not yet validated.
ControlMesh decode_compact_level(Cursor& in, int level, int width, int height, int version);

}  // namespace subvec::svec_detail
