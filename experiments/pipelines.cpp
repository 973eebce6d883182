#include "pipelines.hpp"

#include <stdexcept>

#include "core/cpu_backend.hpp"
#if DEFORMLAB_HAVE_CUDA
#include "cuda_kernels/pipelines.hpp"
#endif
#if DEFORMLAB_HAVE_GL
#include "gl/pipelines.hpp"
#endif
#if DEFORMLAB_HAVE_INTEROP
#include "interop/pipelines.hpp"
#endif

namespace deformlab {
namespace {

struct Known {
  const char* name;
  const char* summary;
  const char* needs;  // why it may be missing from a build
};

// In order of expected speed on a GPU machine; the CPU pipelines close the list.
const Known kKnown[] = {
    {"cuda-fused", "CUDA, force and update in one kernel", "CUDA"},
    {"cuda-tiled", "CUDA, shared-memory tiled gather", "CUDA"},
    {"cuda-naive", "CUDA, one thread per node gathering from global memory", "CUDA"},
    {"cuda-scatter", "CUDA, one thread per spring, atomic scatter", "CUDA"},
    {"glsl-compute", "GLSL compute shaders over storage buffers", "OpenGL"},
    {"glsl-tf", "GLSL vertex shader + transform feedback (the paper's)", "OpenGL"},
    {"hybrid", "CUDA forces into GL buffers, transform feedback update", "CUDA and OpenGL"},
    {"hybrid-compute", "CUDA forces into GL buffers, compute-shader update", "CUDA and OpenGL"},
    {"omp", "", ""},
    {"cpu", "", ""},
    {"reference", "", ""},
};

PipelineRegistry build() {
  PipelineRegistry built;
  add_cpu_pipelines(built);
#if DEFORMLAB_HAVE_CUDA
  add_cuda_pipelines(built);
#endif
#if DEFORMLAB_HAVE_GL
  add_gl_pipelines(built);
#endif
#if DEFORMLAB_HAVE_INTEROP
  add_hybrid_pipelines(built);
#endif
  PipelineRegistry r;
  for (const auto& k : kKnown) {
    if (const PipelineEntry* e = built.find(k.name)) {
      r.add(*e);
      continue;
    }
    const std::string why = std::string("not in this build (needs ") + k.needs + " support at configure time)";
    r.add({k.name, k.summary, true, [why] { return why; }, [why](Integrator) { return why; },
           [why](const PipelineSetup&) -> std::unique_ptr<Pipeline> { throw std::invalid_argument(why); }});
  }
  for (const auto& e : built.all())
    if (!r.find(e.name)) r.add(e);
  return r;
}

}  // namespace

const PipelineRegistry& pipelines() {
  static const PipelineRegistry r = build();
  return r;
}

const PipelineEntry& best_pipeline(Integrator i) {
  for (const auto& e : pipelines().all())
    if (e.unavailable().empty() && e.unsupported(i).empty()) return e;
  throw std::logic_error("no pipeline runs this integrator");
}

}  // namespace deformlab
