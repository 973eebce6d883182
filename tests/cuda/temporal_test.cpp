// cuda-temporal against cuda-fused: k steps a launch on shared-memory tiles give fused's
// states. With exact math bit for bit (per node and step the same operations in the same
// order), with fast math within the rounding tolerance of tests/match (8x the CPU float run's
// distance from the double reference on the same trajectory, floored at a few ulp): the
// compiler contracts each kernel's expressions in its own way. Odd grid sizes, tiles much
// smaller than the grid (halos crossing several blocks) and runs of 2k + 3 steps (the last
// launch short) on cloths and lattices, with every constraint at work.
#include <gtest/gtest.h>

#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

#include "cuda_kernels/pipelines.hpp"
#include "cuda_test_support.hpp"
#include "tests/support/gpu_required.hpp"

namespace deformlab::test {
namespace {

using cuda::Variant;

const Integrator kOnePass[] = {Integrator::explicit_euler, Integrator::semi_implicit_euler, Integrator::verlet};

struct Scene {
  std::string name;
  ContactScene sc;
  cuda::TemporalTile tile;  // small: many blocks
  std::vector<int> ks;
};

std::vector<Scene> scenes() {
  std::vector<Scene> out;
  for (bool spring : {false, true}) {
    const std::string drag = spring ? " spring drag" : " hard drag";
    out.push_back({"cloth 37x53" + drag, contact_scene(small_cloth(37, 53), spring), {8, 6, 1}, {1, 2, 4, 8}});
    out.push_back({"cloth 61x29" + drag, contact_scene(small_cloth(61, 29), spring), {13, 7, 1}, {1, 3, 8}});
    out.push_back({"lattice 9x7x11" + drag, contact_scene(small_lattice(9, 7, 11), spring), {3, 3, 3}, {1, 2}});
  }
  // Free of constraints but for the pins: wind and spring damping only.
  ContactScene free = contact_scene(small_cloth(45, 31), false);
  free.p = small_params();
  free.p.wind = {0.002f, 0.f, -0.001f};
  out.push_back({"cloth 45x31 free", free, {16, 16, 1}, {1, 2, 4, 8}});
  return out;
}

cuda::Options temporal(int k, cuda::TemporalTile t, Math math) {
  cuda::Options o{Variant::temporal, {}, true, math};
  o.steps_per_launch = k;
  o.temporal_tile = t;
  return o;
}

TEST(CudaTemporal, ExactMatchesCudaFusedBitForBit) {
  DEFORMLAB_REQUIRE_CUDA();
  for (const Scene& s : scenes())
    for (Integrator integ : kOnePass)
      for (int k : s.ks)
        for (bool default_tile : {false, true}) {
          const std::string what = s.name + " " + std::string(info(integ).name) + " k=" + std::to_string(k) +
                                   (default_tile ? " default tile" : " small tile");
          const State s0 = perturbed_state(s.sc.m, 5u);
          const int steps = 2 * k + 3;
          auto fused = cuda::make_pipeline({s.sc.m, s.sc.p, integ}, options(Variant::fused));
          auto t = cuda::make_pipeline({s.sc.m, s.sc.p, integ},
                                       temporal(k, default_tile ? cuda::TemporalTile{} : s.tile, Math::exact));
          const State f = advance(*fused, s0, steps), g = advance(*t, s0, steps);
          ASSERT_GT(max_position_diff(f, s0), 1e-5) << what << ": the scene must move";
          EXPECT_TRUE(bitwise_equal(g, f)) << what << ": |x - x_fused| = " << max_position_diff(g, f);
          EXPECT_EQ(t->max_displacement(), fused->max_displacement()) << what;
        }
}

TEST(CudaTemporal, FastMatchesCudaFusedWithinRounding) {
  DEFORMLAB_REQUIRE_CUDA();
  for (const Scene& s : scenes())
    for (Integrator integ : kOnePass) {
      const State s0 = perturbed_state(s.sc.m, 5u);
      const int steps = 19;
      const Params p = for_integrator(s.sc.p, integ);
      auto cpu = make_cpu_pipeline({s.sc.m, p, integ}, Precision::f32, true);
      auto ref = make_cpu_pipeline({s.sc.m, p, integ}, Precision::f64, true);
      const State c = advance(*cpu, s0, steps), r = advance(*ref, s0, steps);
      const RoundingBound b = rounding_bound(c, r, ulp_floor(c, p.dt));
      cuda::Options fo = options(Variant::fused);
      fo.math = Math::fast;
      auto fused = cuda::make_pipeline({s.sc.m, p, integ}, fo);
      const State f = advance(*fused, s0, steps);
      for (int k : s.ks) {
        const std::string what = s.name + " " + std::string(info(integ).name) + " k=" + std::to_string(k);
        auto t = cuda::make_pipeline({s.sc.m, p, integ}, temporal(k, s.tile, Math::fast));
        const State g = advance(*t, s0, steps);
        const testing::AssertionResult near = within_rounding(g, f, b);
        EXPECT_TRUE(near) << what;
        EXPECT_LE(std::abs(t->max_displacement() - fused->max_displacement()), 2 * b.max.x) << what;
        std::printf("%s fast, against cuda-fused fast: %s\n", what.c_str(), near.message());
      }
    }
}

TEST(CudaTemporal, ConstraintsHoldAcrossLaunches) {
  DEFORMLAB_REQUIRE_CUDA();
  const ContactScene sc = contact_scene(small_cloth(37, 53), false);
  const State s0 = perturbed_state(sc.m, 21u);
  auto t = cuda::make_pipeline({sc.m, sc.p, Integrator::semi_implicit_euler}, temporal(8, {8, 6, 1}, Math::exact));
  const State g = advance(*t, s0, 21);
  for (int i : sc.pinned) EXPECT_TRUE(g.x[i] == s0.x[i]) << "pinned node " << i << " moved";
  for (int i = 0; i < sc.m.node_count(); ++i) {
    if (sc.m.pinned(i)) continue;
    EXPECT_GE(g.x[i].y, *sc.p.ground) << "node " << i << " under the ground";
    for (const Sphere& sp : sc.p.spheres)
      EXPECT_GE(norm(g.x[i] - sp.center), sp.radius * (1 - 1e-6f)) << "node " << i << " inside a sphere";
  }
  EXPECT_TRUE(g.x[sc.p.drag.node] == sc.p.drag.target(g.t)) << "hard drag node off its target";
}

// The stop rule's check sees the last step of a launch: a NaN put into the state is found.
TEST(CudaTemporal, FindsANonFiniteState) {
  DEFORMLAB_REQUIRE_CUDA();
  const Model m = small_cloth(37, 53);
  State s0 = perturbed_state(m, 3u);
  s0.v[700].y = std::numeric_limits<float>::quiet_NaN();
  for (int k : {1, 4}) {
    auto t = cuda::make_pipeline({m, small_params(), Integrator::semi_implicit_euler}, temporal(k, {8, 6, 1}, Math::exact));
    advance(*t, s0, 2 * k);
    EXPECT_TRUE(std::isnan(t->max_displacement())) << "k=" << k;
  }
}

// A launch taken back (the run loop's lagged checks) leaves the state before it, Verlet's
// half_step included, and the launches after it go on as if it had not been; a launch still
// held, or one taken back, cannot be.
TEST(CudaTemporal, TakesTheLastLaunchBack) {
  DEFORMLAB_REQUIRE_CUDA();
  const ContactScene sc = contact_scene(small_cloth(37, 53), false);
  for (Integrator integ : kOnePass) {
    const std::string what(info(integ).name);
    auto t = cuda::make_pipeline({sc.m, sc.p, integ}, temporal(3, {8, 6, 1}, Math::exact));
    auto twin = cuda::make_pipeline({sc.m, sc.p, integ}, temporal(3, {8, 6, 1}, Math::exact));
    const State s0 = perturbed_state(sc.m, 9u);
    ASSERT_TRUE(t->can_step_back()) << what;
    const State one = advance(*twin, s0, 3);
    advance(*t, s0, 6);
    t->step_back();
    EXPECT_TRUE(bitwise_equal(t->state(), one)) << what;
    EXPECT_THROW(t->step_back(), std::logic_error) << what;
    t->step();
    EXPECT_THROW(t->step_back(), std::logic_error) << what << ": two steps still held";
    t->step();
    t->step();
    for (int k = 0; k < 3; ++k) twin->step();
    EXPECT_TRUE(bitwise_equal(t->state(), twin->state())) << what;
    EXPECT_EQ(t->max_displacement(), twin->max_displacement()) << what;
  }
}

// Steps held for a launch are timed as their share of it: every step gets a time.
TEST(CudaTemporal, EveryStepIsTimed) {
  DEFORMLAB_REQUIRE_CUDA();
  const Model m = small_cloth(64, 64);
  auto t = cuda::make_pipeline({m, small_params(), Integrator::verlet}, temporal(4, {}, Math::exact));
  auto timer = t->step_timer();
  const std::vector<double> ms = timed_steps(*t, *timer, 10);  // two launches of 4, one of 2
  ASSERT_EQ(ms.size(), 10u);
  for (double x : ms) EXPECT_GT(x, 0.0);
  EXPECT_EQ(ms[0], ms[3]);  // one launch's share
  EXPECT_EQ(ms[8], ms[9]);
}

// A profiled launch gives each of its steps an equal share: one force+update span a step.
TEST(CudaTemporal, EachStepGetsItsShareOfALaunchsSpan) {
  DEFORMLAB_REQUIRE_CUDA();
  const Model m = small_cloth(64, 64);
  auto t = cuda::make_pipeline({m, small_params(), Integrator::semi_implicit_euler}, temporal(4, {}, Math::exact));
  Profiler prof;
  t->set_state(rest_state(m));
  t->set_profiler(&prof);
  for (int k = 1; k <= 10; ++k) {  // launches after steps 4 and 8; steps 9 and 10 go when read
    prof.set_step(k);
    t->step();
  }
  t->max_displacement();
  t->set_profiler(nullptr);
  std::vector<int> steps;
  for (const Span& s : prof.spans()) {
    EXPECT_EQ(s.name, "force+update");
    EXPECT_GT(s.ms, 0.0);
    steps.push_back(s.step);
  }
  EXPECT_EQ(steps, (std::vector<int>{1, 2, 3, 4, 5, 6, 7, 8, 9, 10}));
  EXPECT_EQ(prof.spans()[0].ms, prof.spans()[3].ms);
}

// Sampling one window of 8 steps in 2 times the launches that end in steps 1-8 and 17-24.
TEST(CudaTemporal, SpansOnlyInTheSampledLaunches) {
  DEFORMLAB_REQUIRE_CUDA();
  const Model m = small_cloth(64, 64);
  auto t = cuda::make_pipeline({m, small_params(), Integrator::semi_implicit_euler}, temporal(4, {}, Math::exact));
  EXPECT_EQ(sampled_span_steps(*t, rest_state(m), 24, 2),
            (std::vector<int>{1, 2, 3, 4, 5, 6, 7, 8, 17, 18, 19, 20, 21, 22, 23, 24}));
}

TEST(CudaTemporal, RefusesWhatItDoesNotRun) {
  DEFORMLAB_REQUIRE_CUDA();
  const Params p = small_params();
  auto refused = [&](const Model& m, Integrator i, const cuda::Options& o, const std::string& says) {
    try {
      cuda::make_pipeline({m, p, i}, o);
      ADD_FAILURE() << "expected a refusal naming " << says;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
    }
  };
  refused(small_lattice(9, 7, 11), Integrator::verlet, temporal(4, {}, Math::exact), "shared memory");
  refused(small_cloth(37, 53), Integrator::verlet, temporal(2, {400, 400, 1}, Math::exact), "shared memory");
  refused(explicit_springs(small_cloth(9, 9)), Integrator::verlet, temporal(2, {}, Math::exact), "grid models");
  refused(small_cloth(9, 9), Integrator::rk4, temporal(2, {}, Math::exact), "cuda-temporal runs");
}

// ---- no device needed ----

TEST(CudaTemporal, OptionsAreChecked) {
  EXPECT_EQ(cuda::steps_per_launch_option({{"steps_per_launch", "8"}}), 8);
  EXPECT_EQ(cuda::steps_per_launch_option({}), 0);
  for (const char* bad : {"0", "9", "2x", "", "-1", "02", "+2", " 2"})
    EXPECT_THROW(cuda::steps_per_launch_option({{"steps_per_launch", bad}}), std::invalid_argument) << bad;
  const cuda::TemporalTile t = cuda::parse_temporal_tile("40x24");
  EXPECT_EQ(t.x, 40);
  EXPECT_EQ(t.y, 24);
  EXPECT_EQ(cuda::parse_temporal_tile("7x5x3").z, 3);
  EXPECT_EQ(cuda::parse_temporal_tile("4096x4096x4096").z, 4096);
  for (const char* bad : {"40", "40x", "x4", "4x4x4x4", "0x4", "4x-1", "4 x4", "040x24", "4x+4", "4x4x", "4x4x0",
                          "4x4x04", "4097x4"})
    EXPECT_THROW(cuda::parse_temporal_tile(bad), std::invalid_argument) << bad;
  EXPECT_EQ(cuda::steps_per_launch({}), 2);
  EXPECT_EQ(cuda::steps_per_launch(cuda::Options{Variant::temporal, {}, true, Math::exact, 5}), 5);
  EXPECT_FALSE(cuda::unsupported(Integrator::rk4, Variant::temporal).empty());
  EXPECT_EQ(cuda::unsupported(Integrator::verlet, Variant::temporal), "");
  // What a pipeline tells the run about its launches.
  DEFORMLAB_SKIP_IF_UNAVAILABLE(cuda::unavailable());
  const Model m = small_cloth(4, 4);
  const Params p = small_params();
  EXPECT_EQ(cuda::make_pipeline({m, p, Integrator::verlet}, temporal(3, {}, Math::exact))->steps_per_launch(), 3);
  EXPECT_EQ(cuda::make_pipeline({m, p, Integrator::verlet}, options(Variant::fused))->steps_per_launch(), 1);
}

}  // namespace
}  // namespace deformlab::test
