// Physics against analytic solutions: a spring oscillator, free fall, energy behaviour of
// each integrator, and backward Euler past the explicit stability limit, solved on one thread on cpu.
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <numeric>
#include <string>

#include "core/cpu_backend.hpp"
#include "core/energy.hpp"
#include "core/physics.hpp"
#include "core/run.hpp"
#include "core/springs.hpp"
#include "core/step_params.hpp"
#include "tests/support/test_states.hpp"

namespace deformlab {
namespace {

// Node 0 pinned at (-l, 0, 0), node 1 of mass m at rest at the origin (so its float
// read-back keeps full precision) on a spring of stiffness k, rest length l.
Model two_node_spring(float k, float mass, float rest) {
  Model m;
  m.rest_position = {{-rest, 0.f, 0.f}, {0.f, 0.f, 0.f}};
  m.inv_mass = {0.f, 1.f / mass};
  m.spring_i = {0};
  m.spring_j = {1};
  m.rest_length = {rest};
  m.kind = {SpringKind::structural};
  m.stiffness = {k, k, k};
  m.build_adjacency();
  return m;
}

Params no_forces(float dt) {
  Params p;
  p.dt = dt;
  p.gravity = {};
  p.damping = 0.f;
  return p;
}

struct Oscillation {
  double period = 0, amplitude = 0, max_error = 0;
  double envelope = 0;  // at the end: sqrt(u^2 + (v / w)^2), the amplitude the state carries
};

// Runs the oscillator for `periods` analytic periods, measuring the period from upward
// zero crossings of the displacement, the amplitude from its extremes, and the final state's
// envelope.
Oscillation oscillate(Integrator integ, double dt, double periods) {
  const float k = 100.f, mass = 1.f, rest = 1.f, amp = 0.1f;
  const double w = std::sqrt(double(k) / mass), period = 2 * std::numbers::pi / w;
  const Model m = two_node_spring(k, mass, rest);
  const Params p = no_forces(float(dt));
  auto pipe = make_cpu_pipeline({m, p, integ}, Precision::f64, false);
  State s = rest_state(m);
  s.x[1].x += amp;
  pipe->set_state(s);
  Oscillation o;
  double prev = amp, first_up = -1, last_up = -1;
  int ups = 0;
  const int steps = int(std::round(periods * period / dt));
  for (int n = 1; n <= steps; ++n) {
    pipe->step();
    const double t = n * double(p.dt), u = pipe->state().x[1].x;
    o.amplitude = std::max(o.amplitude, std::abs(u));
    o.max_error = std::max(o.max_error, std::abs(u - amp * std::cos(w * t)));
    if (prev < 0 && u >= 0) {
      const double tc = t - dt * u / (u - prev);  // linear interpolation of the crossing
      if (first_up < 0) first_up = tc;
      last_up = tc;
      ++ups;
    }
    prev = u;
  }
  o.period = ups > 1 ? (last_up - first_up) / (ups - 1) : 0;
  const State end = pipe->state();
  o.envelope = std::hypot(double(end.x[1].x), end.v[1].x / w);
  return o;
}

// The spring force as written for the GPUs (one reciprocal square root) against its textbook
// form in double, -(k (|d| - l) + kd (v_i - v_j).u) u: within float rounding of the force's
// size; equal and opposite from the other end; no force between coincident nodes, and a
// bounded, finite one between nodes 1e-20 m apart.
TEST(SpringForce, HookeAndDampingAlongTheAxis) {
  using Pf = Physics<float>;
  using Pd = Physics<double>;
  const float k = 250.f, kd = 0.7f, rest = 0.05f;
  const Vec3f xi{0.31f, -0.2f, 0.11f}, vi{0.4f, -1.2f, 0.3f}, vj{-0.5f, 0.2f, 0.9f};
  for (const Vec3f xj : {Vec3f{0.33f, -0.17f, 0.12f}, Vec3f{0.36f, -0.2f, 0.11f}, Vec3f{0.2f, 0.1f, -0.4f}}) {
    const Vec3d d{double(xi.x) - xj.x, double(xi.y) - xj.y, double(xi.z) - xj.z};
    const double len = length(d);
    const Vec3d u{d.x / len, d.y / len, d.z / len};
    const double s = k * (len - rest) + kd * ((double(vi.x) - vj.x) * u.x + (double(vi.y) - vj.y) * u.y +
                                              (double(vi.z) - vj.z) * u.z);
    const Vec3f f = Pf::spring_force(xi, xj, vi, vj, k, kd, rest), g = Pf::spring_force(xj, xi, vj, vi, k, kd, rest);
    const double tol = 4e-7 * (std::abs(s) + k * rest);
    EXPECT_NEAR(f.x, -s * u.x, tol);
    EXPECT_NEAR(f.y, -s * u.y, tol);
    EXPECT_NEAR(f.z, -s * u.z, tol);
    EXPECT_TRUE(g.x == -f.x && g.y == -f.y && g.z == -f.z);
    const Vec3d fd = Pd::spring_force(Vec3d{xi.x, xi.y, xi.z}, Vec3d{xj.x, xj.y, xj.z}, Vec3d{vi.x, vi.y, vi.z},
                                      Vec3d{vj.x, vj.y, vj.z}, k, kd, rest);
    EXPECT_NEAR(fd.x, -s * u.x, 1e-12 * k);
    EXPECT_NEAR(fd.y, -s * u.y, 1e-12 * k);
    EXPECT_NEAR(fd.z, -s * u.z, 1e-12 * k);
  }
  const Vec3f same = Pf::spring_force(xi, xi, vi, vj, k, kd, rest);
  EXPECT_TRUE(same.x == 0.f && same.y == 0.f && same.z == 0.f);
  const Vec3f near = Pf::spring_force(Vec3f{1e-20f, 0.f, 0.f}, Vec3f{}, vi, vj, k, kd, rest);
  EXPECT_TRUE(std::isfinite(near.x) && std::abs(near.x) <= k * rest);
}

TEST(Oscillator, Rk4MatchesTheAnalyticSolution) {
  const double period = 2 * std::numbers::pi / 10.0;
  const Oscillation o = oscillate(Integrator::rk4, 1.0 / 1024, 5);  // dt exact in float
  EXPECT_NEAR(o.period, period, 1e-6 * period);
  EXPECT_NEAR(o.amplitude, 0.1, 1e-6);
  // RK4's global error A w t (w dt)^4 / 120 is 2.4e-10 here, the float read-back of u rounds
  // by up to 3.7e-9; a third-order step would be off by 1.2e-7.
  EXPECT_LT(o.max_error, 1e-8);
}

TEST(Oscillator, EveryIntegratorKeepsPeriodAndAmplitude) {
  const double period = 2 * std::numbers::pi / 10.0;
  for (const auto& i : integrators()) {
    if (i.id == Integrator::explicit_euler || i.id == Integrator::backward_euler) continue;
    const Oscillation o = oscillate(i.id, 1e-3, 5);
    std::printf("%-20s period %.3e of the exact, amplitude %.6f, envelope at the end %.6f\n",
                std::string(i.name).c_str(), o.period / period - 1, o.amplitude, o.envelope);
    // Phase error of the second-order-accurate-in-phase schemes is O((w dt)^2) = 1e-4.
    EXPECT_NEAR(o.period, period, 1e-4 * period) << i.name;
    // Symplectic Euler's amplitude error is O(w dt) = 1e-2 (it keeps a modified energy): the
    // largest excursion must not grow past it, and the envelope at the end not shrink past it.
    EXPECT_NEAR(o.amplitude, 0.1, 0.1 * 0.011) << i.name;
    EXPECT_NEAR(o.envelope, 0.1, 0.1 * 0.011) << i.name;
  }
  // The non-symplectic first-order schemes drift: explicit Euler multiplies the envelope
  // sqrt(u^2 + (v/w)^2) by exactly sqrt(1 + (w dt)^2) a step, backward Euler divides it by that
  // (u + i v/w is multiplied by 1 -+ i w dt, or divided by 1 + i w dt). Over n steps: 1.17 and
  // 0.855. The state is read back as float: u and v/w round by under 1e-8.
  const int n = int(std::round(5 * period / 1e-3));
  const double grow = std::pow(1 + 1e-4, 0.5 * n);
  EXPECT_NEAR(oscillate(Integrator::explicit_euler, 1e-3, 5).envelope, 0.1 * grow, 1e-7);
  EXPECT_NEAR(oscillate(Integrator::backward_euler, 1e-3, 5).envelope, 0.1 / grow, 1e-7);
  EXPECT_NEAR(oscillate(Integrator::explicit_euler, 1e-3, 5).amplitude, 0.1 * grow, 0.1 * 0.01 * grow);
}

TEST(FreeFall, MatchesHalfGTSquared) {
  Model m;
  m.rest_position = {{0.f, 10.f, 0.f}};
  m.inv_mass = {1.f};
  m.build_adjacency();
  Params p;
  p.damping = 0.f;
  p.dt = 0.01f;
  const double g = 9.81, dt = p.dt;
  const int n = 100;
  const double t = n * dt, exact = 10.0 - 0.5 * g * t * t;
  for (const auto& i : integrators()) {
    auto pipe = make_cpu_pipeline({m, p, i.id}, Precision::f64, false);
    for (int k = 0; k < n; ++k) pipe->step();
    const double y = pipe->state().x[0].y;
    // (the state is read back as float: 1e-6 relative)
    if (i.order >= 2) {
      EXPECT_NEAR(y, exact, 1e-5) << i.name << ": exact for constant acceleration";
    } else {
      // explicit Euler lags by g t dt / 2; semi-implicit and backward Euler lead by it.
      const double lag = i.id == Integrator::explicit_euler ? -1.0 : 1.0;
      EXPECT_NEAR(y, exact - lag * 0.5 * g * t * dt, 1e-5) << i.name;
    }
  }
}

// Free fall in float: Verlet keeps its velocity (the leapfrog form), so a step's rounding of x'
// does not stay in it, as it did in position Verlet's x - x_prev (3.35e-3 of the extent after
// 1000 steps of a 4 x 4 cloth, 4.9 m down, against semi-implicit Euler's 3.7e-6).
TEST(FreeFall, VerletsFloatRunStaysWithItsDoubleRun) {
  const Model m = cloth_grid(4, 4, 1.f / 3.f, 1.f, Material{});  // 1 m wide, as the default cloth
  Params p;
  p.damping = 0.f;
  p.dt = 1e-3f;
  auto error = [&](Integrator i) {
    auto f = make_cpu_pipeline({m, p, i}, Precision::f32, false), d = make_cpu_pipeline({m, p, i}, Precision::f64, false);
    for (int k = 0; k < 1000; ++k) {
      f->step();
      d->step();
    }
    EXPECT_NEAR(f->state().x[0].y - m.rest_position[0].y, -4.9, 0.01) << info(i).name << ": it falls";
    return test::max_position_diff(f->state(), d->state()) / m.extent();
  };
  const double verlet = error(Integrator::verlet), sie = error(Integrator::semi_implicit_euler);
  std::printf("of the extent: verlet %.3g, semi-implicit euler %.3g\n", verlet, sie);
  EXPECT_LT(verlet, 1e-5);
  EXPECT_LT(sie, 1e-5);
}

// Undamped, unpinned, no gravity: a soft cloth released from a perturbed state, N steps.
struct EnergyRun {
  double worst = 0;  // largest |E - E0| / E0 over the steps
  double rise = 0;   // largest (E_k+1 - E_k) / E0 of a step
  double ratio = 0;  // E_N / E0
  double w_dt = 0;   // the model's largest angular frequency (Gershgorin, as stability_limit) x dt
};
EnergyRun energy_run(Integrator integ, int steps, float dt = 1e-4f) {
  Material mat;
  mat.stiffness = {10.f, 10.f, 10.f};
  const Model m = cloth_grid(8, 8, 0.05f, 1.f, mat);
  Params p = no_forces(dt);
  auto pipe = make_cpu_pipeline({m, p, integ}, Precision::f64, false);
  State s = test::perturbed_state(m, 7, 0.01f, 0.f);
  pipe->set_state(s);
  const double e0 = energy(m, p, s).total();
  EnergyRun r;
  r.w_dt = 2.0 / stability_limit(m, p, Integrator::semi_implicit_euler) * p.dt;
  double e = e0;
  for (int k = 0; k < steps; ++k) {
    pipe->step();
    const double before = e;
    e = energy(m, p, pipe->state()).total();
    r.worst = std::max(r.worst, std::abs(e - e0) / e0);
    r.rise = std::max(r.rise, (e - before) / e0);
  }
  r.ratio = e / e0;
  return r;
}

// Each scheme's energy against what it does to a linear oscillator at the model's largest
// frequency w: the symplectic schemes keep a modified energy within w dt / 2 of the energy (no
// drift; bounded here by w dt); explicit Euler multiplies a mode's energy by 1 + (w dt)^2 a
// step, so the total grows, by at most (1 + (w dt)^2)^N; backward Euler loses it. The
// Runge-Kutta schemes: EnergyErrorFallsAtEachSchemesRate.
TEST(Energy, EachSchemeWithinWhatItDoesToTheFastestMode) {
  const int n = 10000;
  for (const auto& i : integrators()) {
    const EnergyRun r = energy_run(i.id, n);
    const double wdt = r.w_dt;
    std::printf("%s: worst |E - E0| / E0 %.3g, E_N / E0 %.6g (w dt %.3g)\n", std::string(i.name).c_str(), r.worst,
                r.ratio, wdt);
    switch (i.id) {
      case Integrator::semi_implicit_euler:
      case Integrator::verlet: EXPECT_LT(r.worst, wdt) << i.name; break;
      case Integrator::explicit_euler:
        EXPECT_GT(r.ratio, 1.0) << i.name << ": it gains energy";
        EXPECT_LT(r.ratio, std::pow(1 + wdt * wdt, n)) << i.name;
        break;
      case Integrator::backward_euler: EXPECT_LT(r.ratio, 1.0) << i.name << ": it loses energy"; break;
      default: break;
    }
  }
}

// The potential (springs and fields) of the state x + e d, in double.
double potential_along(const Model& m, const Params& p, const State& s, const std::vector<Vec3d>& d, double e) {
  State t = s;
  for (std::size_t i = 0; i < t.x.size(); ++i)
    for (int c = 0; c < 3; ++c) t.x[i][c] = float(double(s.x[i][c]) + e * d[i][c]);
  const Energy en = energy(m, p, t);
  return en.spring + en.field;
}

// A step's energy change to second order in dt, from the state's potential U alone: with
// m a = -grad U, explicit Euler's step changes E by dt^2 / 2 (sum m |a|^2 + v.H v) and
// semi-implicit Euler's by dt^2 / 2 (v.H v - sum m |a|^2), H the Hessian of U (the first-order
// terms cancel in both). grad U and v.H v by central differences of U.
double predicted_energy_change(const Model& m, const Params& p, const State& s, Integrator integ) {
  const std::size_t n = s.x.size();
  std::vector<Vec3d> v(n), unit(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = {s.v[i].x, s.v[i].y, s.v[i].z};
  const double h = 1e-4;  // m: central differences' truncation (h^2) and float rounding balanced
  double ma2 = 0;
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      std::fill(unit.begin(), unit.end(), Vec3d{});
      unit[i][c] = 1;
      const double g = (potential_along(m, p, s, unit, h) - potential_along(m, p, s, unit, -h)) / (2 * h);
      ma2 += g * g * m.inv_mass[i];
    }
  const double speed = std::sqrt(std::inner_product(v.begin(), v.end(), v.begin(), 0.0,
                                                    std::plus<>(), [](Vec3d a, Vec3d b) { return dot(a, b); }));
  const double e = h / speed;  // x moved by h along v / |v|
  const double vhv = (potential_along(m, p, s, v, e) - 2 * potential_along(m, p, s, v, 0) +
                      potential_along(m, p, s, v, -e)) / (e * e);
  const double sign = integ == Integrator::explicit_euler ? 1 : -1;
  return 0.5 * double(p.dt) * p.dt * (sign * ma2 + vhv);
}

// Measured on an 8 x 8 cloth (undamped, free, no gravity, perturbed positions and velocities):
// the change within 0.54% of its prediction over five steps at each dt, the float state's
// rounding of E (3e-8 J against changes of 5e-6 to 2.5e-5 J); the change 4.0 times as large at
// twice the dt (3.98-4.00). A first-order term left in (a force of the wrong sign) would be O(dt).
TEST(Energy, EulerStepsChangeItByTheirSecondOrderTerm) {
  Material mat;
  mat.stiffness = {10.f, 10.f, 10.f};
  const Model m = cloth_grid(8, 8, 0.05f, 1.f, mat);
  for (const Integrator integ : {Integrator::explicit_euler, Integrator::semi_implicit_euler}) {
    std::vector<double> first;  // the first step's change at each dt
    for (const float dt : {2e-4f, 1e-4f}) {
      const Params p = no_forces(dt);
      auto pipe = make_cpu_pipeline({m, p, integ}, Precision::f64, false);
      pipe->set_state(test::perturbed_state(m, 7, 0.01f, 0.2f));
      double worst = 0;
      for (int k = 0; k < 5; ++k) {
        const State s = pipe->state();
        const double want = predicted_energy_change(m, p, s, integ), e0 = energy(m, p, s).total();
        pipe->step();
        const double got = energy(m, p, pipe->state()).total() - e0;
        if (k == 0) first.push_back(got);
        worst = std::max(worst, std::abs(got / want - 1));
      }
      std::printf("%s, dt %g: a step's energy change within %.2g of its second-order term\n",
                  std::string(info(integ).name).c_str(), dt, worst);
      EXPECT_LT(worst, 0.02) << info(integ).name << " dt " << dt;
    }
    EXPECT_NEAR(first[0] / first[1], 4.0, 0.1) << info(integ).name;
  }
}

// The energy error over one second at dt and dt / 2, as the linear oscillator predicts for each
// scheme at w dt << 1: the symplectic ones' modified energy sits w dt / 2 off (halves with dt,
// no drift); midpoint's |R(i w dt)|^2 is 1 + (w dt)^4 / 4 a step and RK3's 1 - (w dt)^4 / 12, so
// over a fixed time (w dt)^3 (falls 8-fold); RK4's (w dt)^6 / 72 stays under the float
// read-back's rounding of the state (1e-6); backward Euler loses energy in every step.
// Measured: semi-implicit Euler and Verlet 0.99-1.00, midpoint 3.01 and 3.00, RK3 2.99 and
// 2.90 (log2 of the ratio, dt 4e-4 to 2e-4 and 2e-4 to 1e-4).
TEST(Energy, EnergyErrorFallsAtEachSchemesRate) {
  for (const auto& i : integrators()) {
    const EnergyRun a = energy_run(i.id, 2500, 4e-4f), b = energy_run(i.id, 5000, 2e-4f);
    const double rate = std::log2(a.worst / b.worst);
    switch (i.id) {
      case Integrator::semi_implicit_euler:
      case Integrator::verlet: EXPECT_NEAR(rate, 1.0, 0.1) << i.name; break;
      case Integrator::midpoint:
        EXPECT_NEAR(rate, 3.0, 0.2) << i.name;
        EXPECT_GT(a.ratio, 1 + 1e-5) << i.name << ": it gains energy (README, Physics notes)";
        break;
      case Integrator::rk3:
        EXPECT_NEAR(rate, 3.0, 0.2) << i.name;
        EXPECT_LT(a.ratio, 1 - 1e-5) << i.name << ": it loses energy";
        break;
      case Integrator::rk4:
        EXPECT_LT(a.worst, 1e-6) << i.name;
        EXPECT_LT(b.worst, 1e-6) << i.name;
        break;
      case Integrator::backward_euler:
        EXPECT_LT(b.rise, 1e-6) << i.name << ": a step that gains energy";
        EXPECT_LT(a.ratio, b.ratio) << i.name << ": loses more at the larger dt";
        break;
      case Integrator::explicit_euler: EXPECT_GT(a.ratio, b.ratio) << i.name << ": gains more at the larger dt"; break;
    }
  }
}

TEST(BackwardEuler, TheCpuPipelineSolvesOnOneThread) {
  // Eigen's solver threads are a process-wide setting: omp's solve first, then cpu's.
  const Model m = test::small_cloth(64, 64);
  Params p = test::small_params();
  p.max_steps = 1;
  run(*make_cpu_pipeline({m, p, Integrator::backward_euler}, Precision::f32, true), m, p, {});
  if (omp_get_max_threads() > 1) {
    EXPECT_GT(Eigen::nbThreads(), 1) << "omp's solve runs on its threads";
  }
  run(*make_cpu_pipeline({m, p, Integrator::backward_euler}, Precision::f32, false), m, p, {});
  EXPECT_EQ(Eigen::nbThreads(), 1) << "the single-threaded pipeline's solve runs on one thread";
}

TEST(BackwardEuler, StableAtTenTimesTheExplicitLimit) {
  Model m = test::small_cloth(16, 16);
  Params p = test::small_params();
  const double limit = stability_limit(m, p, Integrator::semi_implicit_euler);
  p.dt = float(10 * limit);
  p.max_steps = 400;
  auto be = make_cpu_pipeline({m, p, Integrator::backward_euler}, Precision::f32, true);
  const double e0 = energy(m, p, rest_state(m)).total();
  RunResult r = run(*be, m, p, {});
  EXPECT_EQ(r.steps, 400);
  const Energy e = energy(m, p, be->state());
  EXPECT_LT(e.total(), e0) << "backward Euler dissipates: the cloth settles below its start";
  EXPECT_LT(r.last_displacement, 1e-2);
  // And where it settles is the static equilibrium: on every free node the springs, gravity and
  // damping cancel, a = (f_springs - c v) / m + g ~ 0 (measured: 0.001 g at the largest, against
  // 1 g in the flat rest state it starts from).
  const State st = be->state();
  std::vector<Vec3d> f(m.node_count());
  auto d3 = [](const Vec3f& a) { return Vec3d{a.x, a.y, a.z}; };
  for_each_spring(m, [&](const SpringRef& sp) {
    const Vec3d fi = Physics<double>::spring_force(d3(st.x[sp.i]), d3(st.x[sp.j]), d3(st.v[sp.i]), d3(st.v[sp.j]),
                                                   sp.k, sp.kd, sp.rest);
    f[sp.i] += fi;
    f[sp.j] -= fi;
  });
  double worst = 0;
  const auto sp = step_params<double>(m, p);
  for (int v = 0; v < m.node_count(); ++v) {
    if (m.pinned(v)) continue;
    const Vec3d a = Physics<double>::node_acceleration(sp, v, m.inv_mass[v], d3(st.x[v]), d3(st.v[v]), f[v], Vec3d{});
    worst = std::max(worst, length(a));
  }
  EXPECT_LT(worst, 0.01 * 9.81) << "largest residual acceleration after " << r.steps << " steps";
  // The same step breaks the explicit schemes.
  auto se = make_cpu_pipeline({m, p, Integrator::semi_implicit_euler}, Precision::f32, true);
  EXPECT_THROW(run(*se, m, p, {}), DivergenceError);
}

}  // namespace
}  // namespace deformlab
