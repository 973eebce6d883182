// The CUDA pipelines' force pass on its own, over device arrays that another API may own:
// what the hybrid pipelines' force stage runs (interop/hybrid_pipeline.cpp). Plain C++:
// includable without nvcc.
#pragma once
#include <memory>

#include "cuda_pipeline.hpp"

struct float4;
struct CUstream_st;

namespace deformlab::cuda {

class ForcePass {
 public:
  virtual ~ForcePass() = default;
  // acc = a(x, v) for every node, queued on `stream`: x positions (w: inverse mass), v
  // velocities, acc accelerations; float4 arrays of the model's node count on the current
  // device. `drag_target`: the drag handle's target at the time of the forces.
  virtual void run(const float4* x, const float4* v, float4* acc, Vec3f drag_target, CUstream_st* stream) = 0;
  // The drag handle's node and mode from the next run on (checked by the caller).
  virtual void set_drag(const DragHandle& d) = 0;
};

// The naive, tiled or scatter force pass on the current device, built with `math`; throws
// std::invalid_argument for fused (not a force pass), a bad tile or a model that does not fit.
std::unique_ptr<ForcePass> make_force_pass(const Model& m, const Params& p, Variant v, Tile tile, Math math);

}  // namespace deformlab::cuda
