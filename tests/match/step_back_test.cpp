// Lagged stop-rule checks (Pipeline::can_step_back): the run loop reads step n's displacement
// while the launch after it runs and takes that launch back when n met the rule (one step; k on
// cuda-temporal, checked every k steps). Every GPU pipeline steps back and must end a run where
// checks that wait for each step end it: the same step, state and displacements (bit for bit
// where the pipeline is deterministic; within the scatter kernels' atomic-order rounding
// otherwise), and catch divergence at the same step.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "core/run.hpp"
#include "experiments/pipelines.hpp"
#include "tests/match/pipeline_names.hpp"
#include "tests/support/test_states.hpp"
#include "tests/support/gpu_required.hpp"

namespace deformlab::test {
namespace {

class StepBack : public testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    e_ = pipelines().find(GetParam());
    DEFORMLAB_SKIP_IF_UNAVAILABLE(e_->unavailable());
  }
  void lagged_checks_end_where_waiting_checks_end(Integrator integ);
  void takes_the_last_launch_back_once(Integrator integ);
  const PipelineEntry* e_ = nullptr;
};

struct Ended {
  RunResult r;
  State s;
  int diverged_at = 0;
  bool could_step_back = false;
  int every = 1;  // the check interval: a launch's steps
};

// From a perturbed state, until the stop rule holds, checking at the end of each launch; `wait`:
// an after_step callback makes every check wait for its step.
Ended run_from(const PipelineEntry& e, const Model& m, const Params& p, bool wait,
               Integrator integ = Integrator::semi_implicit_euler) {
  auto pipe = e.make({m, p, integ});
  pipe->set_state(perturbed_state(m, 7));
  Ended out;
  out.could_step_back = pipe->can_step_back();
  out.every = pipe->steps_per_launch();
  Params checked = p;
  checked.check_every = out.every;
  RunOptions o{.until_converged = true, .integrator = integ};
  if (wait) o.after_step = [](int) {};
  try {
    out.r = run(*pipe, m, checked, o);
  } catch (const DivergenceError& err) {
    out.diverged_at = err.step;
  }
  out.s = pipe->state();
  return out;
}

Params settling_params() {
  Params p = small_params();
  p.gravity = {};       // the perturbation settles back to rest in a few hundred steps
  p.damping = 0.5f;
  p.threshold = 1e-5f;  // 1 cm/s at dt = 1 ms
  p.min_steps = 20;
  p.max_steps = 4000;
  return p;
}

// Semi-implicit Euler, and Verlet, whose step also reads the positions before the current ones.
TEST_P(StepBack, LaggedChecksEndWhereWaitingChecksEnd) {
  for (Integrator integ : {Integrator::semi_implicit_euler, Integrator::verlet})
    if (e_->unsupported(integ).empty()) {
      SCOPED_TRACE(info(integ).name);
      lagged_checks_end_where_waiting_checks_end(integ);
    }
}

void StepBack::lagged_checks_end_where_waiting_checks_end(Integrator integ) {
  const Model m = small_cloth(24, 24);
  const Params p = settling_params();
  const Ended lagged = run_from(*e_, m, p, false, integ), waited = run_from(*e_, m, p, true, integ);
  ASSERT_TRUE(lagged.could_step_back) << GetParam() << " cannot step back: each check waits for its step";
  ASSERT_TRUE(waited.r.converged) << "after " << waited.r.steps << " steps, last " << waited.r.last_displacement;
  ASSERT_TRUE(lagged.r.converged) << "after " << lagged.r.steps << " steps";
  EXPECT_EQ(lagged.s.t, lagged.r.steps * double(p.dt)) << "the launch after the stop was not taken back";
  ASSERT_EQ(int(lagged.r.records.size()), lagged.r.steps);
  EXPECT_EQ(lagged.r.steps % lagged.every, 0);
  EXPECT_LT(lagged.r.last_displacement, p.threshold);
  EXPECT_EQ(lagged.r.records.back().max_displacement, lagged.r.last_displacement);
  EXPECT_GE(lagged.r.records[lagged.r.records.size() - 1 - lagged.every].max_displacement, p.threshold);
  if (e_->traits.deterministic) {
    EXPECT_EQ(lagged.r.steps, waited.r.steps);
    EXPECT_EQ(lagged.r.last_displacement, waited.r.last_displacement);
    EXPECT_TRUE(bitwise_equal(lagged.s, waited.s));
  } else {  // near the rest state the atomic order moves the last step by a few
    EXPECT_NEAR(lagged.r.steps, waited.r.steps, 0.05 * waited.r.steps);
    EXPECT_LT(max_position_diff(lagged.s, waited.s), 1e-4);
  }
}

