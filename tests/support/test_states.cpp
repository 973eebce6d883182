#include "test_states.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "core/profiler.hpp"

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

namespace {
void jitter_points(Mesh& m, float amount, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  for (auto& p : m.position) p += Vec3f{u(rng), u(rng), u(rng)} * (amount * 0.05f);
}
}  // namespace

Mesh triangulated_square(int nx, int ny, float jitter, std::uint32_t seed) {
  Mesh m;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) m.position.push_back({0.05f * float(i), 1.f, 0.05f * float(j)});
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      const int a = j * nx + i, b = a + 1, c = a + nx, d = c + 1;
      m.triangle.push_back({a, c, d});
      m.triangle.push_back({a, d, b});
    }
  jitter_points(m, jitter, seed);
  return m;
}

Mesh tetrahedralised_box(int nx, int ny, int nz, float jitter, std::uint32_t seed) {
  Mesh m;
  auto node = [&](int i, int j, int k) { return (k * ny + j) * nx + i; };
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) m.position.push_back({0.05f * float(i), 1.f + 0.05f * float(j), 0.05f * float(k)});
  // The six tetrahedra of a cube around its diagonal from corner 0 to corner 7 (corner bits: x, y, z).
  const int ring[6] = {1, 3, 2, 6, 4, 5};
  for (int k = 0; k + 1 < nz; ++k)
    for (int j = 0; j + 1 < ny; ++j)
      for (int i = 0; i + 1 < nx; ++i) {
        auto corner = [&](int c) { return node(i + (c & 1), j + (c >> 1 & 1), k + (c >> 2 & 1)); };
        for (int t = 0; t < 6; ++t) m.tetrahedron.push_back({corner(0), corner(7), corner(ring[t]), corner(ring[(t + 1) % 6])});
      }
  jitter_points(m, jitter, seed);
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

Params for_integrator(Params p, Integrator i) {
  if (i == Integrator::explicit_euler) p.dt = 1e-4f;
  return p;
}

Params moving_params(const Model& m, Integrator i) {
  Params p = for_integrator(small_params(), i);
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
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double e = norm(a[i] - b[i]);
    if (!std::isfinite(e)) return std::numeric_limits<double>::infinity();  // a NaN or inf on either side
    d = std::max(d, e);
  }
  return d;
}

double max_position_diff(const State& a, const State& b) { return max_diff(a.x, b.x); }
double max_velocity_diff(const State& a, const State& b) { return max_diff(a.v, b.v); }

namespace {
// Root mean square of |a[i] - b[i]| over nodes (infinite as max_diff is).
double rms_diff(const std::vector<Vec3f>& a, const std::vector<Vec3f>& b) {
  if (a.size() != b.size() || !std::isfinite(max_diff(a, b))) return std::numeric_limits<double>::infinity();
  double sum = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double e = norm(a[i] - b[i]);
    sum += e * e;
  }
  return a.empty() ? 0.0 : std::sqrt(sum / double(a.size()));
}
}  // namespace

RoundingBound rounding_bound(const State& a, const State& r, Bound floor, double times) {
  return {{std::max(times * max_diff(a.x, r.x), floor.x), std::max(times * max_diff(a.v, r.v), floor.v)},
          {std::max(times * rms_diff(a.x, r.x), floor.x), std::max(times * rms_diff(a.v, r.v), floor.v)}};
}

Bound ulp_floor(const State& s, float dt) {
  double largest = 1e-3;
  for (const auto& x : s.x) largest = std::max({largest, double(std::abs(x.x)), double(std::abs(x.y)), double(std::abs(x.z))});
  const double ulp = std::ldexp(1.0, std::ilogb(largest) - 23);
  return {4 * ulp, 4 * ulp / dt};
}

testing::AssertionResult within_rounding(const State& g, const State& a, const RoundingBound& b) {
  const double dx = max_diff(g.x, a.x), dv = max_diff(g.v, a.v), rx = rms_diff(g.x, a.x), rv = rms_diff(g.v, a.v);
  // An infinite bound (the CPU's own state not finite) passes nothing.
  const bool finite = std::isfinite(b.max.x) && std::isfinite(b.max.v) && std::isfinite(b.rms.x) && std::isfinite(b.rms.v);
  const bool ok = finite && dx <= b.max.x && dv <= b.max.v && rx <= b.rms.x && rv <= b.rms.v && g.half_step == a.half_step;
  auto result = ok ? testing::AssertionSuccess() : testing::AssertionFailure();
  return result << "positions apart by " << dx << " m at most (bound " << b.max.x << "), " << rx << " rms (" << b.rms.x
                << "); velocities " << dv << " m/s (" << b.max.v << "), " << rv << " rms (" << b.rms.v
                << ")" << (g.half_step != a.half_step ? "; one's Verlet velocity is the half step's, the other's not" : "")
                << (bitwise_equal(g, a) ? "; bitwise equal" : "");
}

bool bitwise_equal(const std::vector<Vec3f>& a, const std::vector<Vec3f>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3f)) == 0);
}
bool bitwise_equal(const State& a, const State& b) {
  return bitwise_equal(a.x, b.x) && bitwise_equal(a.v, b.v) && a.half_step == b.half_step && a.t == b.t;
}

State advance(Pipeline& p, const State& s0, int steps) {
  p.set_state(s0);
  for (int k = 0; k < steps; ++k) p.step();
  return p.state();
}

std::vector<int> sampled_span_steps(Pipeline& p, const State& s0, int steps, int every) {
  Profiler prof;
  prof.sample_every(every);
  p.set_state(s0);
  p.set_profiler(&prof);
  for (int k = 1; k <= steps; ++k) {
    prof.set_step(k);
    p.step();
  }
  p.set_profiler(nullptr);  // collects the pending spans
  std::vector<int> at;
  for (const Span& s : prof.spans()) at.push_back(s.step);
  return at;
}

}  // namespace deformlab::test
