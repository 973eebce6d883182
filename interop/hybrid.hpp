// The hybrid pipelines: a CUDA force pass writes each node's acceleration into a buffer
// shared with GL; a GL update pass (transform feedback or compute shader) integrates and
// applies the constraints, ping-ponging as glsl-tf does. Multi-evaluation integrators
// alternate CUDA force passes and GL update passes: two hand-offs per force pass.
#pragma once
#include <memory>
#include <optional>

#include "core/pipeline.hpp"
#include "cuda_kernels/cuda_pipeline.hpp"
#include "shared_buffers.hpp"

namespace deformlab::interop {

enum class Update { transform_feedback, compute };

struct HybridOptions {
  Update update = Update::transform_feedback;
  std::optional<Mode> mode;                     // none given: default_mode()
  cuda::Variant force = cuda::Variant::naive;  // naive, tiled or scatter
  cuda::Tile tile;                              // thread block of the grid force kernels (0 x 0: default)
  Math math = Math::exact;                      // the CUDA force pass's and the GL update's arithmetic
};

// The interop mode the hybrids run when none is given: external-gpusync where this machine has it,
// else map. Its buffers come from CUDA's allocator: on unordered meshes the force kernels' gathers
// take 1.8-4.1x as long on GL's buffers (map), and its hand-offs are the cheapest (docs/meshes.md).
Mode default_mode();
// Reads the pipeline options `interop`, `force`, `tile` and `math` (throws std::invalid_argument on a
// bad value).
HybridOptions hybrid_options(const PipelineOptions& o, Update u);
// Empty when the integrator runs on the hybrid pipelines, else why not.
std::string hybrid_unsupported(Integrator i);
// Why an option of `o` would do nothing on a model of topology t (a tile where the force pass
// takes none), else empty.
std::string hybrid_idle_option(const PipelineOptions& o, Topology t);
// Throws std::invalid_argument naming what is missing (CUDA, GL, the interop mode's needs).
std::unique_ptr<Pipeline> make_hybrid_pipeline(const PipelineSetup& s, const HybridOptions& o);

}  // namespace deformlab::interop
