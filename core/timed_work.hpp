// Work timed as a GPU pipeline's steps are: after a warm-up, calls back to back (no wait between
// them) for about kGpuTimedMs, each on a StepTimer, with the GPU's clock watched over them. The
// benches' cases and references (the copies, the bare gathers) and the calibration time their
// work this way, so that a reference and the step it is set against share a method.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "core/clock_watch.hpp"
#include "core/step_timer.hpp"

namespace deformlab {

class Pipeline;
struct Model;

// `calls` calls of `work`, each timed by `t` (`prepare`, where given, before each and outside its
// time); their ms in order (waits for them).
std::vector<double> timed_calls(StepTimer& t, const std::function<void()>& work, int calls,
                                const std::function<void()>& prepare = {});

struct TimedWork {
  std::vector<double> ms;  // each timed call, in order
  ClockSummary clock;      // over the timed calls
  double median_ms() const;
};

// `work` on `t` (nothing pending): `warmup` calls, then calls back to back spanning about
// kGpuTimedMs at the warm-up's median call (its first left out), `min_calls` at the least
// (without a warm-up, `min_calls`), rounded up to a multiple of `multiple`; `prepare` as timed_calls'. The GPU with PCI bus id
// `bus` (empty: NVML's first) is watched over the timed calls.
TimedWork time_back_to_back(StepTimer& t, const std::function<void()>& work, int warmup, int min_calls,
                            const std::string& bus = {}, int multiple = 1,
                            const std::function<void()>& prepare = {});

// A GPU pipeline's steps timed as `deformlab run` times them: warm_up_from_rest(p, m, warm_ms),
// then time_back_to_back of p's steps on its step clock.
TimedWork time_steps(Pipeline& p, const Model& m, double warm_ms, int warmup, int min_steps,
                     const std::string& bus = {}, int multiple = 1);

}  // namespace deformlab
