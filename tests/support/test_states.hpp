// Shared helpers for tests that compare pipelines: small scenes and non-trivial states.
#pragma once
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "core/integrator.hpp"
#include "core/mesh_model.hpp"
#include "core/model.hpp"
#include "core/params.hpp"
#include "core/pipeline.hpp"
#include "core/state.hpp"

namespace deformlab::test {

// A cloth or lattice with the default material (stiffness 500/500/100 N/m, 0.01 kg nodes),
// spacing 0.05 m, at height 1 m, top corners pinned unless `pinned` is false.
Model small_cloth(int nx, int ny, bool pinned = true);
Model small_lattice(int nx, int ny, int nz, bool pinned = true);
// Meshes made here: an nx x ny grid of points in the x-z plane at height 1 m split into two
// triangles per square (diagonal from (i, j) to (i+1, j+1)), and an nx x ny x nz box of
// points split into six tetrahedra per cube (around the cube's diagonal), spacing 0.05 m,
// each point moved by up to `jitter` x spacing (seeded) so that rest lengths differ.
Mesh triangulated_square(int nx, int ny, float jitter = 0.f, std::uint32_t seed = 1);
Mesh tetrahedralised_box(int nx, int ny, int nz, float jitter = 0.f, std::uint32_t seed = 1);

// Params with dt = 1 ms, gravity, global damping 0.02, spring damping set on the model by
// the caller if wanted, no colliders, no drag.
Params small_params();

// `p` with dt = 0.1 ms for explicit Euler (at 1 ms it grows ~1.4x per step on these springs,
// and rounding with it, so that a comparison's tolerance would hide a real fault).
Params for_integrator(Params p, Integrator i);

// small_params() with wind and, on models of more than 20 nodes, a free node pulled along a
// path by a drag spring, for_integrator. The scene of the tests that compare pipelines.
Params moving_params(const Model& m, Integrator i);

// The rest state moved off rest and set moving: positions jittered by up to `pos_amp`
// (m) and velocities up to `vel_amp` (m/s), from a fixed seed (deterministic).
State perturbed_state(const Model& m, std::uint32_t seed, float pos_amp = 0.01f, float vel_amp = 0.2f);

// Largest |a[i] - b[i]| over nodes (infinite when the sizes differ or either holds a NaN or
// an infinity); of positions, of velocities.
double max_diff(const std::vector<Vec3f>& a, const std::vector<Vec3f>& b);
double max_position_diff(const State& a, const State& b);
double max_velocity_diff(const State& a, const State& b);
// How far a float pipeline that rounds otherwise than `cpu` (fast math, atomic sums, another
// order of the same operations) may end from `cpu`'s state: `times` x the distance that float
// rounding itself puts between `cpu`'s state and the double reference's on this very
// trajectory, but at least a floor of a few ulp. Both the largest node distance and the root
// mean square over nodes are bounded: on scenes with contact, float and double can put a node
// on either side of a collider, which sets the largest distance; the root mean square still
// sees a fault that moves many nodes a little (a stale buffer, a missing term).
struct Bound {
  double x = 0, v = 0;  // m, m/s
};
struct RoundingBound {
  Bound max, rms;
};
// The bound from `cpu`'s float state `a` and the double reference's `r` after the same steps.
RoundingBound rounding_bound(const State& a, const State& r, Bound floor, double times = 8);
// A floor of 4 ulp of the state's largest coordinate (at least 1 mm's), for velocities turned
// into a velocity by 1/dt.
Bound ulp_floor(const State& s, float dt);
// `g` within `b` of `a`: positions and velocities, each by its largest node distance and its
// root mean square, and the same half_step; the message gives each. Fails
// where a bound is not finite (a NaN or infinity in the states it came from).
testing::AssertionResult within_rounding(const State& g, const State& a, const RoundingBound& b);

// Equal bit for bit (positions, velocities, half_step, time).
bool bitwise_equal(const std::vector<Vec3f>& a, const std::vector<Vec3f>& b);
bool bitwise_equal(const State& a, const State& b);

// Runs `steps` steps of pipeline `p` from state `s0` and returns the state.
State advance(Pipeline& p, const State& s0, int steps);

// Runs `steps` steps from `s0` with a profiler sampling one window of steps in `every`
// (Profiler::sample_every) and returns the step of each span it took, in order.
std::vector<int> sampled_span_steps(Pipeline& p, const State& s0, int steps, int every);

}  // namespace deformlab::test
