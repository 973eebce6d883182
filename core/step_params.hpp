// The per-node physics' view of a model and its params (core/node_physics.h): built once per
// pipeline on the host, in the precision of the pipeline, and copied to wherever its nodes live.
#pragma once
#include <stdexcept>
#include <string>
#include <vector>

#include "grid_stencil.hpp"
#include "model.hpp"
#include "params.hpp"
#include "physics.hpp"

static_assert(MAX_STENCIL == deformlab::kLatticeStencil, "node_physics.h's MAX_STENCIL is the largest grid stencil");

namespace deformlab {

// The drag handle's part of the step parameters.
template <class Real>
void set_drag_params(typename Physics<Real>::StepParams& s, const DragHandle& d) {
  s.drag_node = d.active() ? d.node : -1;
  s.drag_mode = !d.active() ? DRAG_NONE : d.as_spring ? DRAG_SPRING : DRAG_HARD;
  s.drag_stiffness = Real(d.stiffness);
}

template <class Real>
typename Physics<Real>::StepParams step_params(const Model& m, const Params& p) {
  typename Physics<Real>::StepParams s{};
  s.gravity = vec3_cast<Real>(p.gravity);
  s.dt = Real(p.dt);
  s.wind = vec3_cast<Real>(p.wind);
  s.damping = Real(p.damping);
  set_drag_params<Real>(s, p.drag);
  s.has_ground = p.ground ? 1 : 0;
  s.ground = Real(p.ground.value_or(0.f));
  if (p.spheres.size() > MAX_SPHERES)
    throw std::invalid_argument("at most " + std::to_string(MAX_SPHERES) + " spheres are supported, the scene has " +
                                std::to_string(p.spheres.size()));
  s.sphere_count = int(p.spheres.size());
  for (std::size_t q = 0; q < p.spheres.size(); ++q)
    s.spheres[q] = {vec3_cast<Real>(p.spheres[q].center), Real(p.spheres[q].radius)};
  s.nx = m.nx;
  s.ny = m.ny;
  s.nz = m.nz;
  s.node_count = m.node_count();
  return s;
}

// The grid stencil with each entry's spring constants (empty for a general model).
template <class Real>
std::vector<typename Physics<Real>::StencilEntry> stencil_entries(const Model& m) {
  std::vector<typename Physics<Real>::StencilEntry> out;
  if (!m.grid()) return out;
  for (int e = 0; e < grid_stencil_size(m.volume()); ++e) {
    const GridOffset o = grid_offset(m.volume(), e);
    out.push_back({o.di, o.dj, o.dk, Real(grid_rest_length(m, o)), Real(m.stiffness[o.kind]), Real(m.damping[o.kind]), 0, 0});
  }
  return out;
}

}  // namespace deformlab
