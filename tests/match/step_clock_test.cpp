// Every pipeline's step clock (Pipeline::step_timer) through the run loop: each step gets a
// time and the times fit inside the host's wall time of the run (from before the first step
// to the drained device after the last). How much of it they fill depends on whether the host
// or the device is the slower (and, in a parallel test run, on the other processes): the three
// ways of timing one scene are compared on the GPU machine (scripts/gpu-check.sh, timing).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>

#include "core/run.hpp"
#include "experiments/pipelines.hpp"
#include "tests/match/pipeline_names.hpp"
#include "tests/support/test_states.hpp"
#include "tests/support/gpu_required.hpp"

namespace deformlab::test {
namespace {

class StepClock : public testing::TestWithParam<std::string> {};

bool device_clock(const std::string& clock) { return clock == "CUDA events" || clock.starts_with("GL timer queries"); }

TEST_P(StepClock, TimesEveryStepWithinTheDrainedWallTime) {
  const PipelineEntry& e = *pipelines().find(GetParam());
  DEFORMLAB_SKIP_IF_UNAVAILABLE(e.unavailable());
  Params p = small_params();
  p.max_steps = 40;
  p.check_every = p.max_steps;  // one check, at the end: nothing drains the device before it
  int n = 64;
  if (device_clock(e.make({small_cloth(n, n), p, Integrator::semi_implicit_euler})->step_timer()->clock())) n = 1024;
  const Model m = small_cloth(n, n);
  auto pipe = e.make({m, p, Integrator::semi_implicit_euler});
  for (int k = 0; k < 4; ++k) pipe->step();  // first-use costs (shader compiles, step graphs) out of the run
  pipe->max_displacement();

  const auto t0 = std::chrono::steady_clock::now();
  const RunResult r = run(*pipe, m, p, {});
  pipe->max_displacement();
  const double wall_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

  ASSERT_EQ(int(r.records.size()), p.max_steps);
  double sum = 0.0;
  for (const StepRecord& rec : r.records) {
    EXPECT_TRUE(std::isfinite(rec.ms) && rec.ms > 0.0) << "step " << rec.step << ": " << rec.ms;
    EXPECT_GE(rec.queue_ms, 0.0);
    sum += rec.ms;
  }
  EXPECT_NEAR(r.total_ms, sum, 1e-9 * sum);
  EXPECT_LE(sum, 1.01 * r.wall_ms) << r.clock;
  EXPECT_LE(r.wall_ms, wall_ms);
  if (r.clock == "host clock") {
    for (const StepRecord& rec : r.records) EXPECT_LE(rec.ms, rec.queue_ms);  // the timer sits inside
  }
}

INSTANTIATE_TEST_SUITE_P(All, StepClock, testing::ValuesIn(pipeline_names()), pipeline_test_name);

}  // namespace
}  // namespace deformlab::test
