#include "pipelines.hpp"

#include "context.hpp"
#include "gl_pipeline.hpp"
#include "pipelines_internal.hpp"

namespace deformlab {

void add_gl_pipelines(PipelineRegistry& r, const gl::CudaMemory& cuda) {
  auto unavailable = [] { return gl::unavailable_reason(); };
  auto unsupported = [](Integrator i) {
    return i == Integrator::backward_euler
               ? std::string("backward-euler needs a linear solve per step, which the GL pipelines do not have (use "
                             "cpu, omp or reference)")
               : std::string();
  };
  // Deterministic, and equal to the CPU within rounding (the GPU's arithmetic differs).
  auto on = [](Engine e) { return PipelineTraits{e, e, true, CpuMatch::rounding}; };
  auto footprint = [](const ModelSize& m, Integrator i, const PipelineOptions&) {
    Footprint f = gl::footprint(m, i, false);
    if (gl::context_created() && gl::context().software) f = {f.host + f.device, 0};  // its buffers are host memory
    return f;
  };
  // "window": nodes per storage-buffer window (gl/gl_pipeline.hpp, node_windows); "link_view":
  // links per texture-buffer view of a mesh's adjacency; "math": exact or fast; "memory": gl or cuda.
  r.add({"glsl-compute", "GLSL compute shaders over storage buffers", on(Engine::gl_compute), unavailable,
         unsupported, [cuda](const PipelineSetup& s) { return gl::make_compute_pipeline(s, cuda); },
         {"window", "link_view", "math", "memory"}, footprint, gl::read_options});
  r.add({"glsl-tf", "GLSL vertex shader + transform feedback (the paper's)", on(Engine::gl_transform_feedback),
         unavailable, unsupported, [cuda](const PipelineSetup& s) { return gl::make_tf_pipeline(s, cuda); },
         {"link_view", "math", "memory"}, footprint, gl::read_options});
}

}  // namespace deformlab
