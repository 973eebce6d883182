// The OpenGL pipelines: glsl-tf (the paper's vertex shader + transform feedback) and
// glsl-compute (compute shaders over storage buffers).
#pragma once
#include "core/pipeline.hpp"

namespace deformlab {

void add_gl_pipelines(PipelineRegistry& r);

}  // namespace deformlab
