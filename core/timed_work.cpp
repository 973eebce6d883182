#include "timed_work.hpp"

#include <algorithm>
#include <numeric>

#include "pipeline.hpp"
#include "profiler.hpp"

namespace deformlab {

double TimedWork::median_ms() const { return median(ms); }

TimedWork time_back_to_back(StepTimer& t, const std::function<void()>& work, int warmup, int min_calls,
                            const std::string& bus, int multiple, const std::function<void()>& prepare) {
  const auto timed = [&](int calls) {
    for (int c = 0; c < calls; ++c) {
      if (prepare) prepare();
      t.begin();
      work();
      t.end();
    }
    return t.take();
  };
  const std::vector<double> warm = timed(warmup);
  const double mean = warm.empty() ? 0.0 : std::accumulate(warm.begin(), warm.end(), 0.0) / double(warm.size());
  const int calls = steps_spanning(warm.empty() ? 0.0 : kGpuTimedMs, std::max(mean, 1e-3), min_calls, multiple);
  ClockWatch watch(bus);
  TimedWork w;
  w.ms = timed(calls);
  w.clock = watch.stop();
  return w;
}

}  // namespace deformlab
