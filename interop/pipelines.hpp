// Registers the hybrid pipelines: hybrid (CUDA forces, transform-feedback update) and
// hybrid-compute (CUDA forces, compute-shader update). Options: interop (map, external,
// external-gpusync, staged; default map), force (naive, tiled, scatter; default naive) and
// tile (the CUDA grid kernels' block, WxH).
#pragma once
#include "core/pipeline.hpp"

namespace deformlab {

void add_hybrid_pipelines(PipelineRegistry& r);

}  // namespace deformlab
