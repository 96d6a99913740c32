// Private helpers for error messages, shared by the layers above core: one way to throw an
// invalid-argument error and one way to print a number in a message.
#pragma once

#include <cmath>
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

// Throws "FIELD must be RULE, got VALUE" (kInvalidArgument): the one form of an option's range
// message, for the validate() of every parameter struct.
[[noreturn]] inline void out_of_range(const std::string& field, const std::string& rule, double value) {
  invalid(field + " must be " + rule + ", got " + num(value));
}

// `value` in [lo, hi] (so finite); the message names `field`.
inline void check_in(const std::string& field, double value, double lo, double hi) {
  if (!(value >= lo && value <= hi)) out_of_range(field, "in [" + num(lo) + ", " + num(hi) + "]", value);
}

// `value` finite and > 0.
inline void check_positive(const std::string& field, double value) {
  if (!(std::isfinite(value) && value > 0)) out_of_range(field, "a positive number", value);
}

}  // namespace subvec::detail