TEST_P(StepBack, LaggedChecksCatchDivergenceAtTheSameStep) {
  const Model m = small_cloth(24, 24);
  Params p = settling_params();
  p.damping = 0.02f;
  p.dt = float(3 * stability_limit(m, p, Integrator::semi_implicit_euler));
  const Ended lagged = run_from(*e_, m, p, false), waited = run_from(*e_, m, p, true);
  ASSERT_TRUE(lagged.could_step_back) << GetParam() << " cannot step back: each check waits for its step";
  ASSERT_GT(waited.diverged_at, 0);
  // Growth at 3x the limit is a factor per step: rounding order moves it by a step at most.
  EXPECT_NEAR(lagged.diverged_at, waited.diverged_at, e_->traits.deterministic ? 0 : 1);
  EXPECT_EQ(lagged.s.t, lagged.diverged_at * double(p.dt)) << "the launch after the divergence was not taken back";
}

// Bit for bit, or within a few ulp of the 1 m coordinates (the
// scatter kernels' atomic order).
void expect_same(const State& a, const State& b, bool bitwise) {
  if (bitwise) {
    EXPECT_TRUE(bitwise_equal(a, b));
  } else {
    EXPECT_LT(max_position_diff(a, b), 1e-6);
    EXPECT_LT(max_diff(a.v, b.v), 1e-4);
  }
}

// The contract itself: the last launch (one step; cuda-temporal's k) back, to the state before
// it, once, then on as if the launch taken back had not been (its displacement word included);
// with semi-implicit Euler and with Verlet.
TEST_P(StepBack, TakesTheLastLaunchBackOnce) {
  for (Integrator integ : {Integrator::semi_implicit_euler, Integrator::verlet})
    if (e_->unsupported(integ).empty()) {
      SCOPED_TRACE(info(integ).name);
      takes_the_last_launch_back_once(integ);
    }
}

void StepBack::takes_the_last_launch_back_once(Integrator integ) {
  const Model m = small_cloth(24, 24);
  const Params p = moving_params(m, integ);
  auto pipe = e_->make({m, p, integ});
  ASSERT_TRUE(pipe->can_step_back()) << GetParam() << " cannot step back";
  auto twin = e_->make({m, p, integ});
  const int steps = pipe->steps_per_launch();
  auto launch = [steps](Pipeline& q) {
    for (int s = 0; s < steps; ++s) q.step();
  };
  pipe->set_state(perturbed_state(m, 3));
  twin->set_state(perturbed_state(m, 3));
  launch(*pipe);
  launch(*twin);
  const State one = twin->state();
  // The launch taken back jumps a node a metre, so that its largest displacement, had it been
  // kept, would exceed the next launch's.
  pipe->set_drag({5, {{0.f, m.rest_position[5] + Vec3f{0.f, 1.f, 0.f}}}, false});
  launch(*pipe);
  pipe->step_back();
  pipe->set_drag(p.drag);
  const State back = pipe->state();
  EXPECT_EQ(back.t, one.t);
  expect_same(back, one, e_->traits.deterministic);
  EXPECT_THROW(pipe->step_back(), std::logic_error);
  EXPECT_THROW(pipe->queue_displacement(), std::logic_error);  // that launch's read is gone
  launch(*pipe);
  launch(*twin);
  const double d = pipe->max_displacement(), d_twin = twin->max_displacement();
  if (e_->traits.deterministic)
    EXPECT_EQ(d, d_twin);
  else
    EXPECT_NEAR(d, d_twin, 1e-6);
  expect_same(pipe->state(), twin->state(), e_->traits.deterministic);
}

// Which pipelines take the lagged path: those whose kernels or passes write a state set other
// than the one they read, every GPU pipeline.
TEST(StepBackPipelines, PingPongPipelinesCanStepBack) {
  const std::set<std::string> can = {"cuda-fused",   "cuda-tiled", "cuda-naive", "cuda-scatter",  "cuda-temporal",
                                     "glsl-compute", "glsl-tf",    "hybrid",     "hybrid-compute"};
  const Model m = small_cloth(8, 8);
  const Params p = small_params();
  int seen = 0;
  for (const auto& e : pipelines().all()) {
    if (!e.unavailable().empty() || e.traits.force == Engine::cpu) continue;
    ++seen;
    EXPECT_EQ(e.make({m, p, Integrator::semi_implicit_euler})->can_step_back(), can.count(e.name) == 1) << e.name;
    if (e.unsupported(Integrator::verlet).empty()) {
      EXPECT_EQ(e.make({m, p, Integrator::verlet})->can_step_back(), can.count(e.name) == 1) << e.name << " (verlet)";
    }
  }
  if (seen == 0) DEFORMLAB_SKIP_IF_UNAVAILABLE("no GPU pipeline on this machine");
}

// The GPU pipelines, every one of which steps back (above); the CPU's checks wait for each step.
std::vector<std::string> gpu_pipeline_names() {
  std::vector<std::string> out;
  for (const auto& e : pipelines().all())
    if (on_gpu(e)) out.push_back(e.name);
  return out;
}

INSTANTIATE_TEST_SUITE_P(All, StepBack, testing::ValuesIn(gpu_pipeline_names()), pipeline_test_name);

}  // namespace
}  // namespace deformlab::test
