// The CUDA pipelines as built for each math mode (core/pipeline.hpp, Math): cuda_pipeline.cu
// compiled twice, with nvcc's exact and fast arithmetic. Callers go through make_pipeline and
// make_force_pass (cuda_pipeline.hpp, force_pass.hpp), which pick the build.
#pragma once
#include <memory>

#include "force_pass.hpp"

namespace deformlab::cuda {
namespace exact {
std::unique_ptr<CudaPipeline> make_pipeline(const PipelineSetup& s, const Options& o);
std::unique_ptr<ForcePass> make_force_pass(const Model& m, const Params& p, const Options& o);
}  // namespace exact
namespace fast {
std::unique_ptr<CudaPipeline> make_pipeline(const PipelineSetup& s, const Options& o);
std::unique_ptr<ForcePass> make_force_pass(const Model& m, const Params& p, const Options& o);
}  // namespace fast
}  // namespace deformlab::cuda
