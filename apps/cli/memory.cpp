#include "memory.h"

#include <cstdint>
#include <cstdlib>
#include <limits>
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

void tune_memory() {
#if SUBVEC_TUNE_MEMORY
  constexpr size_t kReserve = size_t(1) << 30;
  constexpr uintptr_t kHugePage = uintptr_t(2) << 20;
  mallopt(M_MMAP_THRESHOLD, 32 << 20);  // the largest glibc accepts
  mallopt(M_TRIM_THRESHOLD, std::numeric_limits<int>::max());  // above the reserve: it stays
  mallopt(M_TOP_PAD, 64 << 20);
  mallopt(M_ARENA_MAX, 1);
#if defined(MADV_HUGEPAGE)
  mallopt(M_MMAP_MAX, 0);  // the reserve must come from the heap, not from a mapping of its own
  void* block = std::malloc(kReserve);
  mallopt(M_MMAP_MAX, 65536);  // glibc's default
  if (block == nullptr) return;
  const uintptr_t begin = (reinterpret_cast<uintptr_t>(block) + kHugePage - 1) & ~(kHugePage - 1);
  const uintptr_t end = (reinterpret_cast<uintptr_t>(block) + kReserve) & ~(kHugePage - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
  std::free(block);  // to the heap's free top, which stays under the trim threshold
#endif
#endif
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
