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
  // Every kind, in its order: the build's entry, or a placeholder that says what it needs.
  PipelineRegistry r;
  for (const PipelineKind& k : pipeline_kinds()) {
    if (const PipelineEntry* e = built.find(k.name)) {
      r.add(*e);
      continue;
    }
    const std::string why = "not in this build (needs " + k.needs + " support at configure time)";
    r.add({k.name, k.summary, k.traits, [why] { return why; }, [why](Integrator) { return why; },
           [why](const PipelineSetup&) -> std::unique_ptr<Pipeline> { throw std::invalid_argument(why); },
           k.options});
  }
  for (const PipelineEntry& e : built.all())
    if (!r.find(e.name)) throw std::logic_error("pipeline " + e.name + " is registered but not a kind (core/pipeline_kinds.cpp)");
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
