// Raster image files through OpenCV, and PNG through libpng (io/image_io.h).
//
// Reading: the whole file is read into memory (io/file.h), its size checked against `max_pixels`
// from the header where we can parse it cheaply (PNG IHDR, JPEG SOFn, BMP DIB header, WebP VP8 /
// VP8L / VP8X, the first TIFF directory) before anything is decoded, and again after decoding.
// Everything becomes 8-bit RGB:
//  - gray (and gray + alpha) is replicated to R = G = B;
//  - 16-bit samples are scaled by 255/65535 with rounding, float samples are taken as 0-1;
//  - alpha is composited over black (c * a / 255), so a transparent pixel reads as black; this
//    matches the renderer, whose transparent pixels outside the image are (0, 0, 0, 0);
//  - JPEG is decoded with OpenCV's colour path, which converts CMYK/YCCK and applies the EXIF
//    orientation; other formats are decoded as stored (IMREAD_UNCHANGED keeps alpha and depth).
// A PNG whose chunks are cut short or fail their CRC, a JPEG whose entropy-coded data has no
// end-of-image marker, and a BMP shorter than its rows are reported as truncated before decoding
// (libjpeg would fill the missing rows with grey). PNG is decoded with libpng directly, so that its
// errors become messages instead of lines on stderr (decode_png). An image whose header declares
// no pixels, or a TIFF whose size cannot be found in its header, is refused before decoding.
// Other formats are refused before decoding. OpenCV's own messages about damaged files (std::cerr)
// are muted during the decode; libjpeg may still print a warning about a damaged but readable JPEG
// ("Corrupt JPEG data: ...").
//
// OpenCV's image codecs depend on some 120 shared libraries (GDAL, GDCM, HDF5, poppler, ...), and
// loading them cost every start of a program 0.15 s. PNG, what the tools read most, is read
// through libpng; the codecs are loaded (dlopen) when the first other image is read.
//
// Writing: PNG through the parallel encoder (io/png_encoder_p.h), then written atomically
// (AtomicFile, io/file.h).
#include "subvec/io/image_io.h"

#include <dlfcn.h>
#include <png.h>

#include <algorithm>
#include <array>
#include <bit>
#include <csetjmp>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <mutex>
#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "io/png_encoder_p.h"
#include "subvec/core/error.h"
#include "subvec/io/file.h"

