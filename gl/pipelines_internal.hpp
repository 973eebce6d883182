// The GL pipelines' factories (registered by pipelines.cpp, used directly by tests and bench).
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "core/pipeline.hpp"
#include "gl_pipeline.hpp"

namespace deformlab::gl {

// Their node buffers from `cuda` with option memory=cuda (and by default where it is available),
// else GL's own.
std::unique_ptr<Pipeline> make_tf_pipeline(const PipelineSetup& s, const CudaMemory& cuda = {});
std::unique_ptr<Pipeline> make_compute_pipeline(const PipelineSetup& s, const CudaMemory& cuda = {});
// The same passes reading each node's acceleration from buffers allocated by `shared` and
// written by an outside force stage (the update passes of the hybrid pipelines); their own
// buffers (the Runge-Kutta slopes) from `cuda` where available.
std::unique_ptr<GlPipeline> make_tf_update(const PipelineSetup& s, SharedAllocator shared, const CudaMemory& cuda = {});
std::unique_ptr<GlPipeline> make_compute_update(const PipelineSetup& s, SharedAllocator shared,
                                                const CudaMemory& cuda = {});

// The compute passes' dispatch: `groups` work groups as x by y, x at most `max_x` (a driver
// may allow only the spec's 65535), y as small as possible, x * y - groups < y.
std::array<std::uint32_t, 2> dispatch_shape(std::int64_t groups, std::int64_t max_x);

// glsl-compute's work group on grids: a warp wide (coalesced rows) and 8 rows tall, 256
// invocations reading 12 rows' worth of cache lines instead of 5 per row of 256; and the
// defines that give it to a shader (TILE_X, TILE_Y).
inline constexpr int kComputeTileX = 32, kComputeTileY = 8;
std::string compute_tile_defines();

// The grid stencil for the shaders as defines (core/grid_stencil.hpp's table): STENCIL_SIZE,
// STENCIL_VOLUME (true for a lattice's) and STENCIL_OFFSETS.
std::string stencil_defines(bool volume);

}  // namespace deformlab::gl
