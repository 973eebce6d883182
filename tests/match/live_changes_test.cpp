// What the viewer changes while a pipeline runs, on every pipeline in the registry: the drag
// handle replaced between steps (Pipeline::set_drag) gives the `cpu` pipeline's trajectory
// under the same changes, and a state handed from one pipeline to another arrives bit for bit.
// Tolerances as in match_cpu_test.cpp: bitwise pipelines equal, the others within 8 x the
// `cpu` pipeline's own distance from the double reference on this trajectory (floor 1e-6 m,
// 1e-4 m/s).
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "core/cpu_backend.hpp"
#include "experiments/pipelines.hpp"
#include "tests/match/pipeline_names.hpp"
#include "tests/support/test_states.hpp"
#include "tests/support/gpu_required.hpp"

namespace deformlab::test {
namespace {

class LiveChanges : public testing::TestWithParam<std::string> {
 protected:
  const PipelineEntry& entry() const { return *pipelines().find(GetParam()); }
};

constexpr int kSide = 24, kPhaseSteps = 8;

// Three handles in turn: a spring pulling the centre towards a point held still, a hard handle
// moving another node along a path that starts at the pipeline's time, then none.
std::vector<DragHandle> handles(const Model& m, double t0) {
  const int centre = kSide * (kSide / 2) + kSide / 2, side = kSide * 5 + 3;
  DragHandle spring{centre, {{0.f, m.rest_position[centre] + Vec3f{0.f, 0.06f, 0.03f}}}, true, 40.f};
  const Vec3f a = m.rest_position[side];
  const float t = float(t0 + kPhaseSteps * 1e-3);  // small_params: dt = 1 ms
  DragHandle hard{side, {{t, a}, {t + 0.004f, a + Vec3f{0.02f, 0.03f, 0.f}}}, false};
  return {spring, hard, DragHandle{}};
}

// The state after each phase of handles(), from s0.
std::vector<State> drive(Pipeline& p, const Model& m, const State& s0) {
  std::vector<State> out;
  p.set_state(s0);
  for (const DragHandle& h : handles(m, s0.t)) {
    p.set_drag(h);
    for (int k = 0; k < kPhaseSteps; ++k) p.step();
    out.push_back(p.state());
  }
  return out;
}

TEST_P(LiveChanges, DragHandleReplacedBetweenStepsAsOnCpu) {
  const PipelineEntry& e = entry();
  DEFORMLAB_SKIP_IF_UNAVAILABLE(e.unavailable());
  Model m = small_cloth(kSide, kSide);
  m.damping = {0.02f, 0.02f, 0.01f};
  const Params p = small_params();
  const PipelineSetup setup{m, p, Integrator::semi_implicit_euler};
  const State s0 = perturbed_state(m, 5u);

  auto subject = e.make(setup);
  const std::vector<State> g = drive(*subject, m, s0);
  const std::vector<State> a = drive(*make_cpu_pipeline(setup, Precision::f32, false), m, s0);
  const std::vector<State> r = drive(*make_cpu_pipeline(setup, Precision::f64, false), m, s0);

  const std::vector<DragHandle> h = handles(m, s0.t);
  const int pulled = h[0].node, moved = h[1].node;
  EXPECT_GT(a[0].x[pulled].y - s0.x[pulled].y, 1e-4) << "the spring pulls the centre up";
  EXPECT_EQ(a[1].x[moved], h[1].target(a[1].t)) << "a hard handle's node sits on its path";
  EXPECT_NE(a[2].x[moved], h[1].target(a[2].t)) << "released, the node moves on its own";
  for (std::size_t phase = 0; phase < g.size(); ++phase) {
    SCOPED_TRACE("phase " + std::to_string(phase));
    EXPECT_EQ(g[phase].t, a[phase].t);
    if (phase == 1) {
      EXPECT_EQ(g[phase].x[moved], h[1].target(g[phase].t)) << "hard handles are exact on every pipeline";
    }
    if (e.traits.cpu_match == CpuMatch::bitwise) {
      EXPECT_TRUE(bitwise_equal(g[phase], a[phase])) << "|x - x_cpu| = " << max_position_diff(g[phase], a[phase]);
      continue;
    }
    EXPECT_TRUE(within_rounding(g[phase], a[phase], rounding_bound(a[phase], r[phase], {1e-6, 1e-4})));
  }
}

TEST_P(LiveChanges, StateHandedOverArrivesBitForBit) {
  const PipelineEntry& e = entry();
  DEFORMLAB_SKIP_IF_UNAVAILABLE(e.unavailable());
  const Model m = small_cloth(kSide, kSide);
  State s = perturbed_state(m, 9u);
  s.t = 0.125;
  for (const Integrator i : {Integrator::semi_implicit_euler, Integrator::verlet}) {
    if (!e.unsupported(i).empty()) continue;
    s.half_step = i == Integrator::verlet;
    auto p = e.make({m, small_params(), i});
    p->set_state(s);
    EXPECT_TRUE(bitwise_equal(p->state(), s)) << info(i).name;
  }
}

TEST_P(LiveChanges, RefusesAHandleOutsideTheModel) {
  const PipelineEntry& e = entry();
  DEFORMLAB_SKIP_IF_UNAVAILABLE(e.unavailable());
  const Model m = small_cloth(8, 8);
  auto p = e.make({m, small_params(), Integrator::semi_implicit_euler});
  EXPECT_THROW(p->set_drag({64, {{0.f, {}}}}), std::invalid_argument);
  EXPECT_THROW(p->set_drag({3, {}}), std::invalid_argument);
  EXPECT_NO_THROW(p->set_drag({3, {{0.f, {}}}}));
}

std::vector<std::string> names() {
  std::vector<std::string> out;
  for (const auto& e : pipelines().all())
    if (e.name != "cpu" && e.name != "reference") out.push_back(e.name);
  return out;
}

INSTANTIATE_TEST_SUITE_P(All, LiveChanges, testing::ValuesIn(names()), pipeline_test_name);

}  // namespace
}  // namespace deformlab::test
