// libFuzzer target: the binary `.svec` reader. Any input either parses into a valid image, which
// must then survive a write/read round trip unchanged (or be refused by the compact writer), or
// is rejected with subvec::Error. Anything else (a crash, a sanitizer report, another exception
// type, a hang) is a bug.
#include <cstdint>
#include <cstdlib>
#include <span>

#include "subvec/core/error.h"
#include "subvec/io/svec.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  subvec::VectorImage image;
  try {
    image = subvec::parse_svec_binary(std::span<const uint8_t>(data, size));
  } catch (const subvec::Error&) {
    return 0;
  }
  // The compact writer refuses (with subvec::Error) colors too large for its grid, which the
  // lossless form reads.
  // Both compact versions (3, the default, range-coded; 2, varints) must round-trip.
  for (const int version : {3, 2}) {
    const subvec::SvecWriteOptions options{.compact_version = version};
    std::vector<uint8_t> bytes;
    try {
      bytes = subvec::to_svec_binary(image, options);
    } catch (const subvec::Error&) {
      return 0;
    }
    if (subvec::to_svec_binary(subvec::parse_svec_binary(bytes), options) != bytes) std::abort();
  }
  return 0;
}
