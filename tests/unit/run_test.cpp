// The run loop: the paper's stop rule, divergence caught at the step it happens, and the
// stability limit it reports.
#include <gtest/gtest.h>

#include <cmath>
#include <deque>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <utility>

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

// The stop rule starts at min_steps, or at the first step at or past the drag path's end; a
// path too long for an int's steps never lets it start (and takes no time to say so).
TEST(Run, FirstStopStepIsMinStepsOrThePathsEnd) {
  Params p;
  p.dt = 0.002f;
  p.min_steps = 100;
  EXPECT_EQ(first_stop_step(p), 100) << "no drag";
  p.drag = {0, {{0.f, {}}, {2.f, {}}}, false, 1.f};
  EXPECT_EQ(first_stop_step(p), 1000) << "step 1000 is at t = 2.0000001 s (dt as a float)";
  EXPECT_GE(1000 * double(p.dt), 2.0);
  EXPECT_LT(999 * double(p.dt), 2.0);
  p.min_steps = 5000;
  EXPECT_EQ(first_stop_step(p), 5000);
  p.min_steps = 0;
  p.dt = 1e-10f;
  EXPECT_EQ(first_stop_step(p), std::numeric_limits<int>::max());
}

// Runs `i` from `s0` at 0.98 and 1.02 x `limit`: below it the run ends with `bounded` true of its
// state, above it in a divergence whose message holds `named`.
void expect_sharp_bound(const Model& m, Params p, const State& s0, Integrator i, double limit,
                        const std::function<bool(const State&)>& bounded, const std::string& named = "") {
  for (double f : {0.98, 1.02}) {
    p.dt = float(f * limit);
    auto pipe = make_cpu_pipeline({m, p, i}, Precision::f64, false);
    pipe->set_state(s0);
    if (f < 1) {
      EXPECT_NO_THROW(run(*pipe, m, p, {.integrator = i})) << info(i).name << " at 0.98 x its bound";
      EXPECT_TRUE(bounded(pipe->state())) << info(i).name;
      continue;
    }
    try {
      run(*pipe, m, p, {.integrator = i});
      ADD_FAILURE() << info(i).name << " at 1.02 x its bound did not diverge";
    } catch (const DivergenceError& e) {
      EXPECT_NE(std::string(e.what()).find(named), std::string::npos) << e.what();
    }
  }
}

// Params without gravity, with global damping `damping`, for `max_steps` steps.
Params field_free(float damping, int max_steps, float runaway_factor = 1.f) {
  Params p;
  p.gravity = {};
  p.damping = damping;
  p.max_steps = max_steps;
  p.runaway_factor = runaway_factor;
  return p;
}

// Nodes 0 and 1, 10 cm apart, on one spring of stiffness k and damping kd; node 1 of inverse
// mass 100 /kg, node 0 of `inv_mass0`.
Model one_spring(float inv_mass0, float k, float kd) {
  Model m;
  m.rest_position = {{0.f, 1.f, 0.f}, {0.1f, 1.f, 0.f}};
  m.inv_mass = {inv_mass0, 100.f};
  m.spring_i = {0};
  m.spring_j = {1};
  m.rest_length = {0.1f};
  m.kind = {SpringKind::structural};
  m.stiffness = {k, k, k};
  m.damping = {kd, 0.f, 0.f};
  m.build_adjacency();
  return m;
}

// Two free nodes on one spring: w^2 = 2k/m exactly, which is also the Gershgorin bound. Each
// scheme with a bound stays bounded 2% below it and diverges 2% above it.
TEST(Run, StabilityBoundIsSharpOnASingleSpring) {
  const Model m = one_spring(100.f, 500.f, 0.f);
  const Params p = field_free(0.f, 4000);
  State s0 = rest_state(m);
  s0.x[1].x += 1e-3f;  // stretched 1 mm
  for (Integrator i : {Integrator::semi_implicit_euler, Integrator::verlet, Integrator::rk3, Integrator::rk4}) {
    const double limit = stability_limit(m, p, i);
    const double c = i == Integrator::rk3 ? std::sqrt(3.0) : i == Integrator::rk4 ? 2 * std::sqrt(2.0) : 2.0;
    EXPECT_NEAR(limit, c / std::sqrt(2 * 500 * 100.0), 1e-9) << info(i).name;
    // Within 10x the stretch below the bound.
    expect_sharp_bound(m, p, s0, i, limit, [](const State& s) { return std::abs(s.x[1].x - 0.1f) < 1e-2; });
  }
}

