// Private constants and helpers shared by the .svec.json and .svec readers and writers.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>

namespace subvec::svec_detail {

// .svec binary header: magic, then u32 version, u32 flags, u64 payload size, u64 frame size.
inline constexpr std::array<uint8_t, 8> kMagic = {'S', 'U', 'B', 'V', 'E', 'C', 0x00, 0x1A};
inline constexpr uint32_t kLosslessVersion = 1;  // exact values, the image's own order
inline constexpr uint32_t kCompactVersion = 2;   // quantized, predicted, traversal order
inline constexpr uint32_t kCodedVersion = 3;     // version 2's content, range-coded
// Header flag: the payload holds objects (mesh/vector_image.h) after its levels. Files without
// objects have no flag and are byte for byte what builds before objects wrote.
inline constexpr uint32_t kObjectsFlag = 1;
// Header flag: the objects carry strokes (only with kObjectsFlag).
inline constexpr uint32_t kObjectStrokesFlag = 2;
inline constexpr size_t kHeaderBytes = 8 + 4 + 4 + 8 + 8;
inline constexpr uint64_t kMaxPayloadBytes = uint64_t{1} << 30;  // 1 GiB uncompressed
inline constexpr int kZstdLevel = 9;

// .svec.json: version 1, or 2 when the image has objects (the "objects" member).
inline constexpr int kJsonVersion = 1;
inline constexpr int kJsonObjectsVersion = 2;
inline constexpr int kMaxJsonDepth = 32;

// Largest file read_svec() accepts (either form).
inline constexpr int64_t kMaxFileBytes = int64_t{1} << 30;  // 1 GiB

// Messages are one line: control characters (from keys in a file, say) become \xNN escapes.
inline std::string one_line(std::string s) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  out.reserve(s.size());
  for (char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c < 0x20 || c == 0x7F) {
      out += "\\x";
      out += digits[c >> 4];
      out += digits[c & 15];
    } else {
      out += ch;
    }
  }
  return out;
}

inline bool has_magic(std::span<const uint8_t> bytes) {
  if (bytes.size() < kMagic.size()) return false;
  for (size_t i = 0; i < kMagic.size(); ++i)
    if (bytes[i] != kMagic[i]) return false;
  return true;
}

}  // namespace subvec::svec_detail
