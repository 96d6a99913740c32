// The range coder of `.svec` version 3 (src/io/svec_range_p.h): bits, equiprobable bits and
// numbers come back as coded, in skewed and in even contexts; a fixed input gives fixed bytes
// (a broken or changed coder fails here before it fails on files); a cut or padded stream is an
// error, never a hang.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "io/svec_range_p.h"
#include "subvec/core/error.h"

namespace subvec::svec_detail {
namespace {

struct Symbol {
  int kind;  // 0 bit, 1 direct, 2 unsigned, 3 signed
  int context;
  int64_t value;
  int bits;
};

std::vector<Symbol> random_symbols(uint32_t seed, size_t n) {
  std::mt19937 rng(seed);
  std::vector<Symbol> out;
  for (size_t i = 0; i < n; ++i) {
    const int kind = int(rng() % 4), context = int(rng() % 4);
    Symbol s{kind, context, 0, 0};
    if (kind == 0) {
      s.value = (rng() % 100) < uint32_t(5 + 30 * context);  // skewed per context
    } else if (kind == 1) {
      s.bits = 1 + int(rng() % 32);
      s.value = int64_t(rng() & ((uint64_t{1} << s.bits) - 1));
    } else {
      const int magnitude_bits = int(rng() % (context == 3 ? 50 : 8));
      s.value = int64_t(uint64_t(rng()) << 32 | rng()) & ((int64_t{1} << magnitude_bits) - 1);
      if (kind == 3 && rng() % 2) s.value = -s.value;
    }
    out.push_back(s);
  }
  return out;
}

struct Contexts {
  BitModel bits[4];
  NumberModel numbers[4];
};

std::vector<uint8_t> encode(const std::vector<Symbol>& symbols) {
  Contexts c;
  RangeEncoder e;
  for (const Symbol& s : symbols) {
    if (s.kind == 0) e.bit(c.bits[s.context], int(s.value));
    if (s.kind == 1) e.direct(uint64_t(s.value), s.bits);
    if (s.kind == 2) put_unsigned(e, c.numbers[s.context], uint64_t(s.value < 0 ? -s.value : s.value));
    if (s.kind == 3) put_signed(e, c.numbers[s.context], s.value);
  }
  return e.finish();
}

// Decodes symbols of the kinds and contexts of `symbols`; throws Error where the decoder does.
std::vector<int64_t> decode(const std::vector<uint8_t>& bytes, const std::vector<Symbol>& symbols) {
  Contexts c;
  RangeDecoder d(bytes, "test stream");
  std::vector<int64_t> out;
  for (const Symbol& s : symbols) {
    if (s.kind == 0) out.push_back(d.bit(c.bits[s.context]));
    if (s.kind == 1) out.push_back(int64_t(d.direct(s.bits)));
    if (s.kind == 2) out.push_back(int64_t(get_unsigned(d, c.numbers[s.context])));
    if (s.kind == 3) out.push_back(get_signed(d, c.numbers[s.context]));
  }
  d.finish();
  return out;
}

void expect_decodes(const std::vector<uint8_t>& bytes, const std::vector<Symbol>& symbols) {
  const std::vector<int64_t> values = decode(bytes, symbols);
  for (size_t i = 0; i < symbols.size(); ++i) {
    const Symbol& s = symbols[i];
    const int64_t expected = s.kind == 2 && s.value < 0 ? -s.value : s.value;
    ASSERT_EQ(values[i], expected) << "symbol " << i;
  }
}

TEST(SvecRange, RoundTrips) {
  for (uint32_t seed = 1; seed <= 40; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const std::vector<Symbol> symbols = random_symbols(seed, seed * 97);
    expect_decodes(encode(symbols), symbols);
  }
}

TEST(SvecRange, LongRunsOfOneBitCompressAndCarriesPropagate) {
  // 20000 zeros in one context: the probability saturates, so each costs about 0.011 bits.
  std::vector<Symbol> zeros(20000, Symbol{0, 0, 0, 0});
  const std::vector<uint8_t> bytes = encode(zeros);
  EXPECT_LT(bytes.size(), 40u);
  expect_decodes(bytes, zeros);
  // Ones push `low` up and make 0xFF runs and carries.
  std::vector<Symbol> ones(20000, Symbol{0, 1, 1, 0});
  for (size_t i = 0; i < ones.size(); i += 7) ones[i].value = 0;
  expect_decodes(encode(ones), ones);
  EXPECT_TRUE(encode({}).empty());  // nothing coded: no bytes
}

// Known answers: the documented arithmetic (docs/format.md, "The range coder") gives exactly
// these bytes. An accidental change of the coder or of its adaptation breaks every file.
TEST(SvecRange, KnownBytes) {
  std::vector<Symbol> symbols;
  for (int i = 0; i < 24; ++i) symbols.push_back({0, 0, i % 3 == 0, 0});
  symbols.push_back({1, 0, 0x2A, 7});
  symbols.push_back({3, 1, -5, 0});
  symbols.push_back({2, 2, 300, 0});
  const std::vector<uint8_t> bytes = encode(symbols);
  EXPECT_EQ(bytes, (std::vector<uint8_t>{0x8c, 0x15, 0x77, 0x2a, 0xf8, 0x11, 0x5e}));
  expect_decodes(bytes, symbols);
}

TEST(SvecRange, CutOrPaddedStreamsAreErrors) {
  const std::vector<Symbol> symbols = random_symbols(7, 2000);
  const std::vector<uint8_t> bytes = encode(symbols);
  ASSERT_GT(bytes.size(), 100u);
  // Cut: decoding the same symbols runs past the end (at most 4 zero bytes are implied).
  for (const size_t keep : {size_t{0}, size_t{3}, bytes.size() / 2, bytes.size() - 6}) {
    SCOPED_TRACE("first " + std::to_string(keep) + " bytes");
    const std::vector<uint8_t> cut(bytes.begin(), bytes.begin() + long(keep));
    EXPECT_THROW((void)decode(cut, symbols), Error);
  }
  // Padded by five bytes: the decoder reads at most four past the coded ones, so bytes are left
  // over. (Fewer may take the place of the zeros the encoder dropped: a valid stream.)
  std::vector<uint8_t> padded = bytes;
  padded.insert(padded.end(), 5, 0x55);
  EXPECT_THROW((void)decode(padded, symbols), Error);
  // Garbage decodes to something or fails, but each decision reads input: a loop over many
  // symbols ends with an error once the bytes (and the 4 implied zeros) are spent.
  std::vector<uint8_t> garbage(64, 0xFF);
  garbage[0] = 0x12;
  RangeDecoder d(garbage, "garbage");
  BitModel m;
  EXPECT_THROW(
      {
        for (int i = 0; i < 10'000'000; ++i) (void)d.bit(m);
      },
      Error);
  // A number whose prefix never ends is refused, not looped on.
  std::vector<uint8_t> ones(400, 0xFF);
  ones[3] = 0xFE;  // C = R - 1: every decision is a 1
  RangeDecoder d2(ones, "ones");
  NumberModel n;
  EXPECT_THROW((void)get_unsigned(d2, n), Error);
}

}  // namespace
}  // namespace subvec::svec_detail