// One free node without springs, damped: v' = -(c/m) v. Each scheme's velocity decays 2% below
// its damping bound and grows, a divergence that names the damping, 2% above it.
TEST(Run, DampingBoundIsSharpOnAFreeNode) {
  Model m;
  m.rest_position = {{0.f, 1.f, 0.f}};
  m.inv_mass = {100.f};
  m.build_adjacency();
  // c/m = 50 /s; 1 km a step: the first steps at 1 m/s move 4 cm, more than the 1 mm a point's
  // extent allows.
  Params p = field_free(0.5f, 2000, 1e6f);
  State s0 = rest_state(m);
  s0.v[0] = {1.f, 0.f, 0.f};
  for (Integrator i : {Integrator::explicit_euler, Integrator::semi_implicit_euler, Integrator::midpoint,
                       Integrator::verlet, Integrator::rk3, Integrator::rk4}) {
    const double limit = damping_limit(m, p, i);
    const double reach = i == Integrator::rk3 ? 2.5127453266183286 : i == Integrator::rk4 ? 2.785293563405282 : 2.0;
    EXPECT_NEAR(limit, reach / 50.0, 1e-12) << info(i).name;
    expect_sharp_bound(m, p, s0, i, limit, [](const State& s) { return norm(s.v[0]) < 1e-3f; },
                       "'s bound for the damping (global damping 0.5 N s/m: dt < ");
  }
  EXPECT_TRUE(std::isinf(damping_limit(m, p, Integrator::backward_euler)));
  p.drag = {0, {{0.f, {}}, {1.f, {}}}, false, 1.f};  // hard-dragged: the node follows its path, not its velocity
  EXPECT_TRUE(std::isinf(damping_limit(m, p, Integrator::semi_implicit_euler)));
  p.drag.as_spring = true;  // pulled by a spring: free, and damped
  EXPECT_NEAR(damping_limit(m, p, Integrator::semi_implicit_euler), 2.0 / 50.0, 1e-12);
  p.damping = 0.f;
  EXPECT_TRUE(std::isinf(damping_limit(m, p, Integrator::semi_implicit_euler)));
}

// The springs' damping along their axis: on a spring between two free nodes of mass m the
// stretch rate decays as u' = -(2 kd / m) u, on one to a pinned node as u' = -(kd / m) u; the
// Gershgorin bound is exact on both, and sharp for each scheme as on a free node. (The weak
// spring's stiffness lowers semi-implicit Euler's and Verlet's joint bound by 0.02%: their
// divergence names that one, the tightest.)
TEST(Run, SpringDampingBoundIsSharpOnASpring) {
  for (const bool pinned : {false, true}) {
    // w^2 = 0.2 /s^2: the damping (gamma = 25 or 50 /s) sets the bound.
    const Model m = one_spring(pinned ? 0.f : 100.f, 1e-3f, 0.25f);
    const Params p = field_free(0.f, 2000, 1e6f);
    State s0 = rest_state(m);
    s0.v[1] = {1.f, 0.f, 0.f};  // stretching at 1 m/s
    const double gamma = pinned ? 25.0 : 50.0;
    for (Integrator i : {Integrator::explicit_euler, Integrator::semi_implicit_euler, Integrator::midpoint,
                         Integrator::verlet, Integrator::rk3, Integrator::rk4}) {
      const double limit = damping_limit(m, p, i);
      const double reach = i == Integrator::rk3 ? 2.5127453266183286 : i == Integrator::rk4 ? 2.785293563405282 : 2.0;
      EXPECT_NEAR(limit, reach / gamma, 1e-9) << info(i).name << (pinned ? " to a pinned node" : "");
      const bool joint = i == Integrator::semi_implicit_euler || i == Integrator::verlet;
      expect_sharp_bound(m, p, s0, i, limit, [](const State& s) { return norm(s.v[1] - s.v[0]) < 1e-3f; },
                         joint ? "'s bound for the springs and the damping together (dt < "
                               : "'s bound for the damping (global damping 0 N s/m and the springs' damping: dt < ");
    }
  }
}

