#include "memory.h"

#include <cstdint>
#include <cstdlib>
#if defined(__unix__) || defined(__APPLE__)
#include <sys/resource.h>
#endif
#if defined(__GLIBC__)
#include <malloc.h>
#include <sys/mman.h>
#endif

namespace subvec_cli {

// Under AddressSanitizer malloc is its own, and a 1 GB block would cost every run its shadow.
#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)
#define SUBVEC_TUNE_MEMORY 1
#else
#define SUBVEC_TUNE_MEMORY 0
#endif
#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#undef SUBVEC_TUNE_MEMORY
#define SUBVEC_TUNE_MEMORY 0
#endif
#endif

namespace {

size_t reserved = 0;  // bytes of heap advised for huge pages so far

// Grows the heap to hold a free block of `bytes` and advises it for huge pages.
void grow_reserve(size_t bytes) {
#if SUBVEC_TUNE_MEMORY && defined(MADV_HUGEPAGE)
  constexpr uintptr_t kHugePage = uintptr_t(2) << 20;
  mallopt(M_MMAP_MAX, 0);  // the reserve must come from the heap, not from a mapping of its own
  void* block = std::malloc(bytes);
  mallopt(M_MMAP_MAX, 65536);  // glibc's default
  if (block == nullptr) return;
  const uintptr_t begin = (reinterpret_cast<uintptr_t>(block) + kHugePage - 1) & ~(kHugePage - 1);
  const uintptr_t end = (reinterpret_cast<uintptr_t>(block) + bytes) & ~(kHugePage - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
  std::free(block);  // to the heap's free top, which stays under the trim threshold
  reserved = bytes;
#else
  (void)bytes;
#endif
}

}  // namespace

void tune_memory() {
#if SUBVEC_TUNE_MEMORY
  mallopt(M_MMAP_THRESHOLD, 32 << 20);  // the largest glibc accepts
  mallopt(M_TRIM_THRESHOLD, -1);  // never: the reserve stays, however large (mallopt(3))
  mallopt(M_TOP_PAD, 64 << 20);
  mallopt(M_ARENA_MAX, 1);
  grow_reserve(size_t(1) << 30);
#endif
}

void reserve_memory(int64_t bytes) {
  if (bytes > 0 && size_t(bytes) > reserved) grow_reserve(size_t(bytes));  // a no-op without glibc
}

int64_t peak_resident_bytes() {
#if defined(__unix__) || defined(__APPLE__)
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0;
#if defined(__APPLE__)
  return int64_t(usage.ru_maxrss);  // bytes there
#else
  return int64_t(usage.ru_maxrss) * 1024;  // KB on Linux
#endif
#else
  return 0;
#endif
}

}  // namespace subvec_cli
