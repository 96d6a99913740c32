#include "subvec/core/memory.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string>
#if defined(__unix__) || defined(__APPLE__)
#include <unistd.h>
#endif

namespace subvec {
namespace {

constexpr int64_t kUnknown = std::numeric_limits<int64_t>::max();

// The "MemAvailable:" line of /proc/meminfo, in bytes; kUnknown without one.
int64_t meminfo_available() {
  std::ifstream in("/proc/meminfo");
  std::string key;
  int64_t kb = 0;
  std::string unit;
  while (in >> key >> kb) {
    std::getline(in, unit);
    if (key == "MemAvailable:") return kb * 1024;
  }
  return kUnknown;
}

// One number from a cgroup file ("max" or nothing readable: kUnknown).
int64_t cgroup_value(const std::string& path) {
  std::ifstream in(path);
  std::string text;
  if (!(in >> text) || text == "max") return kUnknown;
  try {
    return std::stoll(text);
  } catch (...) {
    return kUnknown;
  }
}

// Room left under this process's cgroup v2 memory limit; kUnknown without a limit.
int64_t cgroup_room() {
  std::ifstream in("/proc/self/cgroup");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("0::", 0) != 0) continue;  // the v2 line: "0::/path"
    const std::string dir = "/sys/fs/cgroup" + line.substr(3);
    const int64_t max = cgroup_value(dir + "/memory.max");
    if (max == kUnknown) return kUnknown;
    const int64_t current = cgroup_value(dir + "/memory.current");
    return current == kUnknown ? max : std::max<int64_t>(0, max - current);
  }
  return kUnknown;
}

}  // namespace

int64_t available_memory_bytes() {
  int64_t bytes = std::min(meminfo_available(), cgroup_room());
#if defined(_SC_AVPHYS_PAGES) && defined(_SC_PAGESIZE)
  if (bytes == kUnknown) {
    const long pages = sysconf(_SC_AVPHYS_PAGES), size = sysconf(_SC_PAGESIZE);
    if (pages > 0 && size > 0) bytes = int64_t(pages) * size;
  }
#endif
  return bytes;
}

std::string format_bytes(int64_t bytes) {
  static const char* const kUnits[] = {"KB", "MB", "GB", "TB"};
  if (bytes < 1000) return std::to_string(bytes) + " bytes";
  double value = double(bytes);
  int unit = -1;
  while (value >= 1000 && unit < 3) value /= 1000, ++unit;
  char text[32];
  std::snprintf(text, sizeof text, value < 10 ? "%.1f %s" : "%.0f %s", value, kUnits[unit]);
  return text;
}

}  // namespace subvec
