// The progress line `deformlab run` keeps on a terminal: steps done, simulated time, the host
// clock's elapsed time and an estimate of what is left; on a convergence run, the largest
// displacement last checked against the threshold. Written at the first step and then over
// itself twice a second, and only where stderr is a terminal, so logs and pipes get none.
#pragma once
#include <chrono>
#include <string>

namespace deformlab::app {

class ProgressLine {
 public:
  // `threshold` > 0: the run stops once a check finds no node moving more than that (m).
  ProgressLine(int max_steps, double dt, double threshold);
  ~ProgressLine();  // clears the line
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  bool shown() const { return shown_; }  // whether stderr is a terminal
  void operator()(int step, double displacement);

 private:
  std::string text(int step, double displacement, double elapsed_s) const;

  int max_steps_;
  double dt_, threshold_;
  bool shown_, written_ = false;
  std::chrono::steady_clock::time_point start_, next_;
};

}  // namespace deformlab::app
