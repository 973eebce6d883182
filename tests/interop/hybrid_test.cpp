// hybrid and hybrid-compute, every integrator they run, every interop mode: 50 steps from a
// perturbed, moving state on a 32x32 cloth and a 6x5x4 lattice against the CPU float
// pipeline; and the four modes against each other.
//
// Tolerance: the CUDA force pass does the CPU's float operations in the CPU's order; the GL
// update pass may contract a*b+c into one rounding (FMA) and round differently, as in the
// GL tests. Those are rounding differences of the size float rounding itself makes, so the
// hybrid-vs-CPU difference is held to 8 x the CPU float pipeline's own distance from the
// double reference on this very trajectory, plus a floor of a few ulp of the coordinates
// (1 m scale: 1e-6 m, 1e-4 m/s); a real fault (a missing spring, a stale buffer after a
// hand-off) shows as 1e-3 m and more. Explicit Euler takes dt = 0.1 ms (at 1 ms it grows
// ~1.4x per step on these springs). The modes only change how buffers are shared and
// synchronised, not what is computed: their states must be bitwise equal.
#include <gtest/gtest.h>

#include <cstring>

#include "core/cpu_backend.hpp"
#include "cuda_kernels/cuda_pipeline.hpp"
#include "interop/hybrid.hpp"
#include "tests/support/test_states.hpp"

namespace deformlab::test {
namespace {

using namespace deformlab::interop;

#define DEFORMLAB_REQUIRE_INTEROP(mode)                                          \
  do {                                                                           \
    if (const std::string why = ::deformlab::interop::unavailable(mode); !why.empty()) \
      GTEST_SKIP() << why;                                                       \
  } while (0)

struct Scenario {
  Model model;
  Params params;
  State s0;
};

Scenario scenario(bool lattice, Integrator i) {
  Scenario s{lattice ? small_lattice(6, 5, 4) : small_cloth(32, 32), small_params(), {}};
  s.model.damping = {0.02f, 0.02f, 0.01f};
  if (i == Integrator::explicit_euler) s.params.dt = 1e-4f;
  s.params.wind = {0.002f, 0.f, -0.001f};
  Params& p = s.params;
  p.drag.node = s.model.node_count() / 2 + 3;  // a free node pulled by a drag spring
  p.drag.as_spring = true;
  p.drag.stiffness = 50.f;
  p.drag.path = {{0.f, s.model.rest_position[p.drag.node]},
                 {0.1f, s.model.rest_position[p.drag.node] + Vec3f{0.05f, 0.02f, 0.f}}};
  s.s0 = perturbed_state(s.model, 7);
  return s;
}

constexpr int kSteps = 50;

bool bitwise_equal(const std::vector<Vec3f>& a, const std::vector<Vec3f>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3f)) == 0);
}

struct Case {
  Update update;
  Integrator integrator;
  Mode mode;
  cuda::Variant force;
  bool lattice;
};

std::string case_name(const testing::TestParamInfo<Case>& p) {
  const Case& c = p.param;
  std::string s = std::string(c.update == Update::compute ? "compute" : "tf") + "_" +
                  std::string(info(c.integrator).name) + "_" + to_string(c.mode) + "_" + cuda::to_string(c.force) +
                  (c.lattice ? "_lattice" : "_cloth");
  for (char& ch : s)
    if (ch == '-') ch = '_';
  return s;
}

class HybridMatchesCpu : public testing::TestWithParam<Case> {};

