// Private helpers for error messages, shared by the layers above core: one way to throw an
// invalid-argument error and one way to print a number in a message.
#pragma once

#include <cstdio>
#include <string>

#include "subvec/core/error.h"

namespace subvec::detail {

// Throws Error(kInvalidArgument, message).
[[noreturn]] inline void invalid(const std::string& message) {
  throw Error(ErrorCode::kInvalidArgument, message);
}

// v as printf's "%.<digits>g" writes it (6 significant digits unless told).
inline std::string num(double v, int digits = 6) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

}  // namespace subvec::detail
