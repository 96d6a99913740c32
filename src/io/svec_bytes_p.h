// Private byte-level helpers of the .svec binary reader and writer (svec_binary.cpp,
// svec_compact.cpp): a little-endian writer and a bounds-checked cursor that names what it was
// reading when the bytes run out, plus LEB128 varints for the compact (version 2) payload.
#pragma once

#include <bit>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "subvec/core/error.h"
#include "subvec/mesh/validate.h"

namespace subvec::svec_detail {

[[noreturn]] inline void fail(const std::string& message, ErrorCode code = ErrorCode::kBadFile) {
  throw Error(code, message);
}

inline std::string str(uint64_t v) { return std::to_string(v); }

// Unsigned LEB128 and the zigzag map of signed values onto unsigned ones (0, -1, 1, -2, ...).
inline void put_varint(std::vector<uint8_t>& out, uint64_t v) {
  while (v >= 0x80) {
    out.push_back(static_cast<uint8_t>(v | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<uint8_t>(v));
}
inline uint64_t zigzag(int64_t v) {
  return (static_cast<uint64_t>(v) << 1) ^ static_cast<uint64_t>(v >> 63);
}
inline int64_t unzigzag(uint64_t v) {
  return static_cast<int64_t>(v >> 1) ^ -static_cast<int64_t>(v & 1);
}

class ByteWriter {
 public:
  std::vector<uint8_t> bytes;

  void u32(uint32_t v) {
    for (int k = 0; k < 4; ++k) bytes.push_back(static_cast<uint8_t>(v >> (8 * k)));
  }
  void u64(uint64_t v) {
    for (int k = 0; k < 8; ++k) bytes.push_back(static_cast<uint8_t>(v >> (8 * k)));
  }
  void i32(int32_t v) { u32(static_cast<uint32_t>(v)); }
  void f32(float v) { u32(std::bit_cast<uint32_t>(v)); }
  void f64(double v) { u64(std::bit_cast<uint64_t>(v)); }
  void count(size_t n, const char* what) {
    if (n > UINT32_MAX)
      fail(std::string("too many ") + what + " for a .svec file", ErrorCode::kLimit);
    u32(static_cast<uint32_t>(n));
  }
  void string(const std::string& s) {
    count(s.size(), "bytes in a metadata string");
    bytes.insert(bytes.end(), s.begin(), s.end());
  }
};

class Cursor {
 public:
  explicit Cursor(std::span<const uint8_t> bytes) : bytes_(bytes) {}

  // What is being read, for messages: "level 0 triangles".
  void set_context(std::string what) { context_ = std::move(what); }
  size_t remaining() const { return bytes_.size() - pos_; }

  const uint8_t* take(size_t n) {
    if (n > remaining()) {
      fail("truncated payload while reading " + context_ + " (needs " + str(n) +
           " bytes at offset " + str(pos_) + ", " + str(remaining()) + " left)");
    }
    const uint8_t* p = bytes_.data() + pos_;
    pos_ += n;
    return p;
  }
  uint32_t u32() {
    const uint8_t* p = take(4);
    uint32_t v = 0;
    for (int k = 0; k < 4; ++k) v |= uint32_t{p[k]} << (8 * k);
    return v;
  }
  uint64_t u64() {
    const uint8_t* p = take(8);
    uint64_t v = 0;
    for (int k = 0; k < 8; ++k) v |= uint64_t{p[k]} << (8 * k);
    return v;
  }
  int32_t i32() { return static_cast<int32_t>(u32()); }
  uint8_t u8() { return *take(1); }
  // An unsigned LEB128 varint of at most 64 bits.
  uint64_t varint() {
    uint64_t v = 0;
    for (int shift = 0;; shift += 7) {
      const uint8_t b = u8();
      if (shift == 63 && (b & 0x7E) != 0) fail("malformed varint while reading " + context_);
      v |= uint64_t{b & 0x7Fu} << shift;
      if ((b & 0x80) == 0) return v;
      if (shift == 63) fail("malformed varint while reading " + context_);
    }
  }
  int64_t svarint() { return unzigzag(varint()); }
  float f32() { return std::bit_cast<float>(u32()); }
  double f64() { return std::bit_cast<double>(u64()); }

  // An element count, capped by `max` and by the bytes left (each element takes at least
  // `min_bytes`), so that no vector is sized from an unchecked number.
  size_t count(const std::string& what, size_t min_bytes, int64_t max = Limits::kMaxElements) {
    set_context(what + " count");
    const uint32_t n = u32();
    if (n > max) {
      fail(what + ": count " + str(n) + " is over the limit of " + str(uint64_t(max)),
           ErrorCode::kLimit);
    }
    set_context(what);
    if (uint64_t{n} * min_bytes > remaining()) {
      fail("truncated payload while reading " + what + " (" + str(n) + " declared, needing " +
           str(uint64_t{n} * min_bytes) + " bytes at offset " + str(pos_) + ", " +
           str(remaining()) + " left)");
    }
    return n;
  }

  std::string string(const std::string& what) {
    const size_t n = count(what, 1);
    const uint8_t* p = take(n);
    return std::string(reinterpret_cast<const char*>(p), n);
  }

 private:
  std::span<const uint8_t> bytes_;
  size_t pos_ = 0;
  std::string context_ = "the payload";
};

}  // namespace subvec::svec_detail
