// One line of progress on stderr for long runs (`subvec vectorize`, `subvec batch`): only when
// stderr is a terminal. A thread redraws it a few times a second and whenever it changes, and
// finish() (or the destructor) erases it, so the terminal keeps the summary alone and pipes and
// logs get nothing. Two modes:
// - stages: "subvec: LABEL: STAGE NN%, T s, ETA S s" (update() sets the stage), drawn only once the
//   run has taken a second (SUBVEC_PROGRESS_DELAY=SECONDS changes that); the time left is the
//   time to the stage's start over its fraction, less the time since (no ETA at 0 % and 100 %);
// - done/total: "subvec: LABEL [####....] D/TOTAL UNIT (N TALLY, ...), T s, ETA S s" (advance()
//   counts one item done), drawn from the start; the estimated time left is the mean time per
//   item done so far times the items left.
#pragma once

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace subvec_cli {

class ProgressLine {
 public:
  // Stages.
  explicit ProgressLine(std::string label);
  // Done/total; `tallies` name the counts shown in parentheses (advance's `tally` indexes them).
  ProgressLine(std::string label, int total, std::string unit, std::vector<std::string> tallies);
  ~ProgressLine() { finish(); }
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  // Stages: the stage now and its share of the whole run (0 to 1).
  void update(const std::string& stage, double fraction);
  // Done/total: one more item done, also counted in tallies[tally] unless `tally` is -1.
  void advance(int tally = -1);

  // Stops redrawing and erases the line.
  void finish();

 private:
  using Clock = std::chrono::steady_clock;
  void start();
  void run();
  std::string text(double elapsed) const;  // the line, under mutex_

  const std::string label_;
  const bool counting_;  // done/total mode
  const Clock::time_point start_;
  double delay_ = 0;  // seconds before the line appears
  std::chrono::milliseconds period_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::thread thread_;
  // Stages.
  std::string stage_ = "reading";
  double fraction_ = 0;
  double fraction_at_ = 0;  // seconds into the run when fraction_ was set
  // Done/total.
  int total_ = 0, done_ = 0;
  std::string unit_;
  std::vector<std::string> tally_names_;
  std::vector<int> tallies_;

  bool changed_ = false, stop_ = false;
  std::string last_;  // the line on the terminal
  int shown_ = 0;     // widest line drawn, in characters
};

}  // namespace subvec_cli
