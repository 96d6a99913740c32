// Private: the one check of a long job's cancel flag (VectorizeOptions::cancel and the stage
// structs' `cancel`). Stages call it on the calling thread, between parallel phases and every so
// many steps of their loops; a flag may be set from another thread or a signal handler.
#pragma once

#include <atomic>

#include "subvec/core/error.h"

namespace subvec::detail {

// Whether `flag` is set (a null flag never is).
inline bool cancelled(const std::atomic<bool>* flag) { return flag && flag->load(std::memory_order_relaxed); }

// Throws Error(kCancelled, "cancelled") when `flag` is set.
inline void check_cancel(const std::atomic<bool>* flag) {
  if (cancelled(flag)) throw Error(ErrorCode::kCancelled, "cancelled");
}

}  // namespace subvec::detail
