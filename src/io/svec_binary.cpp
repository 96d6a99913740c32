// The `.svec` binary form (docs/format.md): a fixed header and one zstd frame holding a
// little-endian payload.
//
// Reading never trusts a declared size: the header's payload size is capped before anything is
// allocated, the output buffer grows only as zstd produces bytes, every count in the payload is
// capped and checked against the bytes that remain before a vector is sized, and the cursor
// throws "truncated payload while reading <what>" instead of reading past the end. The image is
// then validated like a JSON one. Writing is deterministic (single-threaded zstd, fixed level).
#include <zstd.h>

#include <array>
#include <algorithm>
#include <bit>
#include <climits>
#include <cstring>
#include <memory>
#include <string>

#include "io/svec_bytes_p.h"
#include "io/svec_compact_p.h"
#include "io/svec_p.h"
#include "subvec/core/error.h"
#include "subvec/io/svec.h"
#include "subvec/mesh/validate.h"

namespace subvec {
namespace {

using namespace svec_detail;

// ---------------------------------------------------------------------------------------------
// Payload.

// Strokes and metadata end the payload in both versions, then the optional pyramid records.
void encode_trailer(ByteWriter& w, const VectorImage& image);
void decode_trailer(Cursor& in, VectorImage& image);
void encode_pyramid(ByteWriter& w, const VectorImage& image);
void encode_objects(ByteWriter& w, const VectorImage& image);

// One mesh, every value as stored in memory: the levels of version 1 and every version's objects.
void encode_mesh_v1(ByteWriter& w, const ControlMesh& m) {
  if (m.triangle_colors.size() != m.triangles.size()) {
    fail("cannot write a level whose triangle_colors and triangles differ in length",
         ErrorCode::kInvalidMesh);
  }
  w.count(m.positions.size(), "vertices");
  w.count(m.colors.size(), "colors");
  w.count(m.triangles.size(), "triangles");
  w.count(m.creases.size(), "creases");
  w.count(m.features.size(), "features");
  for (const Vec2& p : m.positions) w.f64(p.x), w.f64(p.y);
  for (const Color& c : m.colors) w.f32(c.r), w.f32(c.g), w.f32(c.b);
  for (const Tri& t : m.triangles)
    for (int32_t v : t) w.i32(v);
  for (const Tri& t : m.triangle_colors)
    for (int32_t c : t) w.i32(c);
  for (const EdgeVerts& e : m.creases) w.i32(e[0]), w.i32(e[1]);
  for (const Feature& f : m.features) {
    w.i32(f.id);
    w.f64(f.saliency);
    w.count(f.vertices.size(), "feature vertices");
    for (int32_t v : f.vertices) w.i32(v);
  }
}

// Version 1: every value as stored in memory, in the image's own order.
std::vector<uint8_t> encode_payload_v1(const VectorImage& image) {
  ByteWriter w;
  w.i32(image.width);
  w.i32(image.height);
  w.count(image.levels.size(), "levels");
  for (const ControlMesh& m : image.levels) encode_mesh_v1(w, m);
  encode_objects(w, image);
  encode_trailer(w, image);
  encode_pyramid(w, image);
  return std::move(w.bytes);
}

// Versions 2 and 3: levels in the compact layout (svec_compact.cpp), already quantized with
// `bits`.
std::vector<uint8_t> encode_payload_compact(const VectorImage& image, uint32_t version,
                                            const std::vector<std::array<int, 2>>& bits,
                                            std::vector<size_t>& block_ends) {
  ByteWriter w;
  std::vector<std::vector<int32_t>> orders(image.levels.size());
  w.i32(image.width);
  w.i32(image.height);
  w.count(image.levels.size(), "levels");
  for (size_t l = 0; l < image.levels.size(); ++l) {
    const ControlMesh& m = image.levels[l];
    w.count(m.positions.size(), "vertices");
    w.count(m.colors.size(), "colors");
    w.count(m.triangles.size(), "triangles");
    w.count(m.creases.size(), "creases");
    w.count(m.features.size(), "features");
    w.bytes.push_back(static_cast<uint8_t>(bits[l][0]));
    w.bytes.push_back(static_cast<uint8_t>(static_cast<int8_t>(bits[l][1])));
    encode_compact_level(m, image.width, image.height, bits[l][0], bits[l][1], int(version), w,
                         block_ends, &orders[l]);
  }
  encode_objects(w, image);
  // The pyramid records name vertices: renumber them as the levels were.
  VectorImage records;
  records.levels.resize(image.levels.size());
  for (size_t l = 1; l < image.levels.size(); ++l) {
    const ControlMesh& m = image.levels[l];
    ControlMesh& r = records.levels[l];
    const std::vector<int32_t>& fine = orders[l - 1];
    r.parent_vertices.resize(m.parent_vertices.size());
    for (size_t v = 0; v < m.parent_vertices.size(); ++v)
      r.parent_vertices[orders[l][v]] = fine[m.parent_vertices[v]];
    for (const EdgeVerts& e : m.collapses) r.collapses.push_back({fine[e[0]], fine[e[1]]});
  }
  encode_trailer(w, image);
  encode_pyramid(w, records);
  return std::move(w.bytes);
}

void encode_strokes(ByteWriter& w, const std::vector<Stroke>& strokes) {
  w.count(strokes.size(), "strokes");
  for (const Stroke& s : strokes) {
    w.i32(s.level);
    w.f32(s.width);
    w.f32(s.color.r), w.f32(s.color.g), w.f32(s.color.b);
    w.f32(s.taper);
    w.count(s.points.size(), "stroke points");
    for (const Vec2& p : s.points) w.f64(p.x), w.f64(p.y);
  }
}

// Reads what encode_strokes wrote; `owner` names them in messages ("", "object 2 ").
void decode_strokes(Cursor& in, std::vector<Stroke>& strokes, const std::string& owner) {
  in.set_context(owner + "strokes");
  strokes.resize(in.count(owner + "strokes", 28));
  for (size_t i = 0; i < strokes.size(); ++i) {
    Stroke& s = strokes[i];
    const std::string what = owner + "stroke " + str(i);
    in.set_context(what);
    s.level = in.i32();
    s.width = in.f32();
    s.color.r = in.f32(), s.color.g = in.f32(), s.color.b = in.f32();
    s.taper = in.f32();
    s.points.resize(in.count(what + " points", 16));
    for (Vec2& p : s.points) p.x = in.f64(), p.y = in.f64();
  }
}

void encode_trailer(ByteWriter& w, const VectorImage& image) {
  encode_strokes(w, image.strokes);
  w.count(image.metadata.size(), "metadata entries");
  for (const auto& [key, value] : image.metadata) {
    w.string(key);
    w.string(value);
  }
}

// Reads what encode_mesh_v1 wrote; `level` names it in messages ("level 2 ", "object 0 ").
void decode_mesh_v1(Cursor& in, ControlMesh& m, const std::string& level) {
  in.set_context(level + "counts");
  const size_t counts[5] = {in.count(level + "vertices", 16), in.count(level + "colors", 12),
                            in.count(level + "triangles", 24), in.count(level + "creases", 8),
                            in.count(level + "features", 16)};
  in.set_context(level + "vertices");
  m.positions.resize(counts[0]);
  for (Vec2& p : m.positions) p.x = in.f64(), p.y = in.f64();
  in.set_context(level + "colors");
  m.colors.resize(counts[1]);
  for (Color& c : m.colors) c.r = in.f32(), c.g = in.f32(), c.b = in.f32();
  in.set_context(level + "triangles");
  m.triangles.resize(counts[2]);
  for (Tri& t : m.triangles)
    for (int32_t& v : t) v = in.i32();
  in.set_context(level + "triangle colors");
  m.triangle_colors.resize(counts[2]);
  for (Tri& t : m.triangle_colors)
    for (int32_t& c : t) c = in.i32();
  in.set_context(level + "creases");
  m.creases.resize(counts[3]);
  for (EdgeVerts& e : m.creases) e[0] = in.i32(), e[1] = in.i32();
  m.features.resize(counts[4]);
  for (size_t i = 0; i < counts[4]; ++i) {
    Feature& f = m.features[i];
    const std::string what = level + "feature " + str(i);
    in.set_context(what);
    f.id = in.i32();
    f.saliency = in.f64();
    f.vertices.resize(in.count(what + " vertices", 4));
    for (int32_t& v : f.vertices) v = in.i32();
  }
}

// The objects (flag kObjectsFlag): a count, then each object's level, visibility, name and mesh;
// then, with kObjectStrokesFlag, each object's strokes.
void decode_objects(Cursor& in, VectorImage& image, uint32_t flags) {
  in.set_context("objects");
  image.objects.resize(in.count("objects", 25, Limits::kMaxObjects));
  for (size_t o = 0; o < image.objects.size(); ++o) {
    Object& object = image.objects[o];
    const std::string what = "object " + str(o) + " ";
    in.set_context(what + "header");
    object.level = in.i32();
    const uint32_t visible = in.u8();
    if (visible > 1) fail(what + "visibility " + str(visible) + " is neither 0 nor 1");
    object.visible = visible == 1;
    object.name = in.string(what + "name");
    decode_mesh_v1(in, object.mesh, what);
  }
  if (flags & kObjectStrokesFlag) {
    for (size_t o = 0; o < image.objects.size(); ++o) decode_strokes(in, image.objects[o].strokes, "object " + str(o) + " ");
  }
}

uint32_t header_flags(const VectorImage& image) {
  if (image.objects.empty()) return 0;
  const bool strokes = std::any_of(image.objects.begin(), image.objects.end(),
                                   [](const Object& o) { return !o.strokes.empty(); });
  return kObjectsFlag | (strokes ? kObjectStrokesFlag : 0);
}

void encode_objects(ByteWriter& w, const VectorImage& image) {
  if (image.objects.empty()) return;  // no flag, no section: the file is as before objects existed
  w.count(image.objects.size(), "objects");
  for (const Object& object : image.objects) {
    w.i32(object.level);
    w.bytes.push_back(object.visible ? 1 : 0);
    w.string(object.name);
    encode_mesh_v1(w, object.mesh);
  }
  if (header_flags(image) & kObjectStrokesFlag) {
    for (const Object& object : image.objects) encode_strokes(w, object.strokes);
  }
}

VectorImage decode_payload(std::span<const uint8_t> payload, uint32_t version, uint32_t flags) {
  Cursor in(payload);
  VectorImage image;
  in.set_context("image size");
  image.width = in.i32();
  image.height = in.i32();
  const size_t num_levels = in.count("levels", 20, Limits::kMaxLevels);
  image.levels.resize(num_levels);
  if (version == kCompactVersion || version == kCodedVersion) {
    if (image.width < 1 || image.height < 1 || image.width > Limits::kMaxDimension ||
        image.height > Limits::kMaxDimension) {
      fail("image size " + std::to_string(image.width) + " x " + std::to_string(image.height) +
           " is out of range (1 to " + str(Limits::kMaxDimension) + " a side)");
    }
    for (size_t l = 0; l < num_levels; ++l)
      image.levels[l] = decode_compact_level(in, int(l), image.width, image.height, int(version));
    if (flags & kObjectsFlag) decode_objects(in, image, flags);
    decode_trailer(in, image);
    return image;
  }
  for (size_t l = 0; l < num_levels; ++l) decode_mesh_v1(in, image.levels[l], "level " + str(l) + " ");
  if (flags & kObjectsFlag) decode_objects(in, image, flags);
  decode_trailer(in, image);
  return image;
}

void decode_trailer(Cursor& in, VectorImage& image) {
  decode_strokes(in, image.strokes, "");
  image.metadata.resize(in.count("metadata entries", 8));
  for (size_t i = 0; i < image.metadata.size(); ++i) {
    const std::string what = "metadata entry " + str(i);
    image.metadata[i].first = in.string(what + " key");
    image.metadata[i].second = in.string(what + " value");
  }
  // Optional: the pyramid records of levels 1 and up (docs/format.md, "Levels and the pyramid").
  // Files written before them end here.
  if (in.remaining() != 0 && in.remaining() < 4)  // too short for a record count: stray bytes
    fail(str(in.remaining()) + " unexpected bytes after the payload's metadata");
  if (in.remaining() != 0) {
    in.set_context("pyramid records");
    const size_t n = in.count("pyramid records", 3, Limits::kMaxLevels);
    for (size_t i = 0; i < n; ++i) {
      const std::string what = "pyramid record " + str(i);
      in.set_context(what);
      const uint32_t l = in.u32();
      if (l < 1 || l >= image.levels.size() || !image.levels[l].parent_vertices.empty() ||
          !image.levels[l].collapses.empty())
        fail(what + ": level " + str(l) + " is out of range or named twice");
      ControlMesh& m = image.levels[l];
      m.parent_vertices.resize(in.count(what + " parent vertices", 1));
      int64_t prev = 0;
      // base + delta as a vertex index; both are checked before they are added.
      auto index = [&](int64_t base, uint64_t code) {
        const int64_t delta = unzigzag(code);
        if (delta < -(int64_t{1} << 32) || delta > (int64_t{1} << 32) || base + delta < 0 ||
            base + delta > INT32_MAX)
          fail(what + ": a vertex index is out of range");
        return static_cast<int32_t>(base + delta);
      };
      for (int32_t& v : m.parent_vertices) prev = v = index(prev, in.varint());
      m.collapses.resize(in.count(what + " collapses", 2));
      for (EdgeVerts& e : m.collapses) {
        e[0] = index(0, zigzag(static_cast<int64_t>(std::min<uint64_t>(in.varint(), uint64_t{1} << 40))));
        e[1] = index(e[0], in.varint());
      }
    }
  }
  if (in.remaining() != 0)
    fail(str(in.remaining()) + " unexpected bytes after the payload's pyramid records");
}

void encode_pyramid(ByteWriter& w, const VectorImage& image) {
  uint32_t n = 0;
  for (size_t l = 1; l < image.levels.size(); ++l)
    n += !image.levels[l].parent_vertices.empty() || !image.levels[l].collapses.empty();
  if (n == 0) return;  // the file ends with the metadata, as before the pyramid existed
  w.count(n, "pyramid records");
  for (size_t l = 1; l < image.levels.size(); ++l) {
    const ControlMesh& m = image.levels[l];
    if (m.parent_vertices.empty() && m.collapses.empty()) continue;
    w.u32(static_cast<uint32_t>(l));
    w.count(m.parent_vertices.size(), "parent vertices");
    int64_t prev = 0;
    for (int32_t v : m.parent_vertices) put_varint(w.bytes, zigzag(int64_t{v} - prev)), prev = v;
    w.count(m.collapses.size(), "collapses");
    for (const EdgeVerts& e : m.collapses) {
      put_varint(w.bytes, static_cast<uint32_t>(e[0]));
      put_varint(w.bytes, zigzag(int64_t{e[1]} - e[0]));
    }
  }
}

// ---------------------------------------------------------------------------------------------
// zstd.

struct DctxDeleter {
  void operator()(ZSTD_DCtx* d) const { ZSTD_freeDCtx(d); }
};
struct CctxDeleter {
  void operator()(ZSTD_CCtx* c) const { ZSTD_freeCCtx(c); }
};

// Decompresses one frame that must produce exactly `expected` bytes. The buffer grows as output
// arrives, so a header that lies about the size costs no memory up front.
std::vector<uint8_t> decompress(std::span<const uint8_t> frame, uint64_t expected) {
  const unsigned long long content = ZSTD_getFrameContentSize(frame.data(), frame.size());
  if (content == ZSTD_CONTENTSIZE_ERROR) fail("corrupt zstd frame: bad frame header");
  if (content != ZSTD_CONTENTSIZE_UNKNOWN && content != expected) {
    fail("zstd frame holds " + str(content) + " bytes but the header declares " + str(expected));
  }
  std::unique_ptr<ZSTD_DCtx, DctxDeleter> dctx(ZSTD_createDCtx());
  if (!dctx) fail("out of memory for zstd", ErrorCode::kIo);
  std::vector<uint8_t> out(std::min<uint64_t>(expected, uint64_t{1} << 24));
  ZSTD_inBuffer input{frame.data(), frame.size(), 0};
  size_t produced = 0;
  for (;;) {
    if (produced == out.size() && out.size() < expected) {
      out.resize(std::min<uint64_t>(expected, uint64_t{out.size()} * 2));
    }
    // Once the buffer holds the declared size, zstd gets one spare byte: any output there means
    // the frame holds more than declared.
    uint8_t spare = 0;
    const bool full = produced == out.size();
    ZSTD_outBuffer output =
        full ? ZSTD_outBuffer{&spare, 1, 0} : ZSTD_outBuffer{out.data(), out.size(), produced};
    const size_t consumed_before = input.pos;
    const size_t ret = ZSTD_decompressStream(dctx.get(), &output, &input);
    if (ZSTD_isError(ret)) fail(std::string("corrupt zstd frame: ") + ZSTD_getErrorName(ret));
    if (full && output.pos > 0) {
      fail("zstd frame decompresses to more than the " + str(expected) +
           " bytes the header declares");
    }
    const bool progress = input.pos != consumed_before || (!full && output.pos != produced);
    if (!full) produced = output.pos;
    if (ret == 0) break;  // frame complete, checksum verified
    if (input.pos == input.size && (full || produced < out.size())) {
      fail("truncated zstd frame: it ends after " + str(produced) + " of " + str(expected) +
           " payload bytes");
    }
    if (!progress) fail("corrupt zstd frame: the decoder makes no progress");
  }
  if (produced != expected) {
    fail("zstd frame decompresses to " + str(produced) + " bytes but the header declares " +
         str(expected));
  }
  if (input.pos != input.size) {
    fail(str(input.size - input.pos) + " unexpected bytes after the zstd frame");
  }
  out.resize(produced);
  return out;
}

// One frame. A new block starts after each offset of `block_ends`, so that sections with
// different statistics get their own entropy tables.
std::vector<uint8_t> compress(std::span<const uint8_t> payload,
                              std::span<const size_t> block_ends = {}) {
  std::unique_ptr<ZSTD_CCtx, CctxDeleter> cctx(ZSTD_createCCtx());
  if (!cctx) fail("out of memory for zstd", ErrorCode::kIo);
  ZSTD_CCtx_setParameter(cctx.get(), ZSTD_c_compressionLevel, kZstdLevel);
  ZSTD_CCtx_setParameter(cctx.get(), ZSTD_c_checksumFlag, 1);
  ZSTD_CCtx_setParameter(cctx.get(), ZSTD_c_contentSizeFlag, 1);
  ZSTD_CCtx_setPledgedSrcSize(cctx.get(), payload.size());
  std::vector<uint8_t> frame(ZSTD_compressBound(payload.size()) + 64 * (block_ends.size() + 1));
  ZSTD_outBuffer output{frame.data(), frame.size(), 0};
  size_t begin = 0;
  auto feed = [&](size_t end, ZSTD_EndDirective mode) {
    ZSTD_inBuffer input{payload.data() + begin, end - begin, 0};
    for (;;) {
      const size_t left = ZSTD_compressStream2(cctx.get(), &output, &input, mode);
      if (ZSTD_isError(left))
        fail(std::string("zstd compression failed: ") + ZSTD_getErrorName(left), ErrorCode::kIo);
      if (left == 0 && input.pos == input.size) break;
      if (output.pos == output.size) fail("zstd compression overflowed its buffer", ErrorCode::kIo);
    }
    begin = end;
  };
  for (const size_t end : block_ends)
    if (end > begin && end < payload.size()) feed(end, ZSTD_e_flush);
  feed(payload.size(), ZSTD_e_end);
  frame.resize(output.pos);
  return frame;
}

std::string hex_bytes(std::span<const uint8_t> bytes) {
  static const char* digits = "0123456789abcdef";
  std::string s;
  for (size_t i = 0; i < bytes.size(); ++i) {
    if (i) s += ' ';
    s += digits[bytes[i] >> 4];
    s += digits[bytes[i] & 15];
  }
  return s;
}

}  // namespace

VectorImage parse_svec_binary(std::span<const uint8_t> bytes) {
  if (!has_magic(bytes)) {
    const size_t n = std::min(bytes.size(), kMagic.size());
    if (n > 0 && n < kMagic.size() && std::memcmp(bytes.data(), kMagic.data(), n) == 0) {
      fail("truncated .svec header: " + str(bytes.size()) + " bytes, the header needs " +
           str(kHeaderBytes));
    }
    fail("not a .svec file: wrong magic bytes (" + hex_bytes(bytes.first(n)) + ", expected " +
         hex_bytes(kMagic) + ")");
  }
  if (bytes.size() < kHeaderBytes) {
    fail("truncated .svec header: " + str(bytes.size()) + " bytes, the header needs " +
         str(kHeaderBytes));
  }
  Cursor header(bytes.subspan(kMagic.size(), kHeaderBytes - kMagic.size()));
  header.set_context("the header");
  const uint32_t version = header.u32();
  const uint32_t flags = header.u32();
  const uint64_t payload_size = header.u64();
  const uint64_t frame_size = header.u64();
  if (version != kLosslessVersion && version != kCompactVersion && version != kCodedVersion) {
    fail("unsupported .svec version " + str(version) + " (this build reads " +
         str(kLosslessVersion) + ", " + str(kCompactVersion) + " and " + str(kCodedVersion) + ")");
  }
  if ((flags & ~(kObjectsFlag | kObjectStrokesFlag)) != 0) {
    fail("unsupported .svec flags " + str(flags) + " (this build knows " + str(kObjectsFlag) +
         ": objects, " + str(kObjectStrokesFlag) + ": object strokes)");
  }
  if ((flags & kObjectStrokesFlag) && !(flags & kObjectsFlag)) {
    fail(".svec flag " + str(kObjectStrokesFlag) + " (object strokes) is set without flag " +
         str(kObjectsFlag) + " (objects)");
  }
  if (payload_size > kMaxPayloadBytes) {
    fail("declared payload of " + str(payload_size) + " bytes is over the limit of " +
             str(kMaxPayloadBytes),
         ErrorCode::kLimit);
  }
  const uint64_t available = bytes.size() - kHeaderBytes;
  if (frame_size > available) {
    fail("truncated .svec file: the header declares a " + str(frame_size) +
         "-byte zstd frame but only " + str(available) + " bytes follow");
  }
  if (frame_size < available) {
    fail(str(available - frame_size) + " unexpected bytes after the zstd frame");
  }
  const std::vector<uint8_t> payload = decompress(bytes.subspan(kHeaderBytes), payload_size);
  VectorImage image = decode_payload(payload, version, flags);
  validate(image);
  return image;
}

std::vector<uint8_t> to_svec_binary(const VectorImage& image, const SvecWriteOptions& options) {
  if (options.position_bits < 0 || options.position_bits > kMaxPositionBits ||
      options.color_bits < kMinColorBits || options.color_bits > kMaxColorBits) {
    fail("position bits " + std::to_string(options.position_bits) + " and color bits " +
             std::to_string(options.color_bits) + " out of range (0 to " +
             str(kMaxPositionBits) + " and " + std::to_string(kMinColorBits) + " to " +
             str(kMaxColorBits) + ")",
         ErrorCode::kInvalidArgument);
  }
  if (options.compact_version != int(kCompactVersion) &&
      options.compact_version != int(kCodedVersion)) {
    fail("compact .svec version " + std::to_string(options.compact_version) +
             " is not one this build writes (2 or 3)",
         ErrorCode::kInvalidArgument);
  }
  const auto compact = static_cast<uint32_t>(options.compact_version);
  // The compact form quantizes each level, with finer positions when the coarse grid would flip or
  // collapse a triangle, and falls back to version 1 when even the finest grid does.
  uint32_t version = options.lossless ? kLosslessVersion : compact;
  VectorImage quantized;
  std::vector<std::array<int, 2>> bits;
  if (version == compact) {
    validate(image);
    quantized.width = image.width;
    quantized.height = image.height;
    quantized.strokes = image.strokes;
    quantized.objects = image.objects;
    quantized.metadata = image.metadata;
    for (size_t l = 0; l < image.levels.size() && version == compact; ++l) {
      version = kLosslessVersion;
      for (int p = options.position_bits; p <= kMaxPositionBits; ++p) {
        ControlMesh q = quantize_positions(image.levels[l], image.width, image.height, p);
        try {
          validate_level(q, image.width, image.height, int(l));
        } catch (const Error&) {
          continue;
        }
        quantized.levels.push_back(std::move(q));
        bits.push_back({p, options.color_bits});
        version = compact;
        break;
      }
    }
  }
  std::vector<size_t> block_ends;
  const std::vector<uint8_t> payload =
      version == kLosslessVersion ? encode_payload_v1(image)
                                  : encode_payload_compact(quantized, version, bits, block_ends);
  if (payload.size() > kMaxPayloadBytes) {
    fail("image too large for a .svec file (" + str(payload.size()) + " bytes of payload, limit " +
             str(kMaxPayloadBytes) + ")",
         ErrorCode::kLimit);
  }
  const std::vector<uint8_t> frame = compress(payload, block_ends);
  ByteWriter w;
  w.bytes.assign(kMagic.begin(), kMagic.end());
  w.u32(version);
  w.u32(header_flags(image));
  w.u64(payload.size());
  w.u64(frame.size());
  w.bytes.insert(w.bytes.end(), frame.begin(), frame.end());
  return std::move(w.bytes);
}

}  // namespace subvec
