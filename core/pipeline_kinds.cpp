#include <omp.h>

#include <stdexcept>

#include "cpu_backend.hpp"
#include "pipeline.hpp"

namespace deformlab {
namespace {

PipelineTraits on(Engine e, CpuMatch m = CpuMatch::rounding) { return {e, e, true, m}; }
// CUDA forces, a GL update: equal to the CPU within rounding.
PipelineTraits hybrid(Engine update) { return {Engine::cuda, update, true, CpuMatch::rounding}; }

// In order of the step times measured at 2048^2 (Table 2 and the cuda-fused and cuda-temporal
// benches on an H100: cuda-temporal is slower than cuda-fused, faster than the other gathers);
// the CPU pipelines close the list. The CUDA gathers give the CPU's bits (tests/cuda), the
// scatter's atomics add a node's forces in any order; the GL pipelines are deterministic and
// equal to the CPU within rounding (the GPU's arithmetic differs).
std::vector<PipelineKind> make_kinds() {
  const PipelineTraits gather = on(Engine::cuda, CpuMatch::bitwise);
  PipelineTraits grids_gather = gather;
  grids_gather.grids_only = true;
  const std::string omp = "OpenMP float, up to " + std::to_string(omp_get_max_threads()) + " threads of at least " +
                          std::to_string(kNodesPerThread) +
                          " nodes each (the paper's optimised CPU); bitwise equal to cpu";
  // Options: "tile", the thread block WxH of the CUDA grid kernels (on cuda-temporal the nodes
  // a block writes, with "steps_per_launch"); "tma" (on|off); "math" (exact|fast); "window",
  // nodes per storage-buffer window; "link_view", links per texture-buffer view of a mesh's
  // adjacency; "memory" (gl|cuda); "interop" and "force", the hybrids' hand-off and force pass.
  return {
      {"cuda-fused", "CUDA, force + update + constraints in one kernel (one-pass integrators; others use the plain gather)",
       "CUDA", gather, {"tile", "tma", "math"}},
      {"cuda-temporal",
       "CUDA, k fused steps per launch on shared-memory tiles with a 2k-node halo (grids; one-pass integrators)", "CUDA",
       grids_gather, {"tile", "steps_per_launch", "math"}},
      {"cuda-naive", "CUDA, one thread per node gathering its springs from global memory", "CUDA", gather,
       {"tile", "math"}},
      {"cuda-tiled",
       "CUDA, gather from shared-memory tiles (grids: the block with a 2-node halo; meshes: Z-order tiles with their "
       "halos)",
       "CUDA", gather, {"tile", "math"}},
      {"glsl-compute", "GLSL compute shaders over storage buffers", "OpenGL", on(Engine::gl_compute),
       {"window", "link_view", "math", "memory"}},
      {"hybrid-compute", "CUDA forces into GL buffers, compute-shader update", "CUDA and OpenGL",
       hybrid(Engine::gl_compute), {"interop", "force", "tile", "math"}},
      {"cuda-scatter", "CUDA, one thread per spring, atomic scatter of +f/-f", "CUDA",
       {Engine::cuda, Engine::cuda, false, CpuMatch::rounding}, {"math"}},
      {"glsl-tf", "GLSL vertex shader + transform feedback (the paper's)", "OpenGL", on(Engine::gl_transform_feedback),
       {"link_view", "math", "memory"}},
      {"hybrid", "CUDA forces into GL buffers, transform feedback update", "CUDA and OpenGL",
       hybrid(Engine::gl_transform_feedback), {"interop", "force", "tile", "math"}},
      {"omp", omp, "", {}, {}},
      {"cpu", "single-threaded float (the paper's unoptimised CPU)", "", {}, {}},
      {"reference", "OpenMP double: the reference for tests and --compare", "", {.cpu_match = CpuMatch::rounding}, {}},
  };
}

}  // namespace

const std::vector<PipelineKind>& pipeline_kinds() {
  static const std::vector<PipelineKind> kinds = make_kinds();
  return kinds;
}

const PipelineKind& pipeline_kind(const std::string& name) {
  for (const PipelineKind& k : pipeline_kinds())
    if (k.name == name) return k;
  throw std::logic_error("no pipeline kind " + name);
}

PipelineEntry described(const std::string& name, std::function<std::string()> unavailable,
                        std::function<std::string(Integrator)> unsupported,
                        std::function<std::unique_ptr<Pipeline>(const PipelineSetup&)> make,
                        std::function<Footprint(const ModelSize&, Integrator, const PipelineOptions&)> footprint,
                        std::function<void(const PipelineOptions&)> read_options,
                        std::function<std::string(const PipelineOptions&, Topology)> idle_option) {
  const PipelineKind& k = pipeline_kind(name);
  return {k.name,    k.summary,           k.traits,  std::move(unavailable), std::move(unsupported), std::move(make),
          k.options, std::move(footprint), std::move(read_options), std::move(idle_option)};
}

}  // namespace deformlab
