// StepTimer: the time of each step on the clock of what runs it. A pipeline on the host has
// done a step when step() returns: the host clock around the call is its time. A GPU pipeline
// has only queued it: CUDA events or GL timestamps around the queued work time the device.
#pragma once
#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace deformlab {

class StepTimer {
 public:
  virtual ~StepTimer() = default;
  virtual void begin() = 0;  // just before Pipeline::step()
  virtual void end() = 0;    // just after it
  // ms of each step ended since the last call, in order; waits for the device to finish them.
  virtual std::vector<double> take() = 0;
  // The clock, as a user reads it ("CUDA events", "GL timer queries", "host clock").
  virtual std::string clock() const = 0;
};

// The host's steady_clock around the call.
class HostStepTimer final : public StepTimer {
 public:
  void begin() override { t0_ = std::chrono::steady_clock::now(); }
  void end() override {
    done_.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0_).count());
  }
  std::vector<double> take() override { return std::exchange(done_, {}); }
  std::string clock() const override { return "host clock"; }

 private:
  std::chrono::steady_clock::time_point t0_;
  std::vector<double> done_;
};

}  // namespace deformlab
