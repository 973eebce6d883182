// The forces other than springs, and the contact rules' velocities, against analytic
// solutions: wind, gravity and global damping on a free node (exponential approach to the
// terminal velocity), the drag spring with damping (a damped oscillator about its target),
// and what the ground and a sphere do to a node's velocity.
#include <gtest/gtest.h>

#include <cmath>

#include "core/cpu_backend.hpp"
#include "core/physics.hpp"

namespace deformlab {
namespace {

// One free node of mass `mass` at x0, no springs.
Model one_node(Vec3f x0, float mass) {
  Model m;
  m.rest_position = {x0};
  m.inv_mass = {1.f / mass};
  m.build_adjacency();
  return m;
}

// |a - b| <= rel max(1, |b|) in every component.
void expect_near(const Vec3f& a, const Vec3d& b, double rel, const char* what, double t) {
  EXPECT_NEAR(a.x, b.x, rel * std::max(1.0, std::abs(b.x))) << what << " at t = " << t;
  EXPECT_NEAR(a.y, b.y, rel * std::max(1.0, std::abs(b.y))) << what << " at t = " << t;
  EXPECT_NEAR(a.z, b.z, rel * std::max(1.0, std::abs(b.z))) << what << " at t = " << t;
}

// The states are read back as float: 6e-8 relative rounding, so 1e-7 relative (1e-7 absolute
// under 1) leaves room for the integrators' own error, which is far smaller in these tests.
constexpr double kFloatReadBack = 1e-7;

// m v' = w - c v + m g from rest: v = u (1 - e^(-t/tau)), x = x0 + u (t - tau (1 - e^(-t/tau))),
// with the terminal velocity u = (w + m g) / c and tau = m / c. RK4 in double at dt = 1/1024 s:
// its error, of order (dt / tau)^4, is under 1e-12 here.
TEST(FieldForces, WindGravityAndDampingApproachTheTerminalVelocity) {
  const float mass = 2.f, c = 0.5f;
  const Vec3f x0{0.25f, 1.f, -0.5f}, wind{0.3f, 0.2f, -0.2f}, g{0.f, -1.5f, 0.f};
  Params p;
  p.dt = 1.f / 1024;
  p.gravity = g;
  p.wind = wind;
  p.damping = c;
  const Model m = one_node(x0, mass);
  auto pipe = make_cpu_pipeline({m, p, Integrator::rk4}, Precision::f64, false);
  const double tau = double(mass) / c;
  const Vec3d u{(wind.x + mass * g.x) / c, (wind.y + mass * g.y) / c, (wind.z + mass * g.z) / c};
  for (int n = 1; n <= 8192; ++n) {  // 8 s, 2 tau
    pipe->step();
    if (n % 1024 != 0) continue;
    const double t = n * double(p.dt), e = std::exp(-t / tau), s = t - tau * (1 - e);
    expect_near(pipe->state().v[0], {u.x * (1 - e), u.y * (1 - e), u.z * (1 - e)}, kFloatReadBack, "v", t);
    expect_near(pipe->state().x[0], {x0.x + u.x * s, x0.y + u.y * s, x0.z + u.z * s}, kFloatReadBack, "x", t);
  }
}

// A spring-dragged node on a fixed target T, with global damping and no other force:
// m x'' = K (T - x) - c x', so from rest at x0, x = T + e^(-g t) (A cos(w t) + (g A / w) sin(w t))
// with A = x0 - T, g = c / 2m, w = sqrt(K/m - g^2). RK4 at dt = 1/1024 s (w dt = 0.01: error
// under 1e-9 over 3 periods).
TEST(FieldForces, DragSpringIsADampedOscillatorAboutItsTarget) {
  const float mass = 0.5f, K = 50.f, c = 0.4f;
  const Vec3f x0{1.f, 0.5f, 0.f}, target{0.9f, 0.55f, 0.02f};
  Params p;
  p.dt = 1.f / 1024;
  p.gravity = {};
  p.damping = c;
  p.drag.node = 0;
  p.drag.as_spring = true;
  p.drag.stiffness = K;
  p.drag.path = {{0.f, target}};
  const Model m = one_node(x0, mass);
  auto pipe = make_cpu_pipeline({m, p, Integrator::rk4}, Precision::f64, false);
  const double gam = c / (2.0 * mass), w = std::sqrt(K / double(mass) - gam * gam);
  const Vec3d a{double(x0.x) - target.x, double(x0.y) - target.y, double(x0.z) - target.z};
  for (int n = 1; n <= 2048; ++n) {  // 2 s, about 3 periods
    pipe->step();
    if (n % 64 != 0) continue;
    const double t = n * double(p.dt), e = std::exp(-gam * t), cw = std::cos(w * t), sw = std::sin(w * t);
    const double pos = e * (cw + gam / w * sw), vel = -e * (w + gam * gam / w) * sw;
    expect_near(pipe->state().x[0], {target.x + a.x * pos, target.y + a.y * pos, target.z + a.z * pos}, kFloatReadBack, "x", t);
    expect_near(pipe->state().v[0], {a.x * vel, a.y * vel, a.z * vel}, kFloatReadBack, "v", t);
  }
}

using Pf = Physics<float>;

Vec3f unit(Vec3f a) { return a * (1.f / norm(a)); }

// Below the ground the node is put on it and loses only a velocity into the ground.
TEST(ContactVelocity, GroundRemovesOnlyTheVelocityIntoIt) {
  Vec3f x{0.3f, -0.02f, 0.1f}, v{1.5f, -2.f, -0.5f};
  Pf::ground_constraint(x, v, 0.f);
  EXPECT_EQ(x, (Vec3f{0.3f, 0.f, 0.1f}));
  EXPECT_EQ(v, (Vec3f{1.5f, 0.f, -0.5f}));
  // Under the ground but moving out: the position is clamped, the velocity kept.
  x = {0.3f, -0.02f, 0.1f};
  v = {1.5f, 2.f, -0.5f};
  Pf::ground_constraint(x, v, 0.f);
  EXPECT_EQ(x, (Vec3f{0.3f, 0.f, 0.1f}));
  EXPECT_EQ(v, (Vec3f{1.5f, 2.f, -0.5f}));
  // Above it: nothing changes.
  x = {0.3f, 0.02f, 0.1f};
  v = {1.5f, -2.f, -0.5f};
  Pf::ground_constraint(x, v, 0.f);
  EXPECT_EQ(x, (Vec3f{0.3f, 0.02f, 0.1f}));
  EXPECT_EQ(v, (Vec3f{1.5f, -2.f, -0.5f}));
}

// Inside a sphere the node goes to the surface along the line from the centre and loses the
// inward normal part of its velocity; the tangential part stays. The rule's float arithmetic
// (a length, a reciprocal, a projection) on values near 1: within 1e-6, about 10 ulps.
TEST(ContactVelocity, SphereRemovesOnlyTheInwardNormalVelocity) {
  const Vec3f c{0.1f, 0.2f, -0.3f};
  const float r = 0.5f;
  const Vec3f n = unit(Vec3f{1.f, 2.f, -2.f}), tangent = unit(Vec3f{2.f, 1.f, 2.f});  // n . tangent = 0
  Vec3f x = c + n * 0.3f, v = tangent * 0.7f - n * 1.2f;
  Pf::sphere_constraint(x, v, c, r);
  expect_near(x, {c.x + n.x * 0.5, c.y + n.y * 0.5, c.z + n.z * 0.5}, 1e-6, "x", 0);
  expect_near(v, {tangent.x * 0.7, tangent.y * 0.7, tangent.z * 0.7}, 1e-6, "v", 0);
  // Moving outwards: projected, velocity kept.
  x = c + n * 0.3f;
  v = tangent * 0.7f + n * 1.2f;
  const Vec3f before = v;
  Pf::sphere_constraint(x, v, c, r);
  EXPECT_NEAR(norm(x - c), r, 1e-6);
  EXPECT_EQ(v, before);
  // At the centre: out along +y.
  x = c;
  v = {0.f, -1.f, 0.f};
  Pf::sphere_constraint(x, v, c, r);
  EXPECT_EQ(x, (c + Vec3f{0.f, r, 0.f}));
  EXPECT_EQ(v, (Vec3f{0.f, 0.f, 0.f}));
}

// A node thrown sideways onto the ground through a whole pipeline: it lands where the
// parabola meets the ground and then slides at its horizontal velocity (no friction), resting
// on the ground with no vertical velocity.
TEST(ContactVelocity, ANodeLandsAndSlidesOnTheGround) {
  const float h = 0.5f, vx = 0.8f;
  Params p;
  p.dt = 1e-3f;
  p.damping = 0.f;
  p.ground = 0.f;
  const Model m = one_node({0.f, h, 0.f}, 1.f);
  auto pipe = make_cpu_pipeline({m, p, Integrator::semi_implicit_euler}, Precision::f64, false);
  State s = pipe->state();
  s.v[0] = {vx, 0.f, 0.f};
  pipe->set_state(s);
  const double land = std::sqrt(2 * h / 9.81);  // 0.319 s
  for (int n = 1; n <= 1000; ++n) {
    pipe->step();
    const double t = n * double(p.dt);
    const Vec3f x = pipe->state().x[0], v = pipe->state().v[0];
    EXPECT_NEAR(x.x, vx * t, 1e-5) << "t = " << t;  // the slide keeps its speed exactly
    EXPECT_EQ(v.x, vx);
    if (t > land + 2 * p.dt) {
      EXPECT_EQ(x.y, 0.f) << "t = " << t;
      EXPECT_EQ(v.y, 0.f) << "t = " << t;
    } else if (t < land - 2 * p.dt) {
      EXPECT_GT(x.y, 0.f) << "t = " << t;
    }
  }
}

}  // namespace
}  // namespace deformlab
