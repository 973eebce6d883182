#include "pipelines.hpp"

#include "context.hpp"
#include "pipelines_internal.hpp"

namespace deformlab {

void add_gl_pipelines(PipelineRegistry& r) {
  auto unavailable = [] { return gl::unavailable_reason(); };
  auto unsupported = [](const char* name) {
    return [name](Integrator i) {
      return i == Integrator::backward_euler
                 ? std::string("not available on ") + name + " (its linear solve runs on the CPU pipelines)"
                 : std::string();
    };
  };
  r.add({"glsl-compute", "GLSL compute shaders over storage buffers", true, unavailable, unsupported("glsl-compute"),
         gl::make_compute_pipeline});
  r.add({"glsl-tf", "GLSL vertex shader + transform feedback (the paper's)", true, unavailable, unsupported("glsl-tf"),
         gl::make_tf_pipeline});
}

}  // namespace deformlab
