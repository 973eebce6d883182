#include "timed_work.hpp"

#include "pipeline.hpp"
#include "profiler.hpp"

namespace deformlab {

std::vector<double> timed_calls(StepTimer& t, const std::function<void()>& work, int calls,
                                const std::function<void()>& prepare) {
  for (int c = 0; c < calls; ++c) {
    if (prepare) prepare();
    t.begin();
    work();
    t.end();
  }
  return t.take();
}

double TimedWork::median_ms() const { return median(ms); }

TimedWork time_back_to_back(StepTimer& t, const std::function<void()>& work, int warmup, int min_calls,
                            const std::string& bus, int multiple, const std::function<void()>& prepare) {
  const std::vector<double> warm = timed_calls(t, work, warmup, prepare);
  // The warm-up's median without its first call, which may compile shaders: that call (or a mean
  // with it) would cut the span short.
  const std::vector<double> settled(warm.begin() + (warm.size() > 1 ? 1 : 0), warm.end());
  const int calls = steps_spanning(warm.empty() ? 0.0 : kGpuTimedMs, median(settled), min_calls, multiple);
  ClockWatch watch(bus);
  TimedWork w;
  w.ms = timed_calls(t, work, calls, prepare);
  w.clock = watch.stop();
  return w;
}

TimedWork time_steps(Pipeline& p, const Model& m, double warm_ms, int warmup, int min_steps, const std::string& bus,
                     int multiple) {
  warm_up_from_rest(p, m, warm_ms);
  const auto timer = p.step_timer();
  return time_back_to_back(*timer, [&] { p.step(); }, warmup, min_steps, bus, multiple);
}

}  // namespace deformlab
