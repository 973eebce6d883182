// Helpers for the CUDA pipeline tests: the skip rule, model variants and comparisons.
#pragma once
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "core/cpu_backend.hpp"
#include "cuda_kernels/cuda_pipeline.hpp"
#include "tests/support/test_states.hpp"
#include "tests/support/gpu_required.hpp"

namespace deformlab::test {

// Every test that needs a device skips cleanly without one (no driver, no GPU).
#define DEFORMLAB_REQUIRE_CUDA() DEFORMLAB_SKIP_IF_UNAVAILABLE(cuda::unavailable())

// The same springs, seen as a general model: the kernels then gather over the CSR adjacency.
inline Model as_general(const Model& m) { return explicit_springs(m); }

// Model m (damped, its top corners pinned) with a ground just under it at 1 m, two spheres
// cutting it from below and a free node dragged along a path that ends after 10 ms, hard or
// by a spring: every constraint of a step at work.
struct ContactScene {
  Model m;
  Params p;
  std::vector<int> pinned;
};
inline ContactScene contact_scene(Model m, bool spring_drag) {
  ContactScene s{std::move(m), small_params(), {}};
  s.m.damping = {0.02f, 0.02f, 0.01f};
  s.pinned = pin_nodes(s.m, PinSet::top_corners, {});
  s.p.ground = 0.995f;  // just under the cloth: gravity and the perturbation push nodes below
  s.p.spheres = {{{0.f, 0.9f, 0.f}, 0.12f}, {{0.5f, 0.97f, 0.3f}, 0.06f}};  // both cut the cloth from below
  s.p.drag.node = s.m.node_count() / 2 + s.m.nx / 3;
  s.p.drag.as_spring = spring_drag;
  s.p.drag.path = {{0.f, s.m.rest_position[s.p.drag.node]},
                   {0.01f, s.m.rest_position[s.p.drag.node] + Vec3f{0.02f, 0.05f, -0.01f}}};
  return s;
}

inline const char* name(cuda::Variant v) { return cuda::to_string(v); }

inline cuda::Options options(cuda::Variant v, bool graphs = true, cuda::Tile tile = {}) { return {v, tile, graphs}; }

}  // namespace deformlab::test
