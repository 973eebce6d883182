// Constraints hold on every step for every integrator: pins, ground, spheres, the drag
// handle; and `omp` is bitwise equal to `cpu`.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>

#include "core/cpu_backend.hpp"
#include "core/energy.hpp"
#include "core/run.hpp"
#include "tests/support/test_states.hpp"

namespace deformlab {
namespace {

// A pinned cloth, its springs damped enough for explicit Euler, falling onto two spheres
// above the ground plane (a sphere crossing the plane could push nodes back under it), or,
// without the spheres, onto a ground plane above the lowest point its sag would reach.
struct Contact {
  explicit Contact(bool spheres, int n = 16) : model(test::small_cloth(n, n)) {
    model.damping = {0.5f, 0.5f, 0.5f};
    params.dt = 5e-4f;
    params.ground = spheres ? 0.6f : 0.75f;
    if (spheres) params.spheres = {{{0.f, 0.82f, 0.1f}, 0.2f}, {{0.3f, 0.75f, -0.2f}, 0.1f}};
  }
  Model model;
  Params params = test::small_params();
};

TEST(Constraints, NeverViolatedByAnyIntegrator) {
  for (const bool spheres : {true, false}) {
    const Contact c(spheres);
    for (const auto& i : integrators()) {
      auto pipe = make_cpu_pipeline({c.model, c.params, i.id}, Precision::f32, true);
      const State s0 = test::perturbed_state(c.model, 11, 0.005f, 0.5f);
      pipe->set_state(s0);
      int touching = 0;  // node-steps on the first sphere, or on the ground
      for (int k = 0; k < 600; ++k) {
        pipe->step();
        const State s = pipe->state();
        ASSERT_TRUE(std::isfinite(pipe->max_displacement())) << i.name << " diverged at step " << k;
        for (int v = 0; v < c.model.node_count(); ++v) {
          if (c.model.pinned(v)) {
            ASSERT_EQ(s.x[v], s0.x[v]) << i.name << " pinned node " << v << " moved at step " << k;
            continue;
          }
          ASSERT_GE(s.x[v].y, *c.params.ground) << i.name << " node " << v << " below ground at step " << k;
          for (const auto& sph : c.params.spheres)
            ASSERT_GE(norm(s.x[v] - sph.center), sph.radius * (1 - 1e-6f)) << i.name << " node " << v << " inside a sphere";
          touching += spheres ? norm(s.x[v] - c.params.spheres[0].center) < c.params.spheres[0].radius * 1.001f
                              : s.x[v].y < *c.params.ground + 1e-6f;
        }
      }
      EXPECT_GT(touching, 0) << i.name << ": the cloth never reached the " << (spheres ? "sphere" : "ground")
                             << ", the test would be vacuous";
    }
  }
}

// A contact's projection moves a node without giving it speed: a free cloth that starts 1 cm
// under the ground is lifted onto it and stays there at rest (gravity's pull each step is taken
// back by the ground, which leaves no speed into it). Damped and at Contact's dt, so that
// explicit Euler's rounding noise does not grow.
TEST(Constraints, AContactsProjectionAddsNoSpeed) {
  Model m = test::small_cloth(8, 8, false);
  m.damping = {0.5f, 0.5f, 0.5f};
  Params p = test::small_params();
  p.dt = 5e-4f;
  p.ground = 1.01f;  // the cloth lies at y = 1
  for (const auto& i : integrators()) {
    auto pipe = make_cpu_pipeline({m, p, i.id}, Precision::f32, true);
    double most = 0;
    for (int k = 0; k < 100; ++k) {
      pipe->step();
      most = std::max(most, energy(m, p, pipe->state()).kinetic);
    }
    // One step of gravity on the cloth's 0.64 kg is 0.64 (9.81 dt)^2 / 2 = 7.7e-6 J; the
    // projection taken for a speed (1 cm a step, 20 m/s) would be 128 J.
    EXPECT_LT(most, 1e-5) << i.name;
    EXPECT_NEAR(pipe->state().x[0].y, 1.01f, 1e-5f) << i.name;
  }
}

// The hard handle's node sits on the path's target for the end of each step, with the
// velocity that took it there, and the cloth follows: the handle's neighbours end higher than
// in the same run without it (the path lifts the node 0.15 m).
TEST(Constraints, HardDragHandleIsOnItsTargetAfterEveryStep) {
  Model m = test::small_cloth(12, 12);
  Params p = test::small_params();
  p.drag.node = 6 * 12 + 6;
  const Vec3f r = m.rest_position[p.drag.node];
  p.drag.path = {{0.f, r}, {0.05f, r + Vec3f{0.f, 0.1f, 0.05f}}, {0.1f, r + Vec3f{-0.05f, 0.15f, 0.f}}};
  const int neighbours[] = {p.drag.node - 1, p.drag.node + 1, p.drag.node - 12, p.drag.node + 12};
  for (const auto& i : integrators()) {
    p.dt = i.id == Integrator::explicit_euler ? 1e-4f : 1e-3f;  // explicit Euler's bound is under 1 ms here
    const int steps = int(std::lround(0.15 / p.dt));
    Params free = p;
    free.drag = {};
    auto pipe = make_cpu_pipeline({m, p, i.id}, Precision::f32, true);
    for (int k = 1; k <= steps; ++k) {
      pipe->step();
      const Vec3f target = p.drag.target(k * double(p.dt)), before = p.drag.target((k - 1) * double(p.dt));
      ASSERT_EQ(pipe->state().x[p.drag.node], target) << i.name << " step " << k;
      const Vec3f v = pipe->state().v[p.drag.node], want = (target - before) * (1.f / p.dt);
      ASSERT_LT(norm(v - want), 1e-3f * (norm(want) + 1.f)) << i.name << " step " << k;  // float rounding
    }
    EXPECT_EQ(pipe->state().x[p.drag.node], p.drag.path.back().position);
    auto alone = make_cpu_pipeline({m, free, i.id}, Precision::f32, true);
    for (int k = 1; k <= steps; ++k) alone->step();
    for (int n : neighbours)
      EXPECT_GT(pipe->state().x[n].y, alone->state().x[n].y + 0.05f) << i.name << " node " << n;
  }
}

// A cloth pinned at its border, its node (5, 5) pulled up by the spring handle to a target
// 0.2 m above it, settles where the handle's pull balances the cloth's springs: k_h (target - x)
// equals the gradient of their energy at that node, taken by central differences of `energy`.
// Their error, measured: 1.4e-6 of the pull at eps = 1e-4 m; truncation above that step (4.7e-4
// at 1e-3), rounding below it (4.6e-6 at 5e-5).
TEST(Constraints, SpringDragHandleSettlesWhereItsPullBalancesTheCloth) {
  const int n = 10, h = 5 * n + 5;
  Model m = test::small_cloth(n, n, false);
  std::vector<int> border;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      if (i == 0 || j == 0 || i == n - 1 || j == n - 1) border.push_back(j * n + i);
  pin(m, border);
  Params p = test::small_params();
  p.damping = 0.2f;
  p.gravity = {};
  p.drag.node = h;
  p.drag.as_spring = true;
  p.drag.stiffness = 200.f;
  const Vec3f goal = m.rest_position[h] + Vec3f{0.f, 0.2f, 0.f};
  p.drag.path = {{0.f, m.rest_position[h]}, {0.2f, goal}};
  auto pipe = make_cpu_pipeline({m, p, Integrator::semi_implicit_euler}, Precision::f32, true);
  for (int k = 0; k < 4000; ++k) pipe->step();
  State s = pipe->state();
  // At rest: from step 2000 on the kinetic energy stays at 2.5e-10 to 3e-10 J, float rounding's level.
  ASSERT_LT(energy(m, p, s).kinetic, 1e-8);
  const Vec3f pull = (goal - s.x[h]) * p.drag.stiffness;
  ASSERT_GT(norm(goal - s.x[h]), 0.05f) << "the cloth should hold the handle well off its target";
  const float eps = 1e-4f;
  for (int c = 0; c < 3; ++c) {
    const float at = s.x[h][c], up = at + eps, down = at - eps;
    s.x[h][c] = up;
    const double e_up = energy(m, p, s).spring;
    s.x[h][c] = down;
    const double e_down = energy(m, p, s).spring;
    s.x[h][c] = at;
    EXPECT_NEAR(pull[c], (e_up - e_down) / (double(up) - double(down)), 1e-5 * norm(pull)) << "axis " << c;
  }
}

TEST(Determinism, OmpEqualsCpuBitwiseForEveryIntegrator) {
  // 2304 nodes: omp splits them over two threads (1024 nodes a thread at least), also on a
  // machine with one hardware thread.
  const int threads = omp_get_max_threads();
  omp_set_num_threads(std::max(threads, 2));
  Contact c(true, 48);
  c.params.drag.node = 40;
  c.params.drag.path = {{0.f, c.model.rest_position[40]}, {0.02f, c.model.rest_position[40] + Vec3f{0, 0.05f, 0}}};
  const State s0 = test::perturbed_state(c.model, 5, 0.01f, 0.3f);
  for (const auto& i : integrators()) {
    auto cpu = make_cpu_pipeline({c.model, c.params, i.id}, Precision::f32, false);
    auto omp = make_cpu_pipeline({c.model, c.params, i.id}, Precision::f32, true);
    const State a = test::advance(*cpu, s0, 60), b = test::advance(*omp, s0, 60);
    for (int v = 0; v < c.model.node_count(); ++v) {
      ASSERT_EQ(a.x[v], b.x[v]) << i.name << " node " << v;
      ASSERT_EQ(a.v[v], b.v[v]) << i.name << " node " << v;
    }
    EXPECT_EQ(cpu->max_displacement(), omp->max_displacement()) << i.name;
    EXPECT_GT(test::max_position_diff(a, s0), 1e-4) << i.name << ": the state should have moved";
  }
  omp_set_num_threads(threads);
}

}  // namespace
}  // namespace deformlab
