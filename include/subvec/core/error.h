// Error policy (docs/design.md): the library reports failures by throwing subvec::Error, whose
// code says which kind of failure it is and whose message is one line naming the problem (which
// field, which index). Boundaries translate: the CLI prints "subvec: <message>" and exits with a
// non-zero status; later front ends map codes to HTTP statuses and exception classes.
#pragma once

#include <stdexcept>
#include <string>

namespace subvec {

enum class ErrorCode {
  kInvalidArgument,  // an option or parameter out of its range
  kInvalidMesh,      // a vector image that breaks an invariant (see mesh/validate.h)
  kBadFile,          // a file that cannot be parsed: truncated, wrong magic, bad field
  kIo,               // the operating system refused a read or a write
  kLimit,            // input over a size limit (pixels, vertices, bytes)
  kCancelled,        // a long job stopped because its cancel flag was set (e.g. Ctrl+C)
};

class Error : public std::runtime_error {
 public:
  Error(ErrorCode code, const std::string& message) : std::runtime_error(message), code_(code) {}
  ErrorCode code() const noexcept { return code_; }

 private:
  ErrorCode code_;
};

}  // namespace subvec
