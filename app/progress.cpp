#include "progress.hpp"

#include <sys/ioctl.h>
#include <unistd.h>

#include <cstdio>
#include <iostream>

#include "core/number_text.hpp"

namespace deformlab::app {

namespace {

constexpr auto kInterval = std::chrono::milliseconds(500);
constexpr const char* kClearLine = "\r\x1b[K";

}  // namespace

ProgressLine::ProgressLine(int max_steps, double dt, double threshold)
    : max_steps_(max_steps), dt_(dt), threshold_(threshold), shown_(::isatty(STDERR_FILENO) == 1),
      start_(std::chrono::steady_clock::now()), next_(start_) {}

ProgressLine::~ProgressLine() {
  if (written_) std::cerr << kClearLine << std::flush;
}

void ProgressLine::operator()(int step, double displacement) {
  if (!shown_) return;
  const auto now = std::chrono::steady_clock::now();
  if (now < next_) return;
  next_ = now + kInterval;
  written_ = true;
  std::string line = text(step, displacement, std::chrono::duration<double>(now - start_).count());
  // A line longer than the terminal would wrap, and the next one would not write over it.
  if (winsize w{}; ::ioctl(STDERR_FILENO, TIOCGWINSZ, &w) == 0 && w.ws_col > 1 && line.size() >= w.ws_col)
    line.resize(w.ws_col - 1u);
  std::cerr << kClearLine << line << std::flush;
}

std::string ProgressLine::text(int step, double displacement, double elapsed_s) const {
  char head[160];
  std::snprintf(head, sizeof head, "  step %d of %s%d (%.0f%%), %.4g s simulated, %s on the host clock", step,
                threshold_ > 0 ? "at most " : "", max_steps_, 100.0 * step / max_steps_, step * dt_,
                duration_text(elapsed_s).c_str());
  std::string line = head;
  const double left = elapsed_s / step * (max_steps_ - step);
  line += (threshold_ > 0 ? ", at most " : ", about ") + duration_text(left) + " left";
  if (threshold_ > 0 && displacement > 0) {
    char tail[96];
    std::snprintf(tail, sizeof tail, "; moved %.3g m (stops under %.3g)", displacement, threshold_);
    line += tail;
  }
  return line;
}

}  // namespace deformlab::app
