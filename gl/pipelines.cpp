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
  auto footprint = [](const ModelSize& m, Integrator i, const PipelineOptions&) {
    Footprint f = gl::footprint(m, i, false);
    if (gl::context_created() && gl::context().software) f = {f.host + f.device, 0};  // its buffers are host memory
    return f;
  };
  r.add(described("glsl-compute", unavailable, unsupported,
                  [cuda](const PipelineSetup& s) { return gl::make_compute_pipeline(s, cuda); }, footprint,
                  gl::read_options, gl::idle_option));
  r.add(described("glsl-tf", unavailable, unsupported,
                  [cuda](const PipelineSetup& s) { return gl::make_tf_pipeline(s, cuda); }, footprint,
                  gl::read_options, gl::idle_option));
}

}  // namespace deformlab
