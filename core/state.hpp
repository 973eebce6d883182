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
  double t = 0.0;             // simulated time, s
  // Verlet: v is the velocity of the half step before t (set by its steps). False: v is at t,
  // and Verlet's next step kicks by half a step (x1 = x + dt v + dt^2/2 a).
  bool half_step = false;
};

// The model at rest: x = rest positions, v = 0, t = 0.
State rest_state(const Model& m);

}  // namespace deformlab
