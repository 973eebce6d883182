// The OpenGL pipelines: glsl-tf (the paper's vertex shader + transform feedback) and
// glsl-compute (compute shaders over storage buffers).
#pragma once
#include "core/pipeline.hpp"

namespace deformlab {
namespace gl {
struct CudaMemory;
}

// `cuda` gives their node buffers CUDA's memory (option memory=cuda): the interop layer's, empty
// in a build without it.
void add_gl_pipelines(PipelineRegistry& r, const gl::CudaMemory& cuda);

}  // namespace deformlab
