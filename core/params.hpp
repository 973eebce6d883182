// Params: the scene's plain data (dt, gravity, damping, colliders, drag handle, stop rule).
#pragma once
#include <optional>
#include <vector>

#include "vec3.hpp"

namespace deformlab {

struct Sphere {
  Vec3f center;
  float radius = 0.f;
};

struct Keyframe {
  float t = 0.f;  // s
  Vec3f position;
};

// A node pulled along a keyframed path (linear between keys, held before the first and after
// the last; a scene's path starts at its node's rest position at t = 0: resolve_params).
// Hard: the node is kinematic and sits on its target after every step. Spring: a spring of
// `stiffness` pulls it towards the target, which the node then follows with some lag.
struct DragHandle {
  int node = -1;  // -1: no drag
  std::vector<Keyframe> path;
  bool as_spring = false;
  float stiffness = 1000.f;  // N/m, spring mode only

  bool active() const { return node >= 0 && !path.empty(); }
  Vec3f target(double t) const;
  double end_time() const { return path.empty() ? 0.0 : path.back().t; }
};

struct Params {
  float dt = 0.002f;                    // s
  Vec3f gravity{0.f, -9.81f, 0.f};      // m/s^2
  float damping = 0.05f;                // global velocity damping c, N s/m (f = -c v)
  Vec3f wind{0.f, 0.f, 0.f};            // constant force on every node, N
  std::optional<float> ground;          // plane y = ground (nodes kept at y >= ground)
  std::vector<Sphere> spheres;
  DragHandle drag;
  float threshold = 0.001f;             // stop when no node moves more than this in a step, m
  int min_steps = 100;                  // the stop rule is not applied before this step
  int max_steps = 100000;
  int check_every = 1;                  // steps between convergence / divergence checks
  float runaway_factor = 1.f;           // diverged if a node moves > factor * model extent in one step

  // How far a node may move in one step before a run takes it for divergence: runaway_factor x
  // the model's extent, the extent counted as at least 1 mm.
  double runaway_distance(float extent) const;
  // Whether the drag holds node n on its path (hard mode): it follows the path, not its forces.
  bool hard_dragged(int n) const { return drag.active() && !drag.as_spring && n == drag.node; }
};

// Throw std::invalid_argument naming the first bad field.
void validate(const Params& p, int node_count);
void validate(const DragHandle& d, int node_count);

}  // namespace deformlab
