// zstd's content checksum: the low 32 bits of XXH64 with seed 0 (the xxHash specification,
// https://github.com/Cyan4973/xxHash/blob/dev/doc/xxhash_spec.md). Checked against the zstd
// command's checksums by web/tests/viewer-decode.mjs.
#include "memory.h"

static const uint64_t P1 = 0x9E3779B185EBCA87ull, P2 = 0xC2B2AE3D27D4EB4Full, P3 = 0x165667B19E3779F9ull,
                      P4 = 0x85EBCA77C2B2AE63ull, P5 = 0x27D4EB2F165667C5ull;

static uint64_t rotl(uint64_t x, int r) { return x << r | x >> (64 - r); }
static uint64_t le64(const uint8_t *p) {
  uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = v << 8 | p[i];
  return v;
}
static uint32_t le32(const uint8_t *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }
static uint64_t round64(uint64_t acc, uint64_t lane) { return rotl(acc + lane * P2, 31) * P1; }
static uint64_t merge(uint64_t h, uint64_t v) { return (h ^ round64(0, v)) * P1 + P4; }

EXPORT(xxh64) uint32_t xxh64(const uint8_t *b, uint32_t n) {
  const uint8_t *end = b + n;
  uint64_t h;
  if (n >= 32) {
    uint64_t v[4] = {P1 + P2, P2, 0, -P1};
    for (; end - b >= 32; b += 32)
      for (int k = 0; k < 4; ++k) v[k] = round64(v[k], le64(b + 8 * k));
    h = rotl(v[0], 1) + rotl(v[1], 7) + rotl(v[2], 12) + rotl(v[3], 18);
    for (int k = 0; k < 4; ++k) h = merge(h, v[k]);
  } else {
    h = P5;
  }
  h += n;
  for (; end - b >= 8; b += 8) h = rotl(h ^ round64(0, le64(b)), 27) * P1 + P4;
  if (end - b >= 4) h = rotl(h ^ (uint64_t)le32(b) * P1, 23) * P2 + P3, b += 4;
  for (; b < end; ++b) h = rotl(h ^ *b * P5, 11) * P1;
  h ^= h >> 33, h *= P2, h ^= h >> 29, h *= P3, h ^= h >> 32;
  return (uint32_t)h;
}
