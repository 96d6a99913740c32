// The adaptive binary range coder of `.svec` version 3 (docs/format.md, "The range coder"):
// LZMA's carry-less-decoder range coder with 12-bit probabilities adapted by a shift, written
// out here so that the format does not depend on any library's internals. Integer-only and
// deterministic: the same bits in the same contexts give the same bytes on every machine.
//
// Encoder: a 33-bit `low` and a 32-bit `range`; a decision with probability p/4096 of a 0 keeps
// the lower (range >> 12) * p of the range for a 0 and the rest for a 1; the top byte of `low`
// leaves whenever the range falls under 2^24 (carries ripple into the bytes held back: `cache`
// and a run of 0xFF). LZMA's always-zero first byte is not written, and the final value is
// chosen with as many trailing zero bits as the interval allows; up to four trailing zero bytes
// are then dropped (the decoder reads zeros past the end, at most four).
// Private to the compact level coder (svec_compact.cpp).
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "io/svec_bytes_p.h"

namespace subvec::svec_detail {

inline constexpr int kProbBits = 12;
inline constexpr uint16_t kProbOne = 1u << kProbBits;  // 4096
inline constexpr uint16_t kProbInit = kProbOne / 2;
inline constexpr int kAdaptShift = 5;
inline constexpr uint32_t kTop = 1u << 24;
inline constexpr int kMaxOverread = 4;

// One adaptive binary context: p, the probability of a 0 in 1/4096, moves towards each coded
// bit by 1/2^shift of the distance, with shift = min(n + 2, 5) after n updates: fast while the
// context is new, steadier after (p stays in [31, 4065]).
struct BitModel {
  uint16_t p = kProbInit;
  uint8_t n = 0;
  void update(int b) {
    const int shift = std::min(n + 2, kAdaptShift);
    if (n < kAdaptShift - 2) ++n;
    if (b == 0) {
      p = static_cast<uint16_t>(p + ((kProbOne - p) >> shift));
    } else {
      p = static_cast<uint16_t>(p - (p >> shift));
    }
  }
};

class RangeEncoder {
 public:
  void bit(BitModel& m, int b) {
    const uint32_t bound = (range_ >> kProbBits) * m.p;
    if (b == 0) {
      range_ = bound;
    } else {
      low_ += bound;
      range_ -= bound;
    }
    m.update(b);
    normalize();
  }
  // `count` equiprobable bits of `value`, highest first (count <= 32).
  void direct(uint64_t value, int count) {
    for (int i = count - 1; i >= 0; --i) {
      range_ >>= 1;
      if ((value >> i) & 1) low_ += range_;
      normalize();
    }
  }
  // The coded bytes; the encoder is spent.
  std::vector<uint8_t> finish() {
    // The value with the most trailing zero bits in [low, low + range).
    for (int k = 32; k >= 0; --k) {
      const uint64_t mask = (uint64_t{1} << k) - 1;
      const uint64_t v = (low_ + mask) & ~mask;
      if (v < low_ + range_) {
        low_ = v;
        break;
      }
    }
    for (int i = 0; i < 5; ++i) shift_low();
    for (int i = 0; i < kMaxOverread && !out_.empty() && out_.back() == 0; ++i) out_.pop_back();
    return std::move(out_);
  }

 private:
  void normalize() {
    while (range_ < kTop) {
      range_ <<= 8;
      shift_low();
    }
  }
  void shift_low() {
    if (static_cast<uint32_t>(low_) < 0xFF000000u || (low_ >> 32) != 0) {
      const auto carry = static_cast<uint8_t>(low_ >> 32);
      uint8_t byte = cache_;
      do {
        put(static_cast<uint8_t>(byte + carry));
        byte = 0xFF;
      } while (--pending_ != 0);
      cache_ = static_cast<uint8_t>(low_ >> 24);
    }
    ++pending_;
    low_ = (low_ & 0x00FFFFFFu) << 8;
  }
  void put(uint8_t b) {
    if (first_) {  // LZMA's leading byte: always 0, not stored
      first_ = false;
      return;
    }
    out_.push_back(b);
  }

  uint64_t low_ = 0;
  uint32_t range_ = 0xFFFFFFFFu;
  uint8_t cache_ = 0;
  uint64_t pending_ = 1;
  bool first_ = true;
  std::vector<uint8_t> out_;
};

class RangeDecoder {
 public:
  // `what` names the stream in messages ("level 0 stream").
  RangeDecoder(std::span<const uint8_t> bytes, std::string what)
      : bytes_(bytes), what_(std::move(what)) {
    for (int i = 0; i < 4; ++i) code_ = (code_ << 8) | next();
    if (code_ >= range_) fail(what_ + ": corrupt coded data (bad first bytes)");
  }
  // What is being decoded now, for messages ("positions").
  void set_context(std::string what) { context_ = std::move(what); }

