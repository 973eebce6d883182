// Registers the CUDA pipelines: cuda-naive, cuda-tiled, cuda-scatter, cuda-fused.
#pragma once
#include "core/pipeline.hpp"

namespace deformlab {

void add_cuda_pipelines(PipelineRegistry& r);

}  // namespace deformlab
