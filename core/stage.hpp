// The two kinds of pass a step is made of, as every backend implements them over the slots
// of the integrator's schedule (core/integrator.hpp): state slot 0 is the current state,
// 1.. the stage states; acceleration slot j holds the force pass at state j.
//   cpu, omp, reference: core/cpu_backend.cpp    cuda-*: cuda_kernels/cuda_pipeline.cu
//   glsl-*: gl/gl_pipeline.cpp                   hybrid-*: interop/hybrid_pipeline.cpp
#pragma once
#include "integrator.hpp"

namespace deformlab {

class ForceStage {
 public:
  virtual ~ForceStage() = default;
  // accel[acc] = a(state[src], t): springs, fields and the drag spring at time t.
  virtual void forces(int src, int acc, double t) = 0;
};

class UpdateStage {
 public:
  virtual ~UpdateStage() = default;
  // A combine, update or solve pass (Pass::Op); the one forming the result applies the constraints.
  virtual void update(const Pass& pass) = 0;
};

// One step's passes in the schedule's order: force passes on `f` at t + time_fraction dt,
// the others on `u`.
void run_passes(const Schedule& s, double t, double dt, ForceStage& f, UpdateStage& u);

}  // namespace deformlab