// Stiff and damped at once: on two free nodes on one spring, u'' = -w^2 u - gamma u' with
// w^2 = 2k/m = 1e5 /s^2 and gamma = 2 kd/m = 50 /s exactly, so semi-implicit Euler's and
// Verlet's bound w^2 dt^2 + 2 gamma dt = 4 (5.84 ms) is sharp, under each bound alone (6.32 ms
// for the springs, 40 ms for the damping).
TEST(Run, SpringsAndDampingTogetherBoundIsSharpOnASpring) {
  const Model m = one_spring(100.f, 500.f, 0.25f);
  // 1 cm a step: growing, the stretch passes it within 10 steps, before the spring's nonlinearity
  // (a stretch like its length) bounds it; decaying from 1 mm, no node moves 2 mm a step.
  const Params p = field_free(0.f, 4000, 0.1f);
  State s0 = rest_state(m);
  s0.x[1].x += 1e-3f;  // stretched 1 mm
  for (Integrator i : {Integrator::semi_implicit_euler, Integrator::verlet}) {
    const double limit = damped_stability_limit(m, p, i);
    EXPECT_NEAR(limit, (std::sqrt(50.0 * 50.0 + 4e5) - 50.0) / 1e5, 1e-9) << info(i).name;
    EXPECT_LT(limit, stability_limit(m, p, i));
    expect_sharp_bound(m, p, s0, i, limit, [](const State& s) { return std::abs(s.x[1].x - s.x[0].x - 0.1f) < 1e-3f; },
                       "'s bound for the springs and the damping together (dt < 0.00584 s");
  }
  EXPECT_TRUE(std::isinf(damped_stability_limit(m, p, Integrator::rk4))) << "derived for the symplectic pair only";
}

// Where dt passes several bounds, the note names the tightest: on the stiff damped spring above
// RK4's springs' bound (8.9 ms) lies under its damping's (55.7 ms), and semi-implicit Euler's
// joint bound (5.84 ms) under both of its own.
TEST(Run, TheBoundNamedIsTheTightestPassed) {
  const Model m = one_spring(100.f, 500.f, 0.25f);
  Params p = field_free(0.f, 100, 0.1f);
  p.dt = 0.06f;
  EXPECT_NE(step_bound_passed(m, p, Integrator::rk4).find("rk4's stability bound dt < 0.00894 s on this model's "
                                                          "linearised springs"),
            std::string::npos)
      << step_bound_passed(m, p, Integrator::rk4);
  EXPECT_NE(step_bound_passed(m, p, Integrator::semi_implicit_euler)
                .find("semi-implicit-euler's bound for the springs and the damping together (dt < 0.00584 s"),
            std::string::npos)
      << step_bound_passed(m, p, Integrator::semi_implicit_euler);
  p.dt = 0.005f;  // under all three
  EXPECT_EQ(step_bound_passed(m, p, Integrator::semi_implicit_euler), "");
}

// A field that moves a free node falling from rest more than the runaway distance in the step
// that tripped the check is named as the cause; global damping slows the fall to its terminal
// step a dt / gamma, and an ordinary field leaves the stability bound named.
TEST(Run, AFieldTooStrongForTheRunawayCheckIsNamed) {
  const Model m = test::small_cloth(6, 6);
  Params p = test::small_params();
  p.gravity = {0.f, -1e9f, 0.f};  // 4 km in the first step at dt = 2 ms
  p.dt = 0.002f;
  auto pipe = make_cpu_pipeline({m, p, Integrator::semi_implicit_euler}, Precision::f32, false);
  try {
    run(*pipe, m, p, {});
    ADD_FAILURE() << "no DivergenceError";
  } catch (const DivergenceError& e) {
    EXPECT_EQ(e.step, 1);
    const std::string what = e.what();
    EXPECT_NE(what.find("gravity and wind alone move a free node falling from rest 4000 m at this step"),
              std::string::npos) << what;
    EXPECT_NE(what.find("the field stopped the run (a larger runaway_factor admits the fall)"), std::string::npos)
        << what;
    EXPECT_EQ(what.find(stability_hint(m, p, Integrator::semi_implicit_euler)), std::string::npos) << what;
  }
  const Integrator semi = Integrator::semi_implicit_euler;
  const double runaway = double(p.runaway_factor) * m.extent();  // 0.35 m
  // Not finite: the field is named only where its fall overflows a move's float length (a fall
  // of 4 km would have tripped the distance check first).
  const std::string finite_fall = divergence(INFINITY, m.extent(), m, p, semi, 1, 0.0);
  EXPECT_EQ(finite_fall.find("gravity and wind"), std::string::npos) << finite_fall;
  p.gravity = {0.f, -1e30f, 0.f};  // 4e24 m in the first step
  const std::string overflow = divergence(INFINITY, m.extent(), m, p, semi, 1, 0.0);
  EXPECT_NE(overflow.find("not finite in float; gravity and wind alone move a free node falling from rest 4e+24 m at "
                          "this step, more than float holds for a move, 1.84467e+19 m: the field stopped the run"),
            std::string::npos)
      << overflow;
  EXPECT_EQ(overflow.find("runaway_factor admits"), std::string::npos) << overflow;
  // g = 1e3 at dt = 2 ms: step 1000 of an undamped fall moves 4 m; damped at gamma = 100 /s,
  // 2 cm (a dt / gamma): under the runaway distance, so the stability bound is named.
  p.gravity = {0.f, -1e3f, 0.f};
  ASSERT_GT(4.0, 2 * runaway);
  p.damping = 0.f;
  EXPECT_NE(divergence(2 * runaway, m.extent(), m, p, semi, 1000, 0.0).find("falling from rest 4 m at this step"),
            std::string::npos);
  p.damping = 1.f;  // 0.01 kg a node: gamma = 100 /s
  EXPECT_EQ(divergence(2 * runaway, m.extent(), m, p, semi, 1000, 0.0).find("gravity and wind"), std::string::npos);
  p.damping = 0.02f;
  p.gravity = {0.f, -9.81f, 0.f};
  EXPECT_EQ(divergence(INFINITY, m.extent(), m, p, semi, 1, 0.0).find("gravity and wind"), std::string::npos);
}

