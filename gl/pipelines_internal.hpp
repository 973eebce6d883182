// The GL pipelines' factories (registered by pipelines.cpp, used directly by tests and bench).
#pragma once
#include <array>
#include <cstdint>
#include <memory>

#include "core/pipeline.hpp"
#include "gl_pipeline.hpp"

namespace deformlab::gl {

std::unique_ptr<Pipeline> make_tf_pipeline(const PipelineSetup& s);
std::unique_ptr<Pipeline> make_compute_pipeline(const PipelineSetup& s);
// The same passes reading each node's acceleration from buffers allocated by `shared` and
// written by an outside force stage (the update passes of the hybrid pipelines).
std::unique_ptr<GlPipeline> make_tf_update(const PipelineSetup& s, SharedAllocator shared);
std::unique_ptr<GlPipeline> make_compute_update(const PipelineSetup& s, SharedAllocator shared);

// The compute passes' dispatch: `groups` work groups as x by y, x at most `max_x` (a driver
// may allow only the spec's 65535), y as small as possible, x * y - groups < y.
std::array<std::uint32_t, 2> dispatch_shape(std::int64_t groups, std::int64_t max_x);

}  // namespace deformlab::gl
