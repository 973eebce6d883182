// Every pipeline name deformlab knows, with the backends this build has registered; names
// whose backend is not in this build are listed as unavailable, with the reason.
#pragma once
#include <string>

#include "core/pipeline.hpp"

namespace deformlab {

const PipelineRegistry& pipelines();
// The PCI bus id of the GPU that runs `e`'s passes (a CUDA pipeline: the current CUDA device; a GL
// one: the CUDA device behind the GL context), which ClockWatch reads; empty for CPU pipelines and
// where it cannot be told (GL without a CUDA device behind it: ClockWatch then reads NVML's
// first GPU).
std::string gpu_bus_id(const PipelineEntry& e);
// Whether `e` runs its passes on a software GL rasteriser (llvmpipe): slower than the CPU
// pipelines, so `best` passes it over.
bool on_software_gl(const PipelineEntry& e);
// What option `name` of pipeline `e` takes, for `deformlab list`: the values of a choice
// ("exact|fast"), which the pipelines that read it accept (tested), or the form of a value
// ("WxH", "N", "1-8").
std::string option_values(const PipelineEntry& e, const std::string& name);
// The first pipeline of the list (PipelineKind's order) that is available here, runs `i` and
// does not run on a software rasteriser.
const PipelineEntry& best_pipeline(Integrator i);

}  // namespace deformlab