// A stop rule that any run passes is named: a threshold past the runaway distance, or a dt so
// small that a free fall's steps stay under the threshold for all of max_steps (damped: under
// its terminal step a dt / gamma).
TEST(Run, AStopRuleThatAnyRunPassesIsNamed) {
  const Model m = test::small_cloth(6, 6);
  Params p = test::small_params();
  EXPECT_EQ(loose_stop_rule(m, p), "") << "the tests' scene";
  p.threshold = 1e30f;
  EXPECT_NE(loose_stop_rule(m, p).find("is at least the runaway distance"), std::string::npos);
  p.threshold = 1e-3f;
  p.max_steps = 1000;
  p.damping = 0.f;
  p.dt = float(std::sqrt(0.999e-3 / (9.81 * 1000)));  // the 1000th step of a fall moves 0.999 mm
  EXPECT_NE(loose_stop_rule(m, p).find("(0.000999 m at most): unless springs"), std::string::npos)
      << loose_stop_rule(m, p);
  p.dt = float(std::sqrt(1.001e-3 / (9.81 * 1000)));
  EXPECT_EQ(loose_stop_rule(m, p), "");
  p.dt = 1e-3f;
  p.max_steps = 1000000;
  EXPECT_EQ(loose_stop_rule(m, p), "") << "undamped, the fall passes 1 mm a step at step 102";
  p.damping = 0.2f;  // gamma = 20 /s: at most 9.81 x 1e-3 / 20 = 0.49 mm a step
  EXPECT_NE(loose_stop_rule(m, p).find("(0.0004905 m at most)"), std::string::npos) << loose_stop_rule(m, p);
  // gamma dt = 1.5: the speed overshoots its terminal value, so the first step moves most
  // (a dt^2 = 2.21 mm, the terminal step 1.47 mm).
  p.dt = 0.015f;
  p.damping = 1.f;
  p.min_steps = 1;
  p.threshold = 2e-3f;
  EXPECT_EQ(loose_stop_rule(m, p), "") << "the first steps pass 2 mm";
  p.threshold = 2.3e-3f;
  EXPECT_NE(loose_stop_rule(m, p).find("(0.00220725 m at most)"), std::string::npos) << loose_stop_rule(m, p);
  p.gravity = {};
  p.wind = {};
  EXPECT_EQ(loose_stop_rule(m, p), "") << "no field: nothing to say";
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

// The runaway limit: runaway_factor x the model's extent, the extent counted as at least 1 mm;
// a state that is not finite always.
TEST(Run, TheRunawayLimitIsTheExtentWithAMillimetreFloor) {
  const Model m = test::small_cloth(4, 4);
  Params p = test::small_params();
  p.runaway_factor = 2.0f;
  const Integrator i = Integrator::semi_implicit_euler;
  EXPECT_TRUE(divergence(1.9, 1.0f, m, p, i, 1, 0.0).empty());
  EXPECT_FALSE(divergence(2.1, 1.0f, m, p, i, 1, 0.0).empty());
  EXPECT_TRUE(divergence(1.9e-3, 1e-5f, m, p, i, 1, 0.0).empty()) << "below 2 x 1 mm";
  EXPECT_FALSE(divergence(2.1e-3, 1e-5f, m, p, i, 1, 0.0).empty());
  EXPECT_FALSE(divergence(std::nan(""), 1.0f, m, p, i, 1, 0.0).empty());
  EXPECT_FALSE(divergence(INFINITY, 1.0f, m, p, i, 1, 0.0).empty());
}

TEST(Run, DivergenceIsCaughtAtTheStepItHappens) {
  const Model m = test::small_cloth(10, 10);
  Params p = test::small_params();
  p.dt = float(3 * stability_limit(m, p, Integrator::semi_implicit_euler));
  p.max_steps = 5000;
  for (Integrator integ : {Integrator::explicit_euler, Integrator::semi_implicit_euler, Integrator::rk4}) {
    // Find the first bad step by stepping by hand, each step set against the limit.
    auto probe = make_cpu_pipeline({m, p, integ}, Precision::f32, false);
    int first_bad = 0;
    for (int k = 1; k <= p.max_steps && !first_bad; ++k) {
      probe->step();
      if (!divergence(probe->max_displacement(), m.extent(), m, p, integ, k, 0.0).empty()) first_bad = k;
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

// A CPU pipeline that can take its last launch back, as the GPU pipelines do, with `per_launch`
// steps a launch (cuda-temporal's k): the lagged checks must give the run the same end as checks
// that wait. It checks that the run loop queues checks and takes launches back only where a
// launch ends.
class SteppingBack final : public Pipeline {
 public:
  SteppingBack(std::unique_ptr<Pipeline> p, bool can, int per_launch)
      : p_(std::move(p)), can_(can), per_launch_(per_launch) {}
  void set_state(const State& s) override { p_->set_state(s); }
  State state() override { return p_->state(); }
  void step() override {
    if (steps_ % per_launch_ == 0) before_ = p_->state();
    p_->step();
    ++steps_;
  }
  void set_drag(const DragHandle& d) override { p_->set_drag(d); }
  double max_displacement() override { return p_->max_displacement(); }
  bool can_step_back() const override { return can_; }
  int steps_per_launch() const override { return per_launch_; }
  void step_back() override {
    ASSERT_EQ(steps_ % per_launch_, 0) << "a launch taken back before it ended";
    ASSERT_TRUE(before_.has_value()) << "launch taken back twice";
    p_->set_state(*std::exchange(before_, std::nullopt));
    steps_ -= per_launch_;
    ++taken_back;
  }
  void queue_displacement() override {
    EXPECT_EQ(steps_ % per_launch_, 0) << "a check queued within a launch";
    queued_.push_back(p_->max_displacement());
    ++queues;
  }
  double take_displacement() override {
    const double d = queued_.front();
    queued_.pop_front();
    return d;
  }
  int queues = 0, taken_back = 0;

 private:
  std::unique_ptr<Pipeline> p_;
  bool can_;
  int per_launch_;
  int steps_ = 0;
  std::optional<State> before_;  // the state before the last launch
  std::deque<double> queued_;
};

struct Ended {
  RunResult r;
  State s;
  int diverged_at = 0, queues = 0, taken_back = 0;
};

Ended run_checked(const Model& m, const Params& p, Integrator i, bool can_step_back, int per_launch = 1) {
  SteppingBack pipe(make_cpu_pipeline({m, p, i}, Precision::f32, false), can_step_back, per_launch);
  Ended e;
  try {
    e.r = run(pipe, m, p, {.until_converged = true, .integrator = i});
  } catch (const DivergenceError& err) {
    e.diverged_at = err.step;
  }
  e.s = pipe.state();
  e.queues = pipe.queues;
  e.taken_back = pipe.taken_back;
  return e;
}

void expect_same_end(const Ended& lagged, const Ended& waited) {
  EXPECT_GT(lagged.queues, 0);
  EXPECT_EQ(waited.queues, 0);
  EXPECT_EQ(lagged.diverged_at, waited.diverged_at);
  EXPECT_EQ(lagged.r.steps, waited.r.steps);
  EXPECT_EQ(lagged.r.converged, waited.r.converged);
  EXPECT_EQ(lagged.r.last_displacement, waited.r.last_displacement);
  EXPECT_EQ(lagged.s.t, waited.s.t);
  EXPECT_EQ(test::max_position_diff(lagged.s, waited.s), 0.0);
  EXPECT_EQ(test::max_diff(lagged.s.v, waited.s.v), 0.0);
  ASSERT_EQ(lagged.r.records.size(), waited.r.records.size());
  for (std::size_t k = 0; k < lagged.r.records.size(); ++k) {
    const double a = lagged.r.records[k].max_displacement, b = waited.r.records[k].max_displacement;
    EXPECT_TRUE(a == b || (std::isnan(a) && std::isnan(b))) << "step " << k + 1 << ": " << a << " vs " << b;
  }
}

Params settling_params() {
  Params p = test::small_params();
  p.damping = 0.5f;
  p.threshold = 1e-5f;
  p.max_steps = 50000;
  p.min_steps = 50;
  return p;
}

TEST(Run, LaggedChecksEndWhereWaitingChecksEnd) {
  const Model m = test::small_cloth(12, 12);
  Params p = settling_params();
  for (int every : {1, 3}) {
    p.check_every = every;
    const Ended lagged = run_checked(m, p, Integrator::semi_implicit_euler, true);
    const Ended waited = run_checked(m, p, Integrator::semi_implicit_euler, false);
    ASSERT_TRUE(waited.r.converged) << "every " << every;
    EXPECT_EQ(lagged.taken_back, 1) << "every " << every;  // the step queued after the stop
    expect_same_end(lagged, waited);
  }
  p.max_steps = 40;  // the budget ends it before the rule: nothing to take back
  const Ended lagged = run_checked(m, p, Integrator::semi_implicit_euler, true);
  EXPECT_EQ(lagged.taken_back, 0);
  EXPECT_EQ(lagged.r.steps, 40);
  expect_same_end(lagged, run_checked(m, p, Integrator::semi_implicit_euler, false));
}

// Several steps a launch: a check at a launch's end is read while the next launch runs, and the
// stop takes that whole launch back.
TEST(Run, LaggedChecksOverLaunchesEndWhereWaitingChecksEnd) {
  const Model m = test::small_cloth(12, 12);
  Params p = settling_params();
  for (int per_launch : {2, 3}) {
    for (int every : {per_launch, 2 * per_launch}) {
      p.check_every = every;
      const Ended lagged = run_checked(m, p, Integrator::semi_implicit_euler, true, per_launch);
      const Ended waited = run_checked(m, p, Integrator::semi_implicit_euler, false, per_launch);
      ASSERT_TRUE(waited.r.converged) << per_launch << " a launch, every " << every;
      EXPECT_EQ(lagged.taken_back, 1) << per_launch << " a launch, every " << every;
      EXPECT_EQ(lagged.r.steps % every, 0);
      expect_same_end(lagged, waited);
    }
  }
  // Checks that fall within launches wait for their steps.
  p.check_every = 3;
  const Ended within = run_checked(m, p, Integrator::semi_implicit_euler, true, 2);
  EXPECT_EQ(within.queues, 0);
  EXPECT_EQ(within.taken_back, 0);
  EXPECT_TRUE(within.r.converged);
  // A budget that ends within a launch: the checks of its last launch wait.
  p.check_every = 2;
  p.max_steps = 41;
  const Ended budget = run_checked(m, p, Integrator::semi_implicit_euler, true, 2);
  EXPECT_EQ(budget.taken_back, 0);
  EXPECT_EQ(budget.r.steps, 41);
  expect_same_end(budget, run_checked(m, p, Integrator::semi_implicit_euler, false, 2));
}

TEST(Run, LaggedChecksCatchDivergenceAtTheSameStep) {
  const Model m = test::small_cloth(10, 10);
  Params p = test::small_params();
  p.dt = float(3 * stability_limit(m, p, Integrator::semi_implicit_euler));
  p.max_steps = 5000;
  for (int per_launch : {1, 2}) {
    p.check_every = per_launch;
    const Ended lagged = run_checked(m, p, Integrator::semi_implicit_euler, true, per_launch);
    const Ended waited = run_checked(m, p, Integrator::semi_implicit_euler, false, per_launch);
    ASSERT_GT(waited.diverged_at, 0);
    EXPECT_EQ(lagged.taken_back, 1);
    expect_same_end(lagged, waited);
  }
}

}  // namespace
}  // namespace deformlab
