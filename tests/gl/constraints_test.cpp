// Constraints, the GPU stop rule and state hand-over on both GL pipelines.
#include <cmath>
#include <limits>

#include "core/cpu_backend.hpp"
#include "core/run.hpp"
#include "gl_test_support.hpp"
#include "tests/support/test_states.hpp"

namespace deformlab::test {
namespace {

struct Case {
  std::string pipeline;
  Integrator integrator;
};

std::string case_name(const testing::TestParamInfo<Case>& p) {
  std::string s = p.param.pipeline + "_" + std::string(info(p.param.integrator).name);
  for (char& c : s)
    if (c == '-') c = '_';
  return s;
}

std::vector<Case> cases() {
  std::vector<Case> out;
  for (const char* pipe : {"glsl-tf", "glsl-compute"})
    for (const auto& i : integrators())
      if (i.id != Integrator::backward_euler) out.push_back({pipe, i.id});
  return out;
}

class GlConstraints : public testing::TestWithParam<Case> {};

// A cloth falling onto a sphere and the ground, two corners pinned, one node dragged.
TEST_P(GlConstraints, PinsDragGroundAndSphereHold) {
  DEFORMLAB_REQUIRE_GL();
  Model m = small_cloth(20, 20);
  m.damping = {0.05f, 0.05f, 0.02f};
  Params p = small_params();
  p.damping = 0.1f;
  if (GetParam().integrator == Integrator::explicit_euler) p.dt = 1e-4f;
  p.ground = 0.93f;
  p.spheres = {{{0.15f, 0.9f, 0.1f}, 0.1f}};
  const int drag = 10 * 20 + 4;
  p.drag.node = drag;
  p.drag.path = {{0.f, m.rest_position[drag]}, {0.2f, m.rest_position[drag] + Vec3f{0.f, 0.1f, 0.05f}}};
  auto pipe = make_gl(GetParam().pipeline, {m, p, GetParam().integrator});
  pipe->set_state(rest_state(m));
  const int steps = GetParam().integrator == Integrator::explicit_euler ? 1500 : 150;
  for (int k = 0; k < steps; ++k) pipe->step();
  const State s = pipe->state();
  ASSERT_TRUE(std::isfinite(pipe->max_displacement()));
  bool touched_ground = false, touched_sphere = false;
  for (int i = 0; i < m.node_count(); ++i) {
    if (m.pinned(i)) {
      EXPECT_EQ(s.x[i], m.rest_position[i]) << "pinned node " << i << " moved";
      EXPECT_EQ(s.v[i], Vec3f{}) << "pinned node " << i;
      continue;
    }
    if (i == drag) {
      const Vec3f target = p.drag.target(s.t);
      EXPECT_NEAR(s.x[i].x, target.x, 1e-6f);
      EXPECT_NEAR(s.x[i].y, target.y, 1e-6f);
      EXPECT_NEAR(s.x[i].z, target.z, 1e-6f);
      continue;
    }
    EXPECT_GE(s.x[i].y, *p.ground - 1e-6f) << "node " << i << " below the ground";
    touched_ground = touched_ground || s.x[i].y < *p.ground + 1e-4f;
    const float from_centre = norm(s.x[i] - p.spheres[0].center);
    EXPECT_GE(from_centre, p.spheres[0].radius * (1.f - 1e-5f)) << "node " << i << " inside the sphere";
    touched_sphere = touched_sphere || from_centre < p.spheres[0].radius * (1.f + 1e-4f);
  }
  EXPECT_TRUE(touched_ground) << "the scene should bring the cloth onto the ground";
  EXPECT_TRUE(touched_sphere) << "the scene should bring the cloth onto the sphere";
}

// The GPU reduction (glsl-compute: inside the step's result pass) equals the largest
// displacement seen on read-back states, step after step, and a non-finite state reads as NaN.
TEST_P(GlConstraints, DisplacementReductionAndNonFinite) {
  DEFORMLAB_REQUIRE_GL();
  const Model m = small_cloth(17, 13);
  Params p = small_params();
  if (GetParam().integrator == Integrator::explicit_euler) p.dt = 1e-4f;
  auto pipe = make_gl(GetParam().pipeline, {m, p, GetParam().integrator});
  const State s0 = perturbed_state(m, 3);
  pipe->set_state(s0);
  EXPECT_EQ(pipe->max_displacement(), 0.0);
  State before = s0;
  for (int k = 0; k < 3; ++k) {
    pipe->step();
    const State after = pipe->state();
    double expect = 0.0;
    for (int i = 0; i < m.node_count(); ++i) expect = std::max(expect, double(norm(after.x[i] - before.x[i])));
    EXPECT_NEAR(pipe->max_displacement(), expect, 1e-6 * expect + 1e-9) << "step " << k + 1;
    before = after;
  }

  State bad = s0;
  bad.v[m.node_count() - 1].y = std::numeric_limits<float>::infinity();
  pipe->set_state(bad);
  pipe->step();
  EXPECT_TRUE(std::isnan(pipe->max_displacement()));
}

// The run loop's stop rule on the GPU: a damped cloth settles, on the same check as the CPU.
TEST_P(GlConstraints, ConvergenceStopReached) {
  DEFORMLAB_REQUIRE_GL();
  Model m = small_cloth(12, 12);
  m.damping = {0.2f, 0.2f, 0.05f};
  Params p = small_params();
  p.dt = GetParam().integrator == Integrator::explicit_euler ? 2e-4f : 2e-3f;
  p.damping = 0.5f;
  p.threshold = 2e-5f;
  p.check_every = 10;
  p.max_steps = 20000;
  auto gpu = make_gl(GetParam().pipeline, {m, p, GetParam().integrator});
  auto cpu = make_cpu_pipeline({m, p, GetParam().integrator}, Precision::f32, false);
  RunOptions o;
  o.until_converged = true;
  gpu->set_state(rest_state(m));
  cpu->set_state(rest_state(m));
  const RunResult g = run(*gpu, m, p, o), c = run(*cpu, m, p, o);
  ASSERT_TRUE(g.converged) << "not converged after " << g.steps << " steps";
  EXPECT_LT(g.last_displacement, p.threshold);
  EXPECT_NEAR(g.steps, c.steps, p.check_every) << "the CPU float pipeline stopped at step " << c.steps;
}

INSTANTIATE_TEST_SUITE_P(Gl, GlConstraints, testing::ValuesIn(cases()), case_name);

// A state read back (Verlet's half-step flag included) and set again continues as if the run
// had not been interrupted.
TEST(GlState, RoundTripContinuesExactly) {
  DEFORMLAB_REQUIRE_GL();
  const Model m = small_cloth(16, 16);
  const Params p = small_params();
  for (const char* name : {"glsl-tf", "glsl-compute"}) {
    auto a = make_gl(name, {m, p, Integrator::verlet});
    auto b = make_gl(name, {m, p, Integrator::verlet});
    const State s0 = perturbed_state(m, 11);
    const State mid = advance(*a, s0, 5);
    ASSERT_TRUE(mid.half_step) << name << ": Verlet's state says its v is the half step's";
    for (int k = 0; k < 5; ++k) a->step();
    const State straight = a->state(), resumed = advance(*b, mid, 5);
    EXPECT_EQ(max_position_diff(straight, resumed), 0.0) << name;
    EXPECT_EQ(max_velocity_diff(straight, resumed), 0.0) << name;
  }
}

TEST(GlState, BackwardEulerIsRefused) {
  DEFORMLAB_REQUIRE_GL();
  const Model m = small_cloth(4, 4);
  const Params p = small_params();
  for (const char* name : {"glsl-tf", "glsl-compute"})
    EXPECT_THROW(make_gl(name, {m, p, Integrator::backward_euler}), std::invalid_argument) << name;
}

}  // namespace
}  // namespace deformlab::test