namespace subvec {
namespace {

namespace fs = std::filesystem;

std::string in_quotes(const fs::path& path) { return "'" + path.string() + "'"; }

[[noreturn]] void fail(ErrorCode code, const fs::path& path, const std::string& why) {
  throw Error(code, "cannot read image " + in_quotes(path) + ": " + why);
}

// OpenCV logs decoder warnings to stderr; the library reports through exceptions instead.
void silence_opencv() {
  static const bool once = [] {
    cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
    return true;
  }();
  (void)once;
}

// cv::imdecode prints a decoder's exception to std::cerr ("imdecode_(''): can't read data: ...")
// before it returns an empty image, for damaged TIFF, WebP and BMP files alike. The library
// reports through exceptions, so std::cerr is muted while any decode runs. It is a process-wide
// stream: what another thread writes to std::cerr meanwhile is lost too.
class MutedCerr {
 public:
  MutedCerr() {
    const std::lock_guard<std::mutex> lock(mutex());
    if (depth()++ == 0) saved() = std::cerr.rdbuf(nullptr);
  }
  ~MutedCerr() {
    const std::lock_guard<std::mutex> lock(mutex());
    if (--depth() == 0) {
      std::cerr.rdbuf(saved());
      std::cerr.clear();  // writes to a null buffer set badbit
    }
  }
  MutedCerr(const MutedCerr&) = delete;
  MutedCerr& operator=(const MutedCerr&) = delete;

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  static int& depth() {
    static int d = 0;
    return d;
  }
  static std::streambuf*& saved() {
    static std::streambuf* s = nullptr;
    return s;
  }
};

// cv::imdecode from OpenCV's codec library, loaded on first use (see the top of this file), or
// what kept it from loading.
using Imdecode = cv::Mat (*)(cv::InputArray, int);
// Compiles only while the header declares cv::imdecode with this type (unevaluated: not linked).
static_assert(sizeof(static_cast<Imdecode>(&cv::imdecode)) > 0);
std::pair<Imdecode, std::string> load_imdecode() {
  static const std::pair<Imdecode, std::string> loaded = []() -> std::pair<Imdecode, std::string> {
    void* library = dlopen(SUBVEC_OPENCV_IMGCODECS, RTLD_NOW | RTLD_LOCAL);
    if (library == nullptr) return {nullptr, dlerror()};
    // cv::imdecode(cv::InputArray, int) under its C++ (Itanium ABI) name.
    void* symbol = dlsym(library, "_ZN2cv8imdecodeERKNS_11_InputArrayEi");
    if (symbol == nullptr) return {nullptr, dlerror()};
    return {reinterpret_cast<Imdecode>(symbol), ""};
  }();
  return loaded;
}

uint32_t big_endian_u32(const uint8_t* p) {
  return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | uint32_t(p[3]);
}
uint32_t big_endian_u16(const uint8_t* p) { return uint32_t(p[0]) << 8 | uint32_t(p[1]); }

bool is_png(const std::vector<uint8_t>& b) {
  static constexpr uint8_t kMagic[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  return b.size() >= 8 && std::memcmp(b.data(), kMagic, 8) == 0;
}
bool is_jpeg(const std::vector<uint8_t>& b) {
  return b.size() >= 3 && b[0] == 0xff && b[1] == 0xd8 && b[2] == 0xff;
}

struct HeaderSize {
  int64_t width = -1, height = -1;  // -1: not known from the header
};

// PNG: signature, then the IHDR chunk (length, "IHDR", width, height as big-endian u32).
HeaderSize png_size(const std::vector<uint8_t>& b) {
  if (b.size() < 24 || std::memcmp(b.data() + 12, "IHDR", 4) != 0) return {};
  return {big_endian_u32(b.data() + 16), big_endian_u32(b.data() + 20)};
}

// libpng reports a broken stream on stderr before OpenCV sees the failure, so the chunk structure
// is checked here first: every chunk inside the file with a correct CRC-32, up to IEND.
uint32_t crc32(const uint8_t* data, size_t n) {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xedb88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  uint32_t crc = 0xffffffffu;
  for (size_t i = 0; i < n; ++i) crc = table[(crc ^ data[i]) & 0xff] ^ (crc >> 8);
  return crc ^ 0xffffffffu;
}

bool png_complete(const std::vector<uint8_t>& b) {
  size_t pos = 8;
  while (pos + 12 <= b.size()) {
    const size_t length = big_endian_u32(b.data() + pos);
    if (length > b.size() - pos - 12) return false;
    const uint8_t* type = b.data() + pos + 4;
    if (crc32(type, length + 4) != big_endian_u32(type + 4 + length)) return false;
    if (std::memcmp(type, "IEND", 4) == 0) return true;
    pos += 12 + length;
  }
  return false;
}

// JPEG: walk the marker segments up to the first start-of-frame (SOF0-SOF15 except DHT C4, JPG
// C8 and DAC CC), whose payload is precision (1 byte), height, width (big-endian u16). Also reports
// whether an end-of-image marker follows the start of scan: inside entropy-coded data 0xFF is
// always followed by 0x00 or a restart marker, so 0xFF 0xD9 after SOS is the real EOI.
struct JpegScan {
  HeaderSize size;
  bool complete = false;
};
JpegScan scan_jpeg(const std::vector<uint8_t>& b) {
  JpegScan scan;
  size_t i = 2;
  while (i + 4 <= b.size()) {
    if (b[i] != 0xff) return scan;  // not a marker: malformed, let the decoder complain
    const uint8_t marker = b[i + 1];
    if (marker == 0xff) {  // fill byte
      ++i;
      continue;
    }
    if (marker == 0x01 || (marker >= 0xd0 && marker <= 0xd7)) {  // markers without a length
      i += 2;
      continue;
    }
    const size_t length = big_endian_u16(b.data() + i + 2);
    const bool sof =
        marker >= 0xc0 && marker <= 0xcf && marker != 0xc4 && marker != 0xc8 && marker != 0xcc;
    if (sof && i + 9 <= b.size() && scan.size.width < 0) {
      scan.size = {big_endian_u16(b.data() + i + 7), big_endian_u16(b.data() + i + 5)};
    }
    if (marker == 0xda) {  // start of scan: look for EOI in the rest
      for (size_t j = i + 2 + length; j + 1 < b.size(); ++j) {
        if (b[j] == 0xff && b[j + 1] == 0xd9) {
          scan.complete = true;
          break;
        }
      }
      return scan;
    }
    i += 2 + length;
  }
  return scan;
}

uint32_t little_endian_u32(const uint8_t* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}
uint32_t little_endian_u16(const uint8_t* p) { return uint32_t(p[0]) | uint32_t(p[1]) << 8; }

bool is_bmp(const std::vector<uint8_t>& b) { return b.size() >= 2 && b[0] == 'B' && b[1] == 'M'; }
bool is_webp(const std::vector<uint8_t>& b) {
  return b.size() >= 12 && std::memcmp(b.data(), "RIFF", 4) == 0 &&
         std::memcmp(b.data() + 8, "WEBP", 4) == 0;
}
bool is_tiff(const std::vector<uint8_t>& b) {  // classic (42) or BigTIFF (43), either byte order
  return b.size() >= 4 &&
         ((b[0] == 'I' && b[1] == 'I' && (b[2] == 42 || b[2] == 43) && b[3] == 0) ||
          (b[0] == 'M' && b[1] == 'M' && b[2] == 0 && (b[3] == 42 || b[3] == 43)));
}

// BMP: "BM", then at 14 the DIB header: its size, then width and height (16-bit in the old
// 12-byte core header, else signed 32-bit; a negative height means top-down rows).
HeaderSize bmp_size(const std::vector<uint8_t>& b) {
  if (b.size() < 26 || b[0] != 'B' || b[1] != 'M') return {};
  const uint32_t dib = little_endian_u32(b.data() + 14);
  if (dib == 12) return {little_endian_u16(b.data() + 18), little_endian_u16(b.data() + 20)};
  const auto width = int32_t(little_endian_u32(b.data() + 18)),
             height = int32_t(little_endian_u32(b.data() + 22));
  return {std::abs(int64_t{width}), std::abs(int64_t{height})};
}

// OpenCV's BMP decoder prints to std::cerr when the file ends early, so check first that it holds
// its headers and, for uncompressed pixels, every row (rows padded to 4 bytes); for RLE the size
// the file header declares, when it declares one.
bool bmp_complete(const std::vector<uint8_t>& b) {
  if (b.size() < 26) return false;
  const uint32_t declared = little_endian_u32(b.data() + 2),
                 offset = little_endian_u32(b.data() + 10);
  const uint32_t dib = little_endian_u32(b.data() + 14);
  if (dib < 12 || b.size() < 14 + uint64_t{dib} || offset < 14 + uint64_t{dib} || offset > b.size())
    return false;
  int64_t width, height;
  uint32_t bits, compression = 0;
  if (dib == 12) {
    width = little_endian_u16(b.data() + 18), height = little_endian_u16(b.data() + 20);
    bits = little_endian_u16(b.data() + 24);
  } else {
    if (dib < 40) return false;
    width = std::abs(int64_t{int32_t(little_endian_u32(b.data() + 18))});
    height = std::abs(int64_t{int32_t(little_endian_u32(b.data() + 22))});
    bits = little_endian_u16(b.data() + 28), compression = little_endian_u32(b.data() + 30);
  }
  if (compression == 0 || compression == 3 || compression == 6) {  // RGB, BITFIELDS, ALPHABITFIELDS
    const int64_t row = (int64_t{bits} * width + 31) / 32 * 4;
    return int64_t(b.size()) - offset >= row * height;
  }
  return declared == 0 || b.size() >= declared;
}

// WebP: "RIFF" size "WEBP", then the first chunk: "VP8 " (lossy: 14-bit sizes after the start
// code 9d 01 2a), "VP8L" (lossless: signature 0x2f, then 14-bit width - 1 and height - 1) or
// "VP8X" (extended: 24-bit canvas width - 1 and height - 1).
HeaderSize webp_size(const std::vector<uint8_t>& b) {
  if (b.size() < 30 || std::memcmp(b.data(), "RIFF", 4) != 0 ||
      std::memcmp(b.data() + 8, "WEBP", 4) != 0)
    return {};
  const uint8_t* chunk = b.data() + 12;
  const uint8_t* data = chunk + 8;
  if (std::memcmp(chunk, "VP8 ", 4) == 0 && data[3] == 0x9d && data[4] == 0x01 && data[5] == 0x2a) {
    return {little_endian_u16(data + 6) & 0x3fff, little_endian_u16(data + 8) & 0x3fff};
  }
  if (std::memcmp(chunk, "VP8L", 4) == 0 && data[0] == 0x2f) {
    const uint32_t bits = little_endian_u32(data + 1);
    return {(bits & 0x3fff) + 1, ((bits >> 14) & 0x3fff) + 1};
  }
  if (std::memcmp(chunk, "VP8X", 4) == 0) {
    const auto u24 = [](const uint8_t* p) {
      return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16;
    };
    return {int64_t{u24(data + 4)} + 1, int64_t{u24(data + 7)} + 1};
  }
  return {};
}

// TIFF (classic or BigTIFF, either byte order): the first image file directory's ImageWidth (256)
// and ImageLength (257) entries, SHORT, LONG or (BigTIFF) LONG8.
HeaderSize tiff_size(const std::vector<uint8_t>& b) {
  if (b.size() < 8) return {};
  const bool little = b[0] == 'I' && b[1] == 'I';
  const auto u16 = [&](size_t at) {
    return little ? little_endian_u16(b.data() + at) : big_endian_u16(b.data() + at);
  };
  const auto u32 = [&](size_t at) {
    return little ? little_endian_u32(b.data() + at) : big_endian_u32(b.data() + at);
  };
  const auto u64 = [&](size_t at) {
    const uint64_t lo = u32(at + (little ? 0 : 4)), hi = u32(at + (little ? 4 : 0));
    return hi << 32 | lo;
  };
  const bool big_tiff = u16(2) == 43;
  // Classic: 4-byte directory offset, 2-byte entry count, 12-byte entries with the value at 8.
  // BigTIFF: 8-byte offset at 8, 8-byte entry count, 20-byte entries with the value at 12.
  if (big_tiff && b.size() < 16) return {};
  const uint64_t ifd = big_tiff ? u64(8) : u32(4);
  const size_t count_size = big_tiff ? 8 : 2, entry_size = big_tiff ? 20 : 12;
  if (ifd > b.size() || b.size() - ifd < count_size) return {};
  const uint64_t entries = big_tiff ? u64(ifd) : u16(ifd);
  HeaderSize size;
  for (uint64_t k = 0; k < entries && k < 4096; ++k) {
    const size_t e = ifd + count_size + entry_size * k;
    if (e + entry_size > b.size()) break;
    const uint32_t tag = u16(e), type = u16(e + 2);
    if (tag != 256 && tag != 257) continue;
    const size_t value = e + (big_tiff ? 12 : 8);
    int64_t v;
    if (type == 3) {
      v = u16(value);
    } else if (type == 4) {
      v = u32(value);
    } else if (type == 16 && big_tiff) {
      v = static_cast<int64_t>(std::min<uint64_t>(u64(value), uint64_t{1} << 62));
    } else {
      continue;
    }
    (tag == 256 ? size.width : size.height) = v;
  }
  return size.width >= 0 && size.height >= 0 ? size : HeaderSize{};
}

void check_pixels(const fs::path& path, int64_t width, int64_t height, int64_t max_pixels) {
  // width * height > max_pixels, without overflow for 32-bit header fields.
  if (width > 0 && height > max_pixels / width) {
    throw Error(ErrorCode::kLimit, "cannot read image " + in_quotes(path) + ": " +
                                       std::to_string(width) + "x" + std::to_string(height) +
                                       " pixels is over the limit of " +
                                       std::to_string(max_pixels) + " pixels");
  }
}

// The size a header declares: refused when empty or over the limit.
void check_header(const fs::path& path, const HeaderSize& size, int64_t max_pixels) {
  if (size.width < 0) return;
  if (size.width == 0 || size.height == 0) {
    fail(ErrorCode::kBadFile, path,
         "the header declares " + std::to_string(size.width) + "x" + std::to_string(size.height) +
             " pixels");
  }
  check_pixels(path, size.width, size.height, max_pixels);
}

// ---- PNG through libpng ----------------------------------------------------------------------
//
// OpenCV's PNG decoder keeps libpng's default handlers, which print "libpng error: ..." and
// "libpng warning: ..." on stderr. Decoding here, errors become the exception's message and
// warnings are dropped. The result is what OpenCV's IMREAD_UNCHANGED gives: gray, gray + alpha,
// BGR or BGRA, 8 or 16 bits per sample; palettes and tRNS expanded.

struct PngInput {
  const uint8_t* data;
  size_t size, pos;
};

struct PngError {
  std::string message;
};

void png_on_error(png_structp png, png_const_charp message) {
  static_cast<PngError*>(png_get_error_ptr(png))->message = message ? message : "unknown error";
  png_longjmp(png, 1);
}
void png_on_warning(png_structp, png_const_charp) {}

void png_read_bytes(png_structp png, png_bytep out, png_size_t n) {
  auto* in = static_cast<PngInput*>(png_get_io_ptr(png));
  if (n > in->size - in->pos) png_error(png, "file is truncated");
  std::memcpy(out, in->data + in->pos, n);
  in->pos += n;
}

class PngReadStruct {
 public:
  explicit PngReadStruct(PngError* error)
      : png_(png_create_read_struct(PNG_LIBPNG_VER_STRING, error, png_on_error, png_on_warning)),
        info_(png_ ? png_create_info_struct(png_) : nullptr) {
    if (!png_ || !info_) throw std::bad_alloc();
  }
  ~PngReadStruct() { png_destroy_read_struct(&png_, &info_, nullptr); }
  PngReadStruct(const PngReadStruct&) = delete;
  PngReadStruct& operator=(const PngReadStruct&) = delete;
  png_structp png() const { return png_; }
  png_infop info() const { return info_; }

 private:
  png_structp png_;
  png_infop info_;
};

// Ancillary chunks (text, ICC profiles) may be compressed: at most this much memory for one.
constexpr png_alloc_size_t kMaxPngChunkBytes = png_alloc_size_t{8} << 20;

cv::Mat decode_png(const std::vector<uint8_t>& bytes, const fs::path& path, int64_t max_pixels) {
  PngError error;
  PngInput input{bytes.data(), bytes.size(), 0};
  const PngReadStruct s(&error);
  png_structp png = s.png();
  png_infop info = s.info();
  cv::Mat out;
  std::vector<png_bytep> rows;
  // libpng reports errors by longjmp back here; only C frames and the callbacks above (which hold
  // no objects with destructors) lie between.
  if (setjmp(png_jmpbuf(png))) {
    fail(ErrorCode::kBadFile, path, "damaged PNG data (" + error.message + ")");
  }
  png_set_read_fn(png, &input, png_read_bytes);
  png_set_user_limits(png, 1u << 24, 1u << 24);  // wider than any image under the pixel limit
  png_set_chunk_malloc_max(png, kMaxPngChunkBytes);
  png_read_info(png, info);
  const png_uint_32 width = png_get_image_width(png, info), height = png_get_image_height(png, info);
  check_pixels(path, width, height, max_pixels);
  png_set_expand(png);  // palette to BGR, gray under 8 bits to 8, tRNS to alpha
  png_set_bgr(png);
  if (png_get_bit_depth(png, info) == 16 && std::endian::native == std::endian::little)
    png_set_swap(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  const int channels = png_get_channels(png, info);
  const int depth = png_get_bit_depth(png, info) == 16 ? CV_16U : CV_8U;
  out.create(int(height), int(width), CV_MAKETYPE(depth, channels));
  rows.resize(height);
  for (png_uint_32 y = 0; y < height; ++y) rows[y] = out.ptr<png_byte>(int(y));
  png_read_image(png, rows.data());
  png_read_end(png, nullptr);
  return out;
}

// Any decoded depth to 8 bits per sample.
cv::Mat to_8bit(const cv::Mat& m, const fs::path& path) {
  cv::Mat out;
  switch (m.depth()) {
    case CV_8U:
      return m;
    case CV_16U:
      m.convertTo(out, CV_8U, 255.0 / 65535.0);
      return out;
    case CV_32F:
    case CV_64F:
      m.convertTo(out, CV_8U, 255.0);
      return out;
    default:
      fail(ErrorCode::kBadFile, path, "unsupported sample type (signed integers)");
  }
}

}  // namespace

std::string image_format_name(const std::vector<uint8_t>& bytes) {
  if (is_png(bytes)) return "PNG";
  if (is_jpeg(bytes)) return "JPEG";
  if (is_webp(bytes)) return "WebP";
  if (is_tiff(bytes)) return "TIFF";
  if (is_bmp(bytes)) return "BMP";
  if (bytes.size() >= 6 && std::memcmp(bytes.data(), "GIF8", 4) == 0) return "GIF";
  if (bytes.size() >= 5 && std::memcmp(bytes.data(), "%PDF-", 5) == 0) return "PDF";
  // SVG: XML text (after a byte order mark, blanks, a prolog or comments) with an <svg element
  // near its start.
  const std::string_view head(reinterpret_cast<const char*>(bytes.data()),
                              std::min<size_t>(bytes.size(), 4096));
  const size_t first = head.find_first_not_of(" \t\r\n\xEF\xBB\xBF");
  if (first != std::string_view::npos && head[first] == '<' && head.find("<svg") != std::string_view::npos)
    return "SVG";
  return "";
}

bool is_raster_input(const std::string& format) {
  return format == "PNG" || format == "JPEG" || format == "WebP" || format == "TIFF" || format == "BMP";
}

Image8 read_image(const fs::path& path, int64_t max_pixels) {
  silence_opencv();
  // A missing file or a directory: read_file's messages, the same for every reader.
  const std::vector<uint8_t> bytes = read_file(path);
  if (bytes.empty()) fail(ErrorCode::kBadFile, path, "file is empty");

  // Only the five documented formats reach the decoders.
  constexpr const char* kTruncated = "file is truncated or not an image";
  int flags = cv::IMREAD_UNCHANGED;
  if (is_png(bytes)) {
    check_header(path, png_size(bytes), max_pixels);
    if (!png_complete(bytes)) fail(ErrorCode::kBadFile, path, kTruncated);
  } else if (is_jpeg(bytes)) {
    const JpegScan scan = scan_jpeg(bytes);
    check_header(path, scan.size, max_pixels);
    if (!scan.complete) fail(ErrorCode::kBadFile, path, kTruncated);
    flags = cv::IMREAD_COLOR;  // CMYK conversion and EXIF orientation; JPEG has no alpha
  } else if (is_bmp(bytes)) {
    check_header(path, bmp_size(bytes), max_pixels);
    if (!bmp_complete(bytes)) fail(ErrorCode::kBadFile, path, kTruncated);
  } else if (is_webp(bytes)) {
    check_header(path, webp_size(bytes), max_pixels);
  } else if (is_tiff(bytes)) {
    // Without the size from the header the limit could not be checked before decoding.
    const HeaderSize size = tiff_size(bytes);
    if (size.width < 0) {
      fail(ErrorCode::kBadFile, path,
           std::string(kTruncated) + " (no image size in the TIFF header)");
    }
    check_header(path, size, max_pixels);
  } else {
    fail(ErrorCode::kBadFile, path, "not a PNG, JPEG, WebP, TIFF or BMP file");
  }

  cv::Mat decoded;
  if (is_png(bytes)) {
    decoded = decode_png(bytes, path, max_pixels);
  } else {
    const auto [imdecode, why] = load_imdecode();
    if (imdecode == nullptr) fail(ErrorCode::kIo, path, "OpenCV's image codecs did not load (" + why + ")");
    try {
      // cv::imdecode takes a non-const Mat header over the buffer but does not write to it.
      const cv::Mat buffer(1, int(bytes.size()), CV_8U, const_cast<uint8_t*>(bytes.data()));
      const MutedCerr quiet;
      decoded = imdecode(buffer, flags);
    } catch (const cv::Exception&) {
      decoded.release();
    }
  }
  if (decoded.empty() || decoded.dims != 2) {
    fail(ErrorCode::kBadFile, path, kTruncated);
  }
  check_pixels(path, decoded.cols, decoded.rows, max_pixels);

  const cv::Mat m = to_8bit(decoded, path);
  const int channels = m.channels();
  if (channels < 1 || channels > 4) {
    fail(ErrorCode::kBadFile, path, "unsupported channel count " + std::to_string(channels));
  }

  Image8 image(m.cols, m.rows, 3);
  for (int y = 0; y < m.rows; ++y) {
    const uint8_t* src = m.ptr<uint8_t>(y);
    uint8_t* dst = image.row(y);
    for (int x = 0; x < m.cols; ++x, src += channels, dst += 3) {
      // OpenCV orders colour samples B, G, R; gray is one sample, gray + alpha two.
      int r, g, b, a = 255;
      if (channels <= 2) {
        r = g = b = src[0];
        if (channels == 2) a = src[1];
      } else {
        b = src[0];
        g = src[1];
        r = src[2];
        if (channels == 4) a = src[3];
      }
      // Over black: c * a / 255, rounded.
      dst[0] = uint8_t((r * a + 127) / 255);
      dst[1] = uint8_t((g * a + 127) / 255);
      dst[2] = uint8_t((b * a + 127) / 255);
    }
  }
  return image;
}

std::vector<uint8_t> encode_png(const Image8& image, int threads) {
  if (image.width <= 0 || image.height <= 0 || (image.channels != 3 && image.channels != 4) ||
      image.pixels.size() != size_t(image.width) * size_t(image.height) * size_t(image.channels)) {
    throw Error(ErrorCode::kInvalidArgument, "the image is empty or malformed");
  }
  detail::PngEncoder encoder(image.width, image.height, image.channels, threads);
  std::vector<uint8_t> out;
  encoder.begin(out);
  encoder.rows(image.pixels.data(), image.height, out);
  encoder.end(out);
  return out;
}

void write_png(const fs::path& path, const Image8& image) {
  std::vector<uint8_t> encoded;
  try {
    encoded = encode_png(image);
  } catch (const Error& e) {
    throw Error(e.code(), "cannot write " + in_quotes(path) + ": " + e.what());
  }
  write_file_atomic(path, encoded);
}

// ---- PngWriter ---------------------------------------------------------------------------------

struct PngWriter::Impl {
  Impl(const fs::path& target, int w, int h, int c, int threads)
      : file(target), encoder(w, h, c, threads) {}
  AtomicFile file;  // the temporary file, renamed onto the target by finish()
  detail::PngEncoder encoder;
  bool done = false;
  std::vector<uint8_t> buffer;  // encoded bytes not yet written to the file

  void flush_buffer() {
    file.write(buffer);
    buffer.clear();
  }
};

PngWriter::PngWriter(const fs::path& path, int width, int height, int channels, int threads) {
  if (width <= 0 || height <= 0 || (channels != 3 && channels != 4) || width > (1 << 24) ||
      height > (1 << 24)) {
    throw Error(ErrorCode::kInvalidArgument, "cannot write " + in_quotes(path) + ": size " +
                                                 std::to_string(width) + " x " +
                                                 std::to_string(height) + " x " +
                                                 std::to_string(channels) + " is not an image");
  }
  impl_ = std::make_unique<Impl>(path, width, height, channels, threads);
  impl_->encoder.begin(impl_->buffer);
}

PngWriter::~PngWriter() = default;

void PngWriter::write_rows(const Image8& rows) {
  Impl& m = *impl_;
  const detail::PngEncoder& e = m.encoder;
  if (m.done || rows.width != e.width() || rows.channels != e.channels() || rows.height < 0 ||
      rows.height > e.height() - e.rows_given() ||
      rows.pixels.size() != size_t(rows.width) * size_t(rows.height) * size_t(rows.channels)) {
    throw Error(ErrorCode::kInvalidArgument,
                "cannot write " + in_quotes(m.file.path()) + ": rows that do not fit the image");
  }
  m.encoder.rows(rows.pixels.data(), rows.height, m.buffer);
  m.flush_buffer();
}

void PngWriter::finish() {
  Impl& m = *impl_;
  if (m.done || m.encoder.rows_given() != m.encoder.height()) {
    throw Error(ErrorCode::kInvalidArgument, "cannot write " + in_quotes(m.file.path()) + ": " +
                                                 std::to_string(m.encoder.rows_given()) + " of " +
                                                 std::to_string(m.encoder.height()) +
                                                 " rows written");
  }
  m.encoder.end(m.buffer);
  m.flush_buffer();
  m.file.commit();
  m.done = true;
}

}  // namespace subvec
