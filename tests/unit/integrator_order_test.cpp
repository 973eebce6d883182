// Measured convergence order of every integrator on a small cloth, against a fine-step
// RK4 reference, in double precision. Undamped and without contact, so that the
// solution is smooth and every scheme can show its order; and Verlet with damping, which costs
// it an order (its velocity is the half step's, a backward difference).
#include <gtest/gtest.h>

#include <cmath>

#include "core/cpu_backend.hpp"
#include "tests/support/test_states.hpp"

namespace deformlab {
namespace {

constexpr double kT = 0.032;  // s, a multiple of every step below

struct OrderCase {
  Integrator integ;
  double expected;
  std::vector<double> dts;  // chosen so errors sit between float read-back noise and 1e-3
};

class Order : public ::testing::Test {
 protected:
  void SetUp() override {
    Material mat;
    mat.stiffness = {50.f, 50.f, 20.f};
    model_ = cloth_grid(6, 6, 0.05f, 0.f, mat);
    pin(model_, pin_nodes(model_, PinSet::top_corners, {}));
    params_.damping = 0.f;
    start_ = test::perturbed_state(model_, 3, 0.01f, 0.3f);
    reference_ = solve(Integrator::rk4, 1e-5);
  }

  State solve(Integrator integ, double dt) {
    Params p = params_;
    p.dt = float(dt);
    auto pipe = make_cpu_pipeline({model_, p, integ}, Precision::f64, false);
    return test::advance(*pipe, start_, int(std::lround(kT / dt)));
  }

  // Least-squares slope of log(error) against log(dt).
  double measured_order(const OrderCase& c) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    const double n = double(c.dts.size());
    for (double dt : c.dts) {
      const double e = test::max_position_diff(solve(c.integ, dt), reference_);
      const double x = std::log(dt), y = std::log(e);
      sx += x; sy += y; sxx += x * x; sxy += x * y;
      std::printf("  %-20s dt=%.2e  error=%.3e m\n", std::string(info(c.integ).name).c_str(), dt, e);
    }
    return (n * sxy - sx * sy) / (n * sxx - sx * sx);
  }

  Model model_;
  Params params_;
  State start_, reference_;
};

TEST_F(Order, EachIntegratorShowsItsOrder) {
  const std::vector<OrderCase> cases = {
      {Integrator::explicit_euler, 1, {2e-4, 1e-4, 5e-5, 2.5e-5}},
      {Integrator::semi_implicit_euler, 1, {2e-4, 1e-4, 5e-5, 2.5e-5}},
      {Integrator::backward_euler, 1, {2e-4, 1e-4, 5e-5, 2.5e-5}},
      {Integrator::midpoint, 2, {8e-4, 4e-4, 2e-4, 1e-4}},
      {Integrator::verlet, 2, {8e-4, 4e-4, 2e-4, 1e-4}},
      {Integrator::rk3, 3, {1.6e-3, 8e-4, 4e-4}},
      {Integrator::rk4, 4, {3.2e-3, 1.6e-3, 8e-4}},
  };
  for (const auto& c : cases) {
    const double p = measured_order(c);
    std::printf("%s: measured order %.2f (expected %.0f)\n", std::string(info(c.integ).name).c_str(), p, c.expected);
    EXPECT_NEAR(p, c.expected, 0.3) << info(c.integ).name;
  }
}

// Damping forces see Verlet's velocity half a step late: first order. Midpoint, on the same
// damped cloth, keeps its second order, so the lost order is Verlet's, not the scene's.
TEST_F(Order, VerletIsFirstOrderWithDamping) {
  params_.damping = 0.05f;
  reference_ = solve(Integrator::rk4, 1e-5);
  const double verlet = measured_order({Integrator::verlet, 1, {4e-4, 2e-4, 1e-4, 5e-5}});
  const double midpoint = measured_order({Integrator::midpoint, 2, {8e-4, 4e-4, 2e-4, 1e-4}});
  std::printf("damped: verlet %.2f, midpoint %.2f\n", verlet, midpoint);
  EXPECT_NEAR(verlet, 1, 0.3);
  EXPECT_NEAR(midpoint, 2, 0.3);
}

}  // namespace
}  // namespace deformlab
