// libFuzzer target: the binary `.svec` reader. Any input either parses into a valid image, which
// must then survive a write/read round trip unchanged, or is rejected with subvec::Error. Anything
// else (a crash, a sanitizer report, another exception type, a hang) is a bug.
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
  const std::vector<uint8_t> bytes = subvec::to_svec_binary(image);
  if (subvec::to_svec_binary(subvec::parse_svec_binary(bytes)) != bytes) std::abort();
  return 0;
}
