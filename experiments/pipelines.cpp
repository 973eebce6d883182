#include "pipelines.hpp"

#include <map>
#include <stdexcept>

#include "core/cpu_backend.hpp"
#if DEFORMLAB_HAVE_CUDA
#include "cuda_kernels/cuda_pipeline.hpp"
#include "cuda_kernels/pipelines.hpp"
#endif
#if DEFORMLAB_HAVE_GL
#include "gl/context.hpp"
#include "gl/gl_pipeline.hpp"
#include "gl/pipelines.hpp"
#endif
#if DEFORMLAB_HAVE_INTEROP
#include "interop/pipelines.hpp"
#include "interop/shared_buffers.hpp"
#endif

namespace deformlab {
namespace {

// Each pipeline as every build knows it: its traits and options are checked against the
// registered entry where the build has it, and carried by the placeholder where not.
struct Known {
  const char* name;
  const char* summary;
  const char* needs;  // why it may be missing from a build
  PipelineTraits traits;
  std::vector<std::string> options = {};
};

constexpr PipelineTraits on(Engine e, bool deterministic = true, CpuMatch m = CpuMatch::rounding) {
  return {e, e, deterministic, m};
}
constexpr PipelineTraits hybrid(Engine update) { return {Engine::cuda, update, true, CpuMatch::rounding}; }

// In order of expected speed on a GPU machine (cuda-temporal, faster on grids, follows
// cuda-fused, which runs every model); the CPU pipelines close the list.
const Known kKnown[] = {
    {"cuda-fused", "CUDA, force and update in one kernel", "CUDA", on(Engine::cuda, true, CpuMatch::bitwise),
     {"tile", "tma", "math"}},
    {"cuda-temporal", "CUDA, k fused steps per launch on shared-memory tiles (grids)", "CUDA",
     {Engine::cuda, Engine::cuda, true, CpuMatch::bitwise, true}, {"tile", "steps_per_launch", "math"}},
    {"cuda-tiled", "CUDA, shared-memory tiled gather", "CUDA", on(Engine::cuda, true, CpuMatch::bitwise), {"tile", "math"}},
    {"cuda-naive", "CUDA, one thread per node gathering from global memory", "CUDA",
     on(Engine::cuda, true, CpuMatch::bitwise), {"tile", "math"}},
    {"cuda-scatter", "CUDA, one thread per spring, atomic scatter", "CUDA", on(Engine::cuda, false), {"math"}},
    {"glsl-compute", "GLSL compute shaders over storage buffers", "OpenGL", on(Engine::gl_compute),
     {"window", "link_view", "math", "memory"}},
    {"glsl-tf", "GLSL vertex shader + transform feedback (the paper's)", "OpenGL", on(Engine::gl_transform_feedback),
     {"link_view", "math", "memory"}},
    {"hybrid", "CUDA forces into GL buffers, transform feedback update", "CUDA and OpenGL",
     hybrid(Engine::gl_transform_feedback), {"interop", "force", "tile", "math"}},
    {"hybrid-compute", "CUDA forces into GL buffers, compute-shader update", "CUDA and OpenGL",
     hybrid(Engine::gl_compute), {"interop", "force", "tile", "math"}},
    {"omp", "", "", {}},
    {"cpu", "", "", {}},
    {"reference", "", "", {.cpu_match = CpuMatch::rounding}},
};

PipelineRegistry build() {
  PipelineRegistry built;
  add_cpu_pipelines(built);
#if DEFORMLAB_HAVE_CUDA
  add_cuda_pipelines(built);
#endif
#if DEFORMLAB_HAVE_GL
#if DEFORMLAB_HAVE_INTEROP
  add_gl_pipelines(built, interop::cuda_memory());
#else
  add_gl_pipelines(built, {});
#endif
#endif
#if DEFORMLAB_HAVE_INTEROP
  add_hybrid_pipelines(built);
#endif
  PipelineRegistry r;
  for (const auto& k : kKnown) {
    if (const PipelineEntry* e = built.find(k.name)) {
      if (!(e->traits == k.traits) || e->options != k.options)
        throw std::logic_error(std::string("pipeline ") + k.name + " registers other traits or options than kKnown's");
      r.add(*e);
      continue;
    }
    const std::string why = std::string("not in this build (needs ") + k.needs + " support at configure time)";
    r.add({k.name, k.summary, k.traits, [why] { return why; }, [why](Integrator) { return why; },
           [why](const PipelineSetup&) -> std::unique_ptr<Pipeline> { throw std::invalid_argument(why); },
           k.options});
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

std::string gpu_bus_id(const PipelineEntry& e) {
  (void)e;
#if DEFORMLAB_HAVE_INTEROP
  if (e.traits.update == Engine::gl_compute || e.traits.update == Engine::gl_transform_feedback) {
    try {
      return cuda::device_info(interop::cuda_device_of_gl()).pci_bus_id;
    } catch (const std::invalid_argument&) {  // no CUDA device behind the context (software GL)
      return {};
    }
  }
#endif
#if DEFORMLAB_HAVE_CUDA
  if (e.traits.force == Engine::cuda) return cuda::device_info().pci_bus_id;
#endif
  return {};
}

std::string option_values(const PipelineEntry& e, const std::string& name) {
  if (name == "tile" && e.name == "cuda-temporal") return "WxH or WxHxD";  // WxHxD on lattices
  static const std::map<std::string, std::string> values = {
      {"tile", "WxH"},     {"tma", "on|off"},    {"math", "exact|fast"},
      {"window", "N"},     {"link_view", "N"},   {"steps_per_launch", "1-8"},
      {"memory", "gl|cuda"}, {"force", "naive|tiled|scatter"},
      {"interop", "map|external|external-gpusync|staged"}};
  const auto v = values.find(name);
  return v == values.end() ? "VALUE" : v->second;
}

bool on_software_gl(const PipelineEntry& e) {
#if DEFORMLAB_HAVE_GL
  const bool gl = is_gl(e.traits.force) || is_gl(e.traits.update);
  return gl && e.unavailable().empty() && gl::context().software;
#else
  (void)e;
  return false;
#endif
}

const PipelineEntry& best_pipeline(Integrator i) {
  for (const auto& e : pipelines().all())
    if (e.unavailable().empty() && e.unsupported(i).empty() && !on_software_gl(e)) return e;
  throw std::logic_error("no pipeline runs this integrator");
}

}  // namespace deformlab
