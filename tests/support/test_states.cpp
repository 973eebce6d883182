#include "test_states.hpp"

#include <algorithm>
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

double max_position_diff(const State& a, const State& b) {
  double d = 0.0;
  for (std::size_t i = 0; i < a.x.size(); ++i) d = std::max(d, double(norm(a.x[i] - b.x[i])));
  return d;
}

double max_velocity_diff(const State& a, const State& b) {
  double d = 0.0;
  for (std::size_t i = 0; i < a.v.size(); ++i) d = std::max(d, double(norm(a.v[i] - b.v[i])));
  return d;
}

State advance(Pipeline& p, const State& s0, int steps) {
  p.set_state(s0);
  for (int k = 0; k < steps; ++k) p.step();
  return p.state();
}

}  // namespace deformlab::test
