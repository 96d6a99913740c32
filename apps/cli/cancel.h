// Ctrl+C for long jobs (`subvec vectorize`, `subvec batch`): while a CancelOnInterrupt lives,
// SIGINT sets a flag that the library's job checks (VectorizeOptions::cancel) and that throws
// subvec::Error(kCancelled) there; main() prints one line and exits with status 130. The handler
// does nothing else (an atomic store) and is installed for one signal only: a second Ctrl+C
// ends the process the default way.
#pragma once

#include <atomic>
#include <csignal>

namespace subvec_cli {

class CancelOnInterrupt {
 public:
  CancelOnInterrupt();
  ~CancelOnInterrupt();
  CancelOnInterrupt(const CancelOnInterrupt&) = delete;
  CancelOnInterrupt& operator=(const CancelOnInterrupt&) = delete;

  const std::atomic<bool>* flag() const;
  bool cancelled() const;
  // Throws subvec::Error(kCancelled) once Ctrl+C was pressed (before writing an output).
  void check() const;

 private:
  struct sigaction previous_ {};
};

}  // namespace subvec_cli
