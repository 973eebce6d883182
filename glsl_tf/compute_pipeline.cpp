// glsl-compute: the same passes as glsl-tf, as compute shaders over storage buffers.
#include "gl_pipeline.hpp"
#include "pipelines_internal.hpp"

namespace deformlab::gl {
namespace {

class ComputePipeline final : public GlPipeline {
 public:
  ComputePipeline(const PipelineSetup& s, ExternalForces* forces)
      : GlPipeline(s, forces ? "hybrid-compute" : "glsl-compute", forces) {
    GLint blocks = 0;
    glGetIntegerv(GL_MAX_COMPUTE_SHADER_STORAGE_BLOCKS, &blocks);
    const int need = forces ? 12 : 11;
    if (blocks < need)
      throw std::invalid_argument(name_ + " needs " + std::to_string(need) + " storage buffers per compute shader");
    init();
  }

 private:
  Program make_program(PassKind, const std::string& defines) override {
    return gl::make_program({{GL_COMPUTE_SHADER, "step.comp"}}, defines);
  }

  void run_pass(GLuint program, const PassIO& io) override {
    const NodeBuffer* in[7] = {io.s0_x, io.s0_v, io.s0_p, io.src_x, io.src_v, io.acc_x, io.acc_v};
    for (int k = 0; k < 7; ++k) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, k, in[k]->id());
    for (int k = 0; k < io.outputs; ++k) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 7 + k, io.out[k]->id());
    if (io.forces_acc) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 11, io.forces_acc->id());
    glUseProgram(program);
    glDispatchCompute(GLuint((n_ + 255) / 256), 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    glUseProgram(0);
  }
};

}  // namespace

std::unique_ptr<Pipeline> make_compute_pipeline(const PipelineSetup& s) {
  return std::make_unique<ComputePipeline>(s, nullptr);
}

std::unique_ptr<GlPipeline> make_compute_update(const PipelineSetup& s, ExternalForces* forces) {
  return std::make_unique<ComputePipeline>(s, forces);
}

}  // namespace deformlab::gl
