#include "test_states.hpp"

#include <algorithm>
#include <cstring>
#include <limits>
#include <random>

namespace deformlab::test {

Model small_cloth(int nx, int ny, bool pinned) {
  Model m = cloth_grid(nx, ny, 0.05f, 1.f, Material{});
  if (pinned) pin(m, pin_nodes(m, PinSet::top_corners, {}));
  return m;
}

Model small_lattice(int nx, int ny, int nz, bool pinned) {
  Model m = lattice(nx, ny, nz, 0.05f, 1.f, Material{});
  if (pinned) pin(m, pin_nodes(m, PinSet::top_corners, {}));
  return m;
}

Params small_params() {
  Params p;
  p.dt = 0.001f;
  p.damping = 0.02f;
  return p;
}

State perturbed_state(const Model& m, std::uint32_t seed, float pos_amp, float vel_amp) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  State s = rest_state(m);
  for (std::size_t i = 0; i < s.x.size(); ++i) {
    if (m.inv_mass[i] == 0.f) continue;
    s.x[i] += Vec3f{u(rng), u(rng), u(rng)} * pos_amp;
    s.v[i] = Vec3f{u(rng), u(rng), u(rng)} * vel_amp;
  }
  return s;
}

Params moving_params(const Model& m, Integrator i) {
  Params p = small_params();
  if (i == Integrator::explicit_euler) p.dt = 1e-4f;
  p.wind = {0.002f, 0.f, -0.001f};
  if (m.node_count() > 20) {
    p.drag.node = m.node_count() / 2 + 3;
    p.drag.as_spring = true;
    p.drag.stiffness = 50.f;
    const Vec3f x0 = m.rest_position[p.drag.node];
    p.drag.path = {{0.f, x0}, {0.1f, x0 + Vec3f{0.05f, 0.02f, 0.f}}};
  }
  return p;
}

double max_diff(const std::vector<Vec3f>& a, const std::vector<Vec3f>& b) {
  if (a.size() != b.size()) return std::numeric_limits<double>::infinity();
  double d = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) d = std::max(d, double(norm(a[i] - b[i])));
  return d;
}

double max_position_diff(const State& a, const State& b) { return max_diff(a.x, b.x); }
double max_velocity_diff(const State& a, const State& b) { return max_diff(a.v, b.v); }

bool bitwise_equal(const std::vector<Vec3f>& a, const std::vector<Vec3f>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3f)) == 0);
}
bool bitwise_equal(const State& a, const State& b) {
  return bitwise_equal(a.x, b.x) && bitwise_equal(a.v, b.v) && bitwise_equal(a.x_prev, b.x_prev) && a.t == b.t;
}

State advance(Pipeline& p, const State& s0, int steps) {
  p.set_state(s0);
  for (int k = 0; k < steps; ++k) p.step();
  return p.state();
}

}  // namespace deformlab::test
