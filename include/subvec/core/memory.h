// The memory a job may count on (vectorize() checks its estimate against it, vectorize.h).
#pragma once

#include <cstdint>
#include <string>

namespace subvec {

// Bytes this process could allocate now without the system swapping or killing it: Linux's
// MemAvailable (/proc/meminfo), lowered to what is left under the process's cgroup limit
// (memory.max less memory.current, cgroup v2) when there is one; elsewhere, the free physical
// pages. INT64_MAX when nothing says.
int64_t available_memory_bytes();

// "1.3 GB", "640 MB", "12 KB", "900 bytes" (powers of 1000, one decimal under 10): for messages.
std::string format_bytes(int64_t bytes);

}  // namespace subvec
