// What only the hybrid pipelines have: the four interop modes against each other (they
// change how buffers are shared and synchronised, not what is computed, so their states must
// be bitwise equal) and the spans of each stage. Against the CPU: tests/match.
#include <gtest/gtest.h>

#include <map>
#include <tuple>

#include "core/cpu_backend.hpp"
#include "cuda_kernels/cuda_pipeline.hpp"
#include "interop/hybrid.hpp"
#include "tests/support/test_states.hpp"
#include "tests/support/gpu_required.hpp"

namespace deformlab::test {
namespace {

using namespace deformlab::interop;

#define DEFORMLAB_REQUIRE_INTEROP(mode) DEFORMLAB_SKIP_IF_UNAVAILABLE(::deformlab::interop::unavailable(mode))

struct Scenario {
  Model model;
  Params params;
  State s0;
};

Scenario scenario(Integrator i) {
  Scenario s{small_cloth(32, 32), {}, {}};
  s.model.damping = {0.02f, 0.02f, 0.01f};
  s.params = moving_params(s.model, i);
  s.s0 = perturbed_state(s.model, 7);
  return s;
}

constexpr int kSteps = 50;

// The four modes share and synchronise the same buffers differently; what is computed is
// the same, so the states are bitwise equal.
class ModesAgree : public testing::TestWithParam<std::tuple<Update, Integrator>> {};

TEST_P(ModesAgree, BitwiseEqualStates) {
  const auto [update, integ] = GetParam();
  DEFORMLAB_REQUIRE_INTEROP(Mode::map);
  const Scenario sc = scenario(integ);
  const PipelineSetup setup{sc.model, sc.params, integ};
  std::optional<State> first;
  for (Mode m : kModes) {
    if (const std::string why = unavailable(m); !why.empty()) {
      ADD_FAILURE() << to_string(m) << " unavailable where map is: " << why;
      continue;
    }
    auto p = make_hybrid_pipeline(setup, {update, m, cuda::Variant::naive});
    const State s = advance(*p, sc.s0, kSteps);
    if (!first) {
      first = s;
      continue;
    }
    EXPECT_TRUE(bitwise_equal(s, *first))
        << to_string(m) << " differs from map: |dx| = " << max_position_diff(s, *first) << " m";
  }
}

INSTANTIATE_TEST_SUITE_P(Hybrid, ModesAgree,
                         testing::Combine(testing::Values(Update::transform_feedback, Update::compute),
                                          testing::Values(Integrator::semi_implicit_euler, Integrator::verlet,
                                                          Integrator::rk4)),
                         [](const testing::TestParamInfo<std::tuple<Update, Integrator>>& p) {
                           std::string s = std::string(std::get<0>(p.param) == Update::compute ? "compute_" : "tf_") +
                                           std::string(deformlab::info(std::get<1>(p.param)).name);
                           for (char& ch : s)
                             if (ch == '-') ch = '_';
                           return s;
                         });

// Without an interop option a hybrid runs default_mode() (external-gpusync where this machine
// has it) and says so; with one it chooses nothing.
TEST(HybridDefaults, InteropModeChosenAndRecorded) {
  DEFORMLAB_REQUIRE_INTEROP(Mode::map);
  const Scenario sc = scenario(Integrator::semi_implicit_euler);
  const PipelineSetup setup{sc.model, sc.params, Integrator::semi_implicit_euler};
  const Mode expected = unavailable(Mode::external_gpusync).empty() ? Mode::external_gpusync : Mode::map;
  EXPECT_EQ(default_mode(), expected);
  for (Update u : {Update::transform_feedback, Update::compute}) {
    HybridOptions o;
    o.update = u;
    const auto chosen = make_hybrid_pipeline(setup, o)->chosen_options();
    EXPECT_EQ(chosen, (std::map<std::string, std::string>{{"interop", to_string(expected)}}));
    o.mode = Mode::staged;
    EXPECT_TRUE(make_hybrid_pipeline(setup, o)->chosen_options().empty());
  }
}

// A profiled run records the force, hand-off and update spans of every step it samples (all
// of them, or steps 1-8 and 17-20 of 20 with one window of 8 in 2), each with its clock.
TEST(HybridProfile, SpansPerStage) {
  DEFORMLAB_REQUIRE_INTEROP(Mode::map);
  const Scenario sc = scenario(Integrator::midpoint);
  for (const auto& [every, steps, sampled] : {std::tuple{1, 5, 5}, std::tuple{2, 20, 12}}) {
    SCOPED_TRACE(every);
    auto p = make_hybrid_pipeline({sc.model, sc.params, Integrator::midpoint}, {});
    Profiler prof;
    prof.sample_every(every);
    p->set_state(sc.s0);
    p->set_profiler(&prof);
    for (int k = 1; k <= steps; ++k) {
      prof.set_step(k);
      p->step();
    }
    p->set_profiler(nullptr);
    int force = 0, hand_off = 0, update = 0;
    for (const Span& s : prof.spans()) {
      EXPECT_GT(s.ms, 0.0) << s.name;
      EXPECT_TRUE(s.step <= 8 || s.step > 16) << s.name << " in step " << s.step;
      force += s.name == span::force;
      hand_off += s.name == span::hand_off;
      update += s.name == span::update;
      // Interop runs on a GPU's GL, whose timer queries time the update.
      const char* clock = s.name == span::force    ? "CUDA events"
                          : s.name == span::update ? "GL timer queries"
                                                   : "host clock";
      EXPECT_EQ(s.clock, clock) << s.name;
    }
    EXPECT_EQ(force, sampled * 2);  // midpoint: two force passes per step
    EXPECT_EQ(hand_off, sampled * 2 * 2);
    EXPECT_EQ(update, sampled * 2);
  }
}

}  // namespace
}  // namespace deformlab::test
