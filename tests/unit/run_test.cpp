// The run loop: the paper's stop rule, divergence caught at the step it happens, and the
// stability limit it reports.
#include <gtest/gtest.h>

#include <cmath>

#include "core/cpu_backend.hpp"
#include "core/run.hpp"
#include "tests/support/test_states.hpp"

namespace deformlab {
namespace {

TEST(Run, StabilityLimitIsTheGershgorinBound) {
  // Interior cloth node: 4 x 500 + 4 x 500 + 4 x 100 N/m incident; 0.01 kg.
  const Model m = test::small_cloth(9, 9);
  const double k_eff = 2.0 * (4 * 500 + 4 * 500 + 4 * 100);
  EXPECT_NEAR(explicit_stability_limit(m, Params{}), 2 * std::sqrt(0.01 / k_eff), 1e-12);
  // A stiff drag spring lowers it on its node.
  Params p;
  p.drag = {40, {{0.f, {}}}, true, 1e5f};
  EXPECT_NEAR(explicit_stability_limit(m, p), 2 * std::sqrt(0.01 / (k_eff + 2e5)), 1e-12);
}

TEST(Run, StopsWhenNoNodeMovesMoreThanTheThreshold) {
  const Model m = test::small_cloth(12, 12);
  Params p = test::small_params();
  p.damping = 0.5f;
  p.threshold = 1e-5f;  // 1 cm/s at dt = 1 ms
  p.max_steps = 50000;
  p.min_steps = 50;
  auto pipe = make_cpu_pipeline({m, p, Integrator::semi_implicit_euler}, Precision::f32, true);
  const RunResult r = run(*pipe, m, p, {.until_converged = true});
  ASSERT_TRUE(r.converged);
  EXPECT_LT(r.steps, p.max_steps);
  EXPECT_GT(r.steps, p.min_steps + 1);
  EXPECT_LT(r.last_displacement, p.threshold);
  // The step before it still moved more than the threshold (the rule stops at the first).
  ASSERT_GE(r.records.size(), 2u);
  EXPECT_GE(r.records[r.records.size() - 2].max_displacement, p.threshold);
  EXPECT_EQ(int(r.records.size()), r.steps);
}

TEST(Run, WaitsForTheDragPathToEnd) {
  const Model m = test::small_cloth(8, 8);
  Params p = test::small_params();
  p.gravity = {};
  p.min_steps = 0;
  p.drag.node = 27;
  p.drag.path = {{0.3f, m.rest_position[27]}, {0.4f, m.rest_position[27] + Vec3f{0.f, 0.f, 0.01f}}};
  auto pipe = make_cpu_pipeline({m, p, Integrator::semi_implicit_euler}, Precision::f32, true);
  const RunResult r = run(*pipe, m, p, {.until_converged = true});
  ASSERT_TRUE(r.converged);
  EXPECT_GE(r.steps * double(p.dt), 0.4 - 1e-9);
}

TEST(Run, FixedStepCountWithoutTheStopRule) {
  const Model m = test::small_cloth(6, 6);
  Params p = test::small_params();
  p.max_steps = 37;
  auto pipe = make_cpu_pipeline({m, p, Integrator::rk4}, Precision::f32, false);
  const RunResult r = run(*pipe, m, p, {});
  EXPECT_EQ(r.steps, 37);
  EXPECT_FALSE(r.converged);
  EXPECT_NEAR(pipe->state().t, 37 * double(p.dt), 1e-12);
}

TEST(Run, DivergenceIsCaughtAtTheStepItHappens) {
  const Model m = test::small_cloth(10, 10);
  Params p = test::small_params();
  p.dt = float(3 * explicit_stability_limit(m, p));
  p.max_steps = 5000;
  for (Integrator integ : {Integrator::explicit_euler, Integrator::semi_implicit_euler, Integrator::rk4}) {
    // Find the first bad step by hand.
    auto probe = make_cpu_pipeline({m, p, integ}, Precision::f32, false);
    const double runaway = p.runaway_factor * m.extent();
    int first_bad = 0;
    for (int k = 1; k <= p.max_steps && !first_bad; ++k) {
      probe->step();
      const double d = probe->max_displacement();
      if (!std::isfinite(d) || d > runaway) first_bad = k;
    }
    ASSERT_GT(first_bad, 0) << info(integ).name << " did not diverge at 3x the limit";
    auto pipe = make_cpu_pipeline({m, p, integ}, Precision::f32, false);
    try {
      run(*pipe, m, p, {});
      FAIL() << info(integ).name << ": no DivergenceError";
    } catch (const DivergenceError& e) {
      EXPECT_EQ(e.step, first_bad) << info(integ).name;
      const std::string what = e.what();
      EXPECT_NE(what.find("diverged at step " + std::to_string(first_bad)), std::string::npos) << what;
      EXPECT_NE(what.find("dt < 2 sqrt(m / k_eff)"), std::string::npos) << what;
    }
  }
}

TEST(Run, CheckEveryKStepsStillCatchesDivergence) {
  const Model m = test::small_cloth(10, 10);
  Params p = test::small_params();
  p.dt = float(3 * explicit_stability_limit(m, p));
  p.check_every = 8;
  p.max_steps = 5000;
  auto pipe = make_cpu_pipeline({m, p, Integrator::semi_implicit_euler}, Precision::f32, false);
  try {
    run(*pipe, m, p, {});
    FAIL() << "no DivergenceError";
  } catch (const DivergenceError& e) {
    EXPECT_EQ(e.step % 8, 0);
  }
}

}  // namespace
}  // namespace deformlab
