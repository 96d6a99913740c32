// libFuzzer target: the `.svec.json` reader. Any input either parses into a valid image, which must
// then survive a write/read round trip unchanged, or is rejected with subvec::Error.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "subvec/core/error.h"
#include "subvec/io/svec.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  subvec::VectorImage image;
  try {
    image = subvec::parse_svec_json(std::string_view(reinterpret_cast<const char*>(data), size));
  } catch (const subvec::Error&) {
    return 0;
  }
  const std::string text = subvec::to_svec_json(image);
  if (subvec::to_svec_json(subvec::parse_svec_json(text)) != text) std::abort();
  return 0;
}
