// The progress line on stderr (progress.h).
#include "progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace subvec_cli {
namespace {

constexpr size_t kMaxLine = 511;  // characters; a longer line (a long file name) is cut

}  // namespace

ProgressLine::ProgressLine(std::string label)
    : label_(std::move(label)), counting_(false), start_(Clock::now()), delay_(1.0),
      period_(200) {
  if (const char* env = std::getenv("SUBVEC_PROGRESS_DELAY")) {
    char* end = nullptr;
    const double v = std::strtod(env, &end);
    if (end != env && *end == '\0' && v >= 0 && std::isfinite(v)) delay_ = v;
  }
  start();
}

ProgressLine::ProgressLine(std::string label, int total, std::string unit,
                           std::vector<std::string> tallies)
    : label_(std::move(label)), counting_(true), start_(Clock::now()), period_(250),
      total_(total), unit_(std::move(unit)), tally_names_(std::move(tallies)),
      tallies_(tally_names_.size(), 0) {
  start();
}

void ProgressLine::start() {
  if (isatty(STDERR_FILENO)) thread_ = std::thread([this] { run(); });
}

void ProgressLine::update(const std::string& stage, double fraction) {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stage_ = stage;
    fraction_ = fraction;
    fraction_at_ = std::chrono::duration<double>(Clock::now() - start_).count();
    changed_ = true;
  }
  wake_.notify_all();
}

void ProgressLine::advance(int tally) {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    ++done_;
    if (tally >= 0) ++tallies_[size_t(tally)];
    changed_ = true;
  }
  wake_.notify_all();
}

void ProgressLine::finish() {
  if (!thread_.joinable()) return;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
  if (shown_ > 0) std::fprintf(stderr, "\r%*s\r", shown_, "");
  std::fflush(stderr);
}

std::string ProgressLine::text(double elapsed) const {
  std::string out = "subvec: " + label_;
  char buf[128];
  if (!counting_) {
    std::snprintf(buf, sizeof buf, " %3d%%, %.0f s", static_cast<int>(std::lround(100 * fraction_)),
                  std::floor(elapsed));
    out += ": " + stage_ + buf;
    if (fraction_ > 0 && fraction_ < 1) {
      const double left = fraction_at_ / fraction_ - elapsed;
      std::snprintf(buf, sizeof buf, ", ETA %.0f s", std::max(1.0, std::ceil(left)));
      out += buf;
    }
    return out;
  }
  constexpr int kBar = 24;
  const int filled = total_ ? kBar * done_ / total_ : kBar;
  out += " [" + std::string(size_t(filled), '#') + std::string(size_t(kBar - filled), '.') + "] " +
         std::to_string(done_) + "/" + std::to_string(total_) + " " + unit_;
  for (size_t k = 0; k < tallies_.size(); ++k) {
    out += (k == 0 ? " (" : ", ") + std::to_string(tallies_[k]) + " " + tally_names_[k];
  }
  if (!tallies_.empty()) out += ")";
  std::string eta = "ETA --";
  if (done_ > 0 && done_ < total_) {
    eta = "ETA " + std::to_string(std::lround(elapsed / done_ * (total_ - done_))) + " s";
  }
  std::snprintf(buf, sizeof buf, ", %.0f s, ", std::floor(elapsed));
  return out + buf + eta;
}

void ProgressLine::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    wake_.wait_for(lock, period_, [this] { return stop_ || changed_; });
    if (stop_) return;
    changed_ = false;
    const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
    if (elapsed < delay_) continue;
    const std::string line = text(elapsed).substr(0, kMaxLine);
    if (line == last_) continue;
    last_ = line;
    const int len = static_cast<int>(line.size());
    std::fprintf(stderr, "\r%s%*s", line.c_str(), std::max(0, shown_ - len), "");
    std::fflush(stderr);
    shown_ = std::max(shown_, len);
  }
}

}  // namespace subvec_cli
