// Every pipeline name deformlab knows, with the backends this build has registered; names
// whose backend is not in this build are listed as unavailable, with the reason.
#pragma once
#include <string>

#include "core/pipeline.hpp"

namespace deformlab {

const PipelineRegistry& pipelines();
// The first pipeline in order of expected speed that is available here and runs `i`.
const PipelineEntry& best_pipeline(Integrator i);

}  // namespace deformlab
