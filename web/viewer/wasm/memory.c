#include "memory.h"

extern unsigned char __heap_base;
static size_t top = 0;

EXPORT(reset) void reset(void) { top = (size_t)&__heap_base; }

void *alloc(size_t n) {
  if (!top) reset();
  size_t start = (top + 7) & ~(size_t)7;
  if (n > SIZE_MAX - start - 65536) return 0;
  size_t end = start + n, have = __builtin_wasm_memory_size(0) * 65536;
  if (end > have && __builtin_wasm_memory_grow(0, (end - have + 65535) / 65536) == (size_t)-1) return 0;
  top = end;
  return __builtin_memset((void *)start, 0, n);
}

void *alloc(size_t n);

void *alloc_array(size_t size, double count) {
  // Counts are integers below 2^53, exact in a double; a negative one is a caller's bug: refuse.
  if (!(count >= 0) || count * (double)size > 4294967295.0) return 0;
  return alloc(size * (size_t)count);
}

EXPORT(alloc) void *alloc_export(size_t n) { return alloc(n); }
