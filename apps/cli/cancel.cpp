// Ctrl+C for long jobs (cancel.h).
#include "cancel.h"

#include "subvec/core/error.h"

namespace subvec_cli {
namespace {

std::atomic<bool> interrupted{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler stores to it");

extern "C" void on_interrupt(int) { interrupted.store(true); }

}  // namespace

CancelOnInterrupt::CancelOnInterrupt() {
  interrupted.store(false);
  struct sigaction action {};
  action.sa_handler = on_interrupt;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND;  // a second Ctrl+C ends the process
  sigaction(SIGINT, &action, &previous_);
}

CancelOnInterrupt::~CancelOnInterrupt() { sigaction(SIGINT, &previous_, nullptr); }

const std::atomic<bool>* CancelOnInterrupt::flag() const { return &interrupted; }

bool CancelOnInterrupt::cancelled() const { return interrupted.load(); }

void CancelOnInterrupt::check() const {
  if (cancelled()) throw subvec::Error(subvec::ErrorCode::kCancelled, "cancelled");
}

}  // namespace subvec_cli
