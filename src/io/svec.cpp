// Reading and writing native files by path (io/svec.h): the form is chosen by content when
// reading and by extension when writing. Messages are prefixed with the path.
#include "subvec/io/svec.h"

#include <algorithm>
#include <cctype>
#include <string>

#include "io/svec_p.h"
#include "subvec/core/error.h"
#include "subvec/io/file.h"
#include "subvec/io/image_io.h"
#include "subvec/mesh/validate.h"

namespace subvec {
namespace {

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// First byte that is not JSON whitespace (after an optional UTF-8 byte order mark), or -1.
int first_significant_byte(std::span<const uint8_t> bytes) {
  size_t i = 0;
  if (bytes.size() >= 3 && bytes[0] == 0xEF && bytes[1] == 0xBB && bytes[2] == 0xBF) i = 3;
  while (i < bytes.size() &&
         (bytes[i] == ' ' || bytes[i] == '\t' || bytes[i] == '\n' || bytes[i] == '\r'))
    ++i;
  return i < bytes.size() ? bytes[i] : -1;
}

// "a PNG image, not a .svec or .svec.json file; vectorize it first: subvec vectorize photo.png
// -o photo.svec" (read_svec puts the path in front). PDF, SVG and GIF are not vectorize's inputs.
std::string not_a_vector_image(const std::filesystem::path& path, const std::string& format) {
  const bool vector = format == "PDF" || format == "SVG";
  std::string message = std::string(format == "SVG" ? "an " : "a ") + format +
                        (vector ? " file" : " image") + ", not a .svec or .svec.json file";
  if (is_raster_input(format)) {
    std::filesystem::path out = path.filename();
    out.replace_extension(".svec");
    message += "; vectorize it first: subvec vectorize " + path.string() + " -o " + out.string();
  } else if (vector) {
    message += "; subvec writes " + format + " (render -o out." + lower(format) +
               ") but cannot read it";
  }
  return message;
}

}  // namespace

SvecFormat svec_format_for(const std::filesystem::path& path) {
  const std::string name = lower(path.filename().string());
  if (ends_with(name, ".svec.json") || ends_with(name, ".json")) return SvecFormat::kJson;
  if (ends_with(name, ".svec")) return SvecFormat::kBinary;
  const std::string ext = path.extension().string();
  throw Error(ErrorCode::kInvalidArgument, path.string() + ": unknown extension " +
                                               (ext.empty() ? "(none)" : "\"" + ext + "\"") +
                                               " (expected .svec or .svec.json)");
}

VectorImage read_svec(const std::filesystem::path& path) {
  try {
    std::vector<uint8_t> bytes = read_file(path, svec_detail::kMaxFileBytes);
    if (svec_detail::has_magic(bytes)) return parse_svec_binary(bytes);
    const int first = first_significant_byte(bytes);
    if (first == '{' || first == '[') {
      size_t skip =
          bytes.size() >= 3 && bytes[0] == 0xEF && bytes[1] == 0xBB && bytes[2] == 0xBF ? 3 : 0;
      return parse_svec_json(std::string_view(reinterpret_cast<const char*>(bytes.data()) + skip,
                                              bytes.size() - skip));
    }
    if (bytes.empty()) throw Error(ErrorCode::kBadFile, "file is empty");
    // Neither form. An image in another format is named, with what to do instead; anything
    // else goes to the binary reader, which names the wrong magic bytes.
    if (const std::string format = image_format_name(bytes); !format.empty())
      throw Error(ErrorCode::kBadFile, not_a_vector_image(path, format));
    return parse_svec_binary(bytes);
  } catch (const Error& e) {
    const std::string prefix = path.string() + ": ";
    const std::string message = e.what();
    if (message.compare(0, prefix.size(), prefix) == 0) throw;  // read_file already named it
    throw Error(e.code(), prefix + message);
  }
}

void write_svec(const std::filesystem::path& path, const VectorImage& image,
                const SvecWriteOptions& options) {
  const SvecFormat format = svec_format_for(path);
  try {
    validate(image);
  } catch (const Error& e) {
    throw Error(e.code(), path.string() + ": refusing to write an invalid image: " + e.what());
  }
  if (format == SvecFormat::kJson) {
    const std::string text = to_svec_json(image);
    write_file_atomic(path, std::span(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
  } else {
    write_file_atomic(path, to_svec_binary(image, options));
  }
}

}  // namespace subvec
