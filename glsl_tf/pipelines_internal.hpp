// The GL pipelines' factories (registered by pipelines.cpp, used directly by tests and bench).
#pragma once
#include <memory>

#include "core/pipeline.hpp"

namespace deformlab::gl {

std::unique_ptr<Pipeline> make_tf_pipeline(const PipelineSetup& s);
std::unique_ptr<Pipeline> make_compute_pipeline(const PipelineSetup& s);

}  // namespace deformlab::gl
