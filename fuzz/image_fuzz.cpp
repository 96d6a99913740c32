// libFuzzer target: image decoding as `subvec vectorize` does it (read_image: PNG, JPEG, WebP,
// TIFF, BMP through OpenCV, then our conversion to 8-bit RGB). The bytes go through a file because
// that is the entry point users reach. Rejection must be a subvec::Error.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "subvec/core/error.h"
#include "subvec/io/image_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("subvec-image-fuzz-" + std::to_string(getpid()));
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  try {
    // A small pixel limit keeps decompression bombs from eating the fuzzer's memory budget; the
    // limit check itself is part of what is tested.
    const subvec::Image8 image = subvec::read_image(path, int64_t{1} << 22);
    if (image.width <= 0 || image.height <= 0 || image.pixels.size() != size_t(image.width) * image.height * image.channels) {
      std::abort();
    }
  } catch (const subvec::Error&) {
  }
  return 0;
}
