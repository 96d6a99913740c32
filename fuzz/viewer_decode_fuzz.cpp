// libFuzzer target: the browser viewer's decoder of compact levels and its level checks
// (web/viewer/wasm/decode.c), built natively under ASan + UBSan. In the browser that code runs in
// WebAssembly, where a read out of bounds of its arena reads the arena instead of crashing: here
// every allocation is its own block, so the sanitizers see what the sandbox would hide.
// Input: a version byte (2 or 3), then a .svec payload as src/decode.ts reads it (width, height,
// the level count, each compact level's counts, precision and stream or six sections).
#include <csetjmp>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

namespace {
std::jmp_buf failed;
std::vector<void *> blocks;
}  // namespace

extern "C" {
void *alloc(size_t n) {
  void *p = std::calloc(1, n ? n : 1);
  if (p) blocks.push_back(p);
  return p;
}
void *alloc_array(size_t size, double count) {
  if (!(count >= 0) || count * static_cast<double>(size) > 4294967295.0) return nullptr;
  return alloc(size * static_cast<size_t>(count));
}
[[noreturn]] void js_fail(const uint8_t *, int32_t) { std::longjmp(failed, 1); }
double js_mean(const double *terms, int32_t n) {
  long double s = 0;
  for (int32_t i = 0; i < n; ++i) s += terms[i];
  return static_cast<double>(std::floor((2 * s + n) / (2.0L * n)));
}
double js_exact(double a, double b, double c, double d) {
  return static_cast<double>(static_cast<long double>(a) * b + static_cast<long double>(c) * d);
}
double js_atan2(double y, double x) { return std::atan2(y, x); }
#include "../web/viewer/wasm/message.c"
#include "../web/viewer/wasm/decode.c"
}

namespace {
// The bytes, read as src/decode.ts's Cursor reads them; false when they run out.
struct Reader {
  const uint8_t *b;
  size_t n, pos = 0;
  bool take(size_t k, const uint8_t **at) {
    if (k > n - pos) return false;
    *at = b + pos, pos += k;
    return true;
  }
  bool u32(uint32_t *v) {
    const uint8_t *p;
    if (!take(4, &p)) return false;
    *v = static_cast<uint32_t>(p[0] | p[1] << 8 | p[2] << 16) | static_cast<uint32_t>(p[3]) << 24;
    return true;
  }
};

void release() {
  for (void *p : blocks) std::free(p);
  blocks.clear();
}

// One level: decoded, then checked as a decoded level and as a JSON level would be.
void level(int version, Reader &r, int32_t width, int32_t height) {
  uint32_t count[5];
  for (uint32_t &c : count)
    if (!r.u32(&c) || c > (1u << 16)) return;  // small levels: the fuzzer explores more of them
  const uint8_t *precision;
  if (!r.take(2, &precision)) return;
  int32_t pb = precision[0], cb = static_cast<int8_t>(precision[1]);
  if (pb > 12 || cb < -4 || cb > 12 || count[0] < 3) return;
  double ops = 3.0 * static_cast<double>(r.n - r.pos);
  Section sections[6] = {};
  for (int k = 0; k < (version == 2 ? 6 : 1); ++k) {
    uint32_t n;
    const uint8_t *bytes;
    if (!r.u32(&n) || n < 1 || !r.take(n, &bytes)) return;
    sections[k] = {bytes, static_cast<int32_t>(n)};
  }
  volatile Level *decoded = nullptr;
  if (!setjmp(failed))
    decoded = compact(version, sections, ops, static_cast<int32_t>(count[0]), static_cast<int32_t>(count[1]),
                      static_cast<int32_t>(count[2]), static_cast<int32_t>(count[3]), static_cast<int32_t>(count[4]), pb, cb,
                      width, height, 0);
  Level *L = const_cast<Level *>(decoded);
  if (!L) return release();
  int32_t nv = static_cast<int32_t>(count[0]), nt = static_cast<int32_t>(count[2]);
  for (const Edges *built : {static_cast<const Edges *>(&L->edges), static_cast<const Edges *>(nullptr)})
    if (!setjmp(failed))
      check_level(nv, L->positions, static_cast<int32_t>(count[1]), L->colors, nt, L->triangles, L->triangleColors,
                  static_cast<int32_t>(count[3]), L->creases, L->numFeatures, L->featureIds, L->featureSaliency, L->featureOffsets,
                  L->featureVertices, width, height, built, 0);
  release();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  if (size < 1 || (data[0] != 2 && data[0] != 3)) return 0;
  Reader r{data + 1, size - 1};
  uint32_t width, height, levels;
  if (!r.u32(&width) || !r.u32(&height) || !r.u32(&levels)) return 0;
  if (width < 1 || height < 1 || width > 65536 || height > 65536) return 0;
  for (uint32_t l = 0; l < levels && l < 4; ++l) level(data[0], r, static_cast<int32_t>(width), static_cast<int32_t>(height));
  return 0;
}
