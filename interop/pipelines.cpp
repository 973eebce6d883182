#include "pipelines.hpp"

#include "cuda_kernels/cuda_pipeline.hpp"
#include "gl/context.hpp"
#include "gl/gl_pipeline.hpp"
#include "hybrid.hpp"

namespace deformlab {

void add_hybrid_pipelines(PipelineRegistry& r) {
  using interop::Update;
  // Available when CUDA and GL are, with a CUDA device behind the GL context; the interop
  // mode's own needs are checked when the pipeline is made (they depend on the option).
  auto unavailable = [] { return interop::unavailable(interop::Mode::map); };
  auto unsupported = [](Integrator i) { return interop::hybrid_unsupported(i); };
  // The GL update's buffers (the states the forces read and the accelerations shared with
  // CUDA) and the CUDA force pass's springs.
  auto footprint = [](Update u) {
    return [u](const ModelSize& m, Integrator i, const PipelineOptions& o) {
      Footprint f = gl::footprint(m, i, true);
      f.device += cuda::spring_bytes(m, interop::hybrid_options(o, u).force);
      return f;
    };
  };
  auto read_options = [](Update u) {
    return [u](const PipelineOptions& o) { interop::hybrid_options(o, u); };
  };
  r.add(described("hybrid", unavailable, unsupported,
                  [](const PipelineSetup& s) {
                    return interop::make_hybrid_pipeline(s,
                                                         interop::hybrid_options(s.options, Update::transform_feedback));
                  },
                  footprint(Update::transform_feedback), read_options(Update::transform_feedback),
                  interop::hybrid_idle_option));
  r.add(described("hybrid-compute", unavailable, unsupported,
                  [](const PipelineSetup& s) {
                    return interop::make_hybrid_pipeline(s, interop::hybrid_options(s.options, Update::compute));
                  },
                  footprint(Update::compute), read_options(Update::compute), interop::hybrid_idle_option));
}

}  // namespace deformlab