  int bit(BitModel& m) {
    const uint32_t bound = (range_ >> kProbBits) * m.p;
    int b;
    if (code_ < bound) {
      range_ = bound;
      b = 0;
    } else {
      code_ -= bound;
      range_ -= bound;
      b = 1;
    }
    m.update(b);
    normalize();
    return b;
  }
  uint64_t direct(int count) {
    uint64_t v = 0;
    for (int i = 0; i < count; ++i) {
      range_ >>= 1;
      int b = 0;
      if (code_ >= range_) {
        code_ -= range_;
        b = 1;
      }
      v = (v << 1) | uint64_t(b);
      normalize();
    }
    return v;
  }
  // After the last symbol: every byte was read (up to the zeros the encoder dropped), and the
  // code lies inside the final interval.
  void finish() const {
    if (pos_ < bytes_.size())
      fail(str(bytes_.size() - pos_) + " unexpected bytes at the end of " + what_);
    if (code_ >= range_) fail(what_ + ": corrupt coded data (the code leaves its interval)");
  }
  [[noreturn]] void corrupt(const std::string& message) const {
    fail(what_ + " " + context_ + ": " + message);
  }

 private:
  void normalize() {
    while (range_ < kTop) {
      range_ <<= 8;
      code_ = (code_ << 8) | next();
    }
  }
  uint32_t next() {
    if (pos_ < bytes_.size()) return bytes_[pos_++];
    if (++overread_ > kMaxOverread)
      fail(what_ + " " + context_ + ": the coded data ends early (" + str(bytes_.size()) +
           " bytes)");
    return 0;
  }

  std::span<const uint8_t> bytes_;
  std::string what_, context_ = "header";
  size_t pos_ = 0;
  int overread_ = 0;
  uint32_t range_ = 0xFFFFFFFFu, code_ = 0;
};

// Numbers over binary decisions (docs/format.md, "Numbers"). An unsigned n is coded as an
// Exp-Golomb code of n + 1 = 2^k + s (0 <= s < 2^k): k as a unary prefix (k ones, then a zero;
// prefix bit i in its own context), then the k bits of s, highest first, the top two in contexts
// of (k, position), the others equiprobable. A signed number is a zero flag, then a sign and
// |n| - 1 as above.
inline constexpr int kMaxPrefix = 56;
inline constexpr int kModeledSuffix = 2;

struct NumberModel {
  BitModel zero, sign;
  BitModel prefix[kMaxPrefix];
  BitModel suffix[kMaxPrefix][kModeledSuffix];
};

inline void put_unsigned(RangeEncoder& e, NumberModel& m, uint64_t n) {
  const uint64_t v = n + 1;  // n < 2^56 - 1 by the callers
  int k = 0;
  while ((v >> (k + 1)) != 0) ++k;
  for (int i = 0; i < k; ++i) e.bit(m.prefix[i], 1);
  e.bit(m.prefix[k], 0);
  for (int i = k - 1; i >= 0; --i) {
    const int b = int((v >> i) & 1);
    const int top = k - 1 - i;
    if (top < kModeledSuffix) {
      e.bit(m.suffix[k][top], b);
    } else {
      e.direct(uint64_t(b), 1);
    }
  }
}
inline void put_signed(RangeEncoder& e, NumberModel& m, int64_t n) {
  e.bit(m.zero, n != 0);
  if (n == 0) return;
  e.bit(m.sign, n < 0);
  put_unsigned(e, m, uint64_t(n < 0 ? -n : n) - 1);
}

inline uint64_t get_unsigned(RangeDecoder& d, NumberModel& m) {
  int k = 0;
  while (d.bit(m.prefix[k])) {
    if (++k == kMaxPrefix) d.corrupt("a number of more than " + str(kMaxPrefix) + " bits");
  }
  uint64_t v = 1;
  for (int i = k - 1; i >= 0; --i) {
    const int top = k - 1 - i;
    const int b = top < kModeledSuffix ? d.bit(m.suffix[k][top]) : int(d.direct(1));
    v = (v << 1) | uint64_t(b);
  }
  return v - 1;
}
inline int64_t get_signed(RangeDecoder& d, NumberModel& m) {
  if (!d.bit(m.zero)) return 0;
  const int negative = d.bit(m.sign);
  const auto magnitude = static_cast<int64_t>(get_unsigned(d, m)) + 1;
  return negative ? -magnitude : magnitude;
}

}  // namespace subvec::svec_detail
