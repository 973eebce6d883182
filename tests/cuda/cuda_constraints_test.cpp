// Constraints on the CUDA pipelines: pins, the ground, spheres and both drag modes hold,
// and the steps match the CPU's: bit for bit where the gather sums in the CPU's order; for
// cuda-scatter (atomic sums in any order) within 4 x the CPU float pipeline's own distance
// from the double reference, at least 4 ulps of the largest coordinate (rounding_bound).
#include <gtest/gtest.h>

#include "cuda_test_support.hpp"

namespace deformlab::test {
namespace {

using cuda::Variant;

// At 1 ms a step the drag path ends after step 10, and the later steps replay a CUDA graph;
// explicit Euler's 0.1 ms steps (for_integrator) stay within the path.
constexpr int kSteps = 30;
constexpr Variant kVariants[] = {Variant::naive, Variant::tiled, Variant::scatter, Variant::fused};

void expect_constraints_hold(const ContactScene& sc, const State& s0, const State& g, const std::string& what) {
  for (int i : sc.pinned) {
    EXPECT_TRUE(g.x[i] == s0.x[i]) << what << ": pinned node " << i << " moved";
    EXPECT_TRUE(g.v[i] == Vec3f{}) << what << ": pinned node " << i << " has a velocity";
  }
  for (int i = 0; i < sc.m.node_count(); ++i) {
    if (sc.m.pinned(i)) continue;
    EXPECT_GE(g.x[i].y, *sc.p.ground) << what << ": node " << i << " under the ground";
    for (const Sphere& sp : sc.p.spheres)
      EXPECT_GE(norm(g.x[i] - sp.center), sp.radius * (1 - 1e-6f)) << what << ": node " << i << " inside a sphere";
  }
  if (!sc.p.drag.as_spring) {
    EXPECT_TRUE(g.x[sc.p.drag.node] == sc.p.drag.target(g.t)) << what << ": hard drag node off its target";
  }
}

TEST(CudaConstraints, PinsGroundSpheresAndDragHold) {
  DEFORMLAB_REQUIRE_CUDA();
  for (bool spring_drag : {false, true}) {
    const ContactScene sc = contact_scene(small_cloth(37, 53), spring_drag);
    const State s0 = perturbed_state(sc.m, 21u);
    for (Integrator integ : {Integrator::explicit_euler, Integrator::semi_implicit_euler, Integrator::midpoint,
                             Integrator::rk4, Integrator::verlet}) {
      const Params p = for_integrator(sc.p, integ);
      auto cpu = make_cpu_pipeline({sc.m, p, integ}, Precision::f32, true);
      const State c = advance(*cpu, s0, kSteps);
      auto ref = make_cpu_pipeline({sc.m, p, integ}, Precision::f64, true);
      const State r = advance(*ref, s0, kSteps);
      const RoundingBound b = rounding_bound(c, r, ulp_floor(c, p.dt), 4);
      for (Variant v : kVariants) {
        const std::string what = std::string(name(v)) + " " + std::string(info(integ).name) +
                                 (spring_drag ? " spring drag" : " hard drag");
        auto gpu = cuda::make_pipeline({sc.m, p, integ}, options(v));
        const State g = advance(*gpu, s0, kSteps);
        expect_constraints_hold(sc, s0, g, what);
        if (v != Variant::scatter) {
          EXPECT_TRUE(bitwise_equal(g, c)) << what << ": x diff " << max_position_diff(g, c);
          EXPECT_EQ(gpu->max_displacement(), cpu->max_displacement()) << what;
        } else {
          EXPECT_TRUE(within_rounding(g, c, b)) << what;
        }
      }
    }
  }
}

}  // namespace
}  // namespace deformlab::test
