// State: what changes during a run, as exchanged between pipelines (host, float).
// Backends keep their own layout (float4 with inverse mass in w on GPUs) and convert here.
#pragma once
#include <vector>

#include "vec3.hpp"

namespace deformlab {

struct Model;

struct State {
  std::vector<Vec3f> x;       // [n] positions, m
  std::vector<Vec3f> v;       // [n] velocities, m/s
  // [n] previous positions, kept by Verlet. Empty means "start from (x, v)": Verlet's
  // first step is then the Taylor start x1 = x + dt v + dt^2/2 a, second-order accurate.
  std::vector<Vec3f> x_prev;
  double t = 0.0;             // simulated time, s
};

// The model at rest: x = rest positions, v = 0, no x_prev, t = 0.
State rest_state(const Model& m);

}  // namespace deformlab
