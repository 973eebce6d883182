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
  const Integrator semi = Integrator::semi_implicit_euler;
  EXPECT_NEAR(stability_limit(m, Params{}, semi), 2 * std::sqrt(0.01 / k_eff), 1e-12);
  EXPECT_NEAR(stability_limit(m, Params{}, Integrator::rk4), std::sqrt(2.0) * stability_limit(m, Params{}, semi), 1e-12);
  EXPECT_EQ(stability_limit(m, Params{}, Integrator::explicit_euler), 0.0);
  EXPECT_TRUE(std::isinf(stability_limit(m, Params{}, Integrator::backward_euler)));
  // A stiff drag spring (to a fixed target: one row term) lowers it on its node.
  Params p;
  p.drag = {40, {{0.f, {}}}, true, 1e5f};
  EXPECT_NEAR(stability_limit(m, p, semi), 2 * std::sqrt(0.01 / (k_eff + 1e5)), 1e-12);
}

// Two free nodes on one spring: w^2 = 2k/m exactly, which is also the Gershgorin bound. Each
// scheme with a bound stays bounded 2% below it and diverges 2% above it.
TEST(Run, StabilityBoundIsSharpOnASingleSpring) {
  Model m;
  m.rest_position = {{0.f, 1.f, 0.f}, {0.1f, 1.f, 0.f}};
  m.inv_mass = {100.f, 100.f};
  m.spring_i = {0};
  m.spring_j = {1};
  m.rest_length = {0.1f};
  m.kind = {SpringKind::structural};
  m.stiffness = {500.f, 500.f, 500.f};
  m.build_adjacency();
  Params p;
  p.gravity = {};
  p.damping = 0.f;
  p.max_steps = 4000;
  State s0 = rest_state(m);
  s0.x[1].x += 1e-3f;  // stretched 1 mm
  for (Integrator i : {Integrator::semi_implicit_euler, Integrator::verlet, Integrator::rk3, Integrator::rk4}) {
    const double limit = stability_limit(m, p, i);
    const double c = i == Integrator::rk3 ? std::sqrt(3.0) : i == Integrator::rk4 ? 2 * std::sqrt(2.0) : 2.0;
    EXPECT_NEAR(limit, c / std::sqrt(2 * 500 * 100.0), 1e-9) << info(i).name;
    for (double f : {0.98, 1.02}) {
      p.dt = float(f * limit);
      auto pipe = make_cpu_pipeline({m, p, i}, Precision::f64, false);
      pipe->set_state(s0);
      if (f < 1) {
        EXPECT_NO_THROW(run(*pipe, m, p, {.integrator = i})) << info(i).name << " at 0.98 x its bound";
        EXPECT_LT(std::abs(pipe->state().x[1].x - 0.1f), 1e-2) << info(i).name;  // 10x the stretch
      } else {
        EXPECT_THROW(run(*pipe, m, p, {.integrator = i}), DivergenceError) << info(i).name << " at 1.02 x its bound";
      }
    }
  }
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
  p.dt = float(3 * stability_limit(m, p, Integrator::semi_implicit_euler));
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
      run(*pipe, m, p, {.integrator = integ});
      FAIL() << info(integ).name << ": no DivergenceError";
    } catch (const DivergenceError& e) {
      EXPECT_EQ(e.step, first_bad) << info(integ).name;
      const std::string what = e.what();
      EXPECT_NE(what.find("diverged at step " + std::to_string(first_bad)), std::string::npos) << what;
      EXPECT_NE(what.find(stability_hint(m, p, integ)), std::string::npos) << what;
    }
  }
}

TEST(Run, CheckEveryKStepsStillCatchesDivergence) {
  const Model m = test::small_cloth(10, 10);
  Params p = test::small_params();
  p.dt = float(3 * stability_limit(m, p, Integrator::semi_implicit_euler));
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
