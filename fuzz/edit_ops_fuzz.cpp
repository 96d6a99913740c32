// libFuzzer target: the edit-ops reader and its application. Any input either parses and applies
// to a small example image (which must still validate afterwards), or is rejected with
// subvec::Error at either step.
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "subvec/core/error.h"
#include "subvec/edit/ops.h"
#include "subvec/io/svec.h"
#include "subvec/mesh/validate.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const subvec::VectorImage example = subvec::read_svec(SUBVEC_SOURCE_DIR "/examples/03-junction.svec.json");
  std::vector<subvec::EditOp> ops;
  try {
    ops = subvec::parse_edit_ops(std::string_view(reinterpret_cast<const char*>(data), size));
  } catch (const subvec::Error&) {
    return 0;
  }
  subvec::VectorImage image = example;
  try {
    subvec::apply_edit_ops(image, ops);
  } catch (const subvec::Error&) {
  }
  subvec::validate(image);  // throws (and so aborts the fuzzer) if an edit broke the image
  return 0;
}