TEST_P(HybridMatchesCpu, FiftyStepsFromAMovingState) {
  const Case& c = GetParam();
  DEFORMLAB_REQUIRE_INTEROP(c.mode);
  const Scenario sc = scenario(c.lattice, c.integrator);
  const PipelineSetup setup{sc.model, sc.params, c.integrator};
  auto hybrid = make_hybrid_pipeline(setup, {c.update, c.mode, c.force});
  auto f32 = make_cpu_pipeline(setup, Precision::f32, false);
  auto f64 = make_cpu_pipeline(setup, Precision::f64, false);
  const State h = advance(*hybrid, sc.s0, kSteps), a = advance(*f32, sc.s0, kSteps), r = advance(*f64, sc.s0, kSteps);

  const double rounding_x = max_position_diff(a, r), rounding_v = max_velocity_diff(a, r);
  const double dx = max_position_diff(h, a), dv = max_velocity_diff(h, a);
  const double tol_x = std::max(8.0 * rounding_x, 1e-6), tol_v = std::max(8.0 * rounding_v, 1e-4);
  EXPECT_LE(dx, tol_x) << "float rounding on this trajectory: " << rounding_x << " m";
  EXPECT_LE(dv, tol_v) << "float rounding on this trajectory: " << rounding_v << " m/s";
  EXPECT_NEAR(h.t, a.t, 1e-9);
  EXPECT_EQ(h.x_prev.empty(), a.x_prev.empty());
  if (!h.x_prev.empty()) {
    State hp = h, ap = a;
    hp.x = h.x_prev;
    ap.x = a.x_prev;
    EXPECT_LE(max_position_diff(hp, ap), tol_x);
  }
  const double disp = hybrid->max_displacement();
  EXPECT_TRUE(std::isfinite(disp));
  EXPECT_GT(disp, 0.0);
  std::printf("%s: |x - x_cpu| = %.3g m (tolerance %.3g), |v - v_cpu| = %.3g m/s (tolerance %.3g)\n",
              case_name({c, 0}).c_str(), dx, tol_x, dv, tol_v);
}

std::vector<Case> cases() {
  std::vector<Case> out;
  for (Update u : {Update::transform_feedback, Update::compute})
    for (const auto& i : integrators())
      if (i.id != Integrator::backward_euler)
        for (Mode m : kModes)
          for (bool lattice : {false, true}) out.push_back({u, i.id, m, cuda::Variant::naive, lattice});
  // The other force passes feeding both updates (the swap experiment's cells).
  for (Update u : {Update::transform_feedback, Update::compute})
    for (cuda::Variant f : {cuda::Variant::tiled, cuda::Variant::scatter})
      for (Integrator i : {Integrator::semi_implicit_euler, Integrator::rk4})
        out.push_back({u, i, Mode::map, f, false});
  return out;
}

INSTANTIATE_TEST_SUITE_P(Hybrid, HybridMatchesCpu, testing::ValuesIn(cases()), case_name);

// The four modes share and synchronise the same buffers differently; what is computed is
// the same, so the states are bitwise equal.
class ModesAgree : public testing::TestWithParam<std::tuple<Update, Integrator>> {};

TEST_P(ModesAgree, BitwiseEqualStates) {
  const auto [update, integ] = GetParam();
  DEFORMLAB_REQUIRE_INTEROP(Mode::map);
  const Scenario sc = scenario(false, integ);
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
    EXPECT_TRUE(bitwise_equal(s.x, first->x) && bitwise_equal(s.v, first->v) && bitwise_equal(s.x_prev, first->x_prev))
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

// A profiled run records the force, hand-off and update spans of every step, each with its clock.
TEST(HybridProfile, SpansPerStage) {
  DEFORMLAB_REQUIRE_INTEROP(Mode::map);
  const Scenario sc = scenario(false, Integrator::midpoint);
  auto p = make_hybrid_pipeline({sc.model, sc.params, Integrator::midpoint}, {});
  Profiler prof;
  p->set_state(sc.s0);
  p->set_profiler(&prof);
  for (int k = 1; k <= 5; ++k) {
    prof.set_step(k);
    p->step();
  }
  p->set_profiler(nullptr);
  int force = 0, hand_off = 0, update = 0;
  for (const Span& s : prof.spans()) {
    EXPECT_GE(s.ms, 0.0) << s.name;
    force += s.name == span::force;
    hand_off += s.name == span::hand_off;
    update += s.name == span::update;
    if (s.name == span::force) {
      EXPECT_EQ(s.clock, "CUDA events");
    }
  }
  EXPECT_EQ(force, 5 * 2);  // midpoint: two force passes per step
  EXPECT_EQ(hand_off, 5 * 2 * 2);
  EXPECT_EQ(update, 5 * 2);
}

}  // namespace
}  // namespace deformlab::test
