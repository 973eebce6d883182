// glsl-compute: the same passes as glsl-tf, as compute shaders over storage buffers.
#include "gl_pipeline.hpp"
#include "pipelines_internal.hpp"

namespace deformlab::gl {

std::array<std::uint32_t, 2> dispatch_shape(std::int64_t groups, std::int64_t max_x) {
  const std::int64_t y = (groups + max_x - 1) / max_x, x = (groups + y - 1) / y;
  return {std::uint32_t(x), std::uint32_t(y)};
}

namespace {

class ComputePipeline final : public GlPipeline {
 public:
  ComputePipeline(const PipelineSetup& s, const SharedAllocator& shared)
      : GlPipeline(s, shared ? "hybrid-compute" : "glsl-compute", shared) {
    GLint blocks = 0;
    glGetIntegerv(GL_MAX_COMPUTE_SHADER_STORAGE_BLOCKS, &blocks);
    const int need = shared ? 10 : 9;
    if (blocks < need)
      throw std::invalid_argument(name_ + " needs " + std::to_string(need) + " storage buffers per compute shader");
    glGetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_COUNT, 0, &max_x_);
    GLint max_y = 0;
    glGetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_COUNT, 1, &max_y);
    for (const NodeWindow& w : windows_)
      if (dispatch_shape((std::int64_t(w.count) + 255) / 256, max_x_)[1] > std::uint32_t(max_y))
        throw std::invalid_argument(name_ + ": " + std::to_string(w.count) + " nodes need more work groups than " +
                                    "this driver's " + std::to_string(max_x_) + " x " + std::to_string(max_y));
    init();
  }

 private:
  Program make_program(int, const std::string& defines) override {
    return gl::make_program({{GL_COMPUTE_SHADER, "step.comp"}}, defines);
  }

  // Window by window (node_windows): the inputs bound over the nodes the window reads, the
  // outputs over the nodes it writes; step.comp offsets its indices by both.
  void run_pass(GLuint program, const PassIO& io) override {
    const NodeBuffer* in[5] = {io.s0_x, io.s0_v, io.s0_p, io.src_x, io.src_v};
    glUseProgram(program);
    if (io.result) {
      const std::uint32_t zero = 0;
      glClearNamedBufferSubData(io.result_max, GL_R32UI, 0, 4, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
      glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 9, io.result_max);
    }
    for (const NodeWindow& w : windows_) {
      for (int k = 0; k < 5; ++k)
        if (in[k]->id()) bind_nodes(GLuint(k), *in[k], w.read_first, w.read_count);
      for (int k = 0; k < io.outputs; ++k) bind_nodes(GLuint(5 + k), *io.out[k], w.first, w.count);
      if (io.forces_acc) bind_nodes(8, *io.forces_acc, w.read_first, w.read_count);
      glUniform1i(kFirst, w.first);
      glUniform1i(kCount, w.count);
      glUniform1i(kReadFirst, w.read_first);
      const auto groups = dispatch_shape((std::int64_t(w.count) + 255) / 256, max_x_);
      glDispatchCompute(groups[0], groups[1], 1);
    }
    // Later passes read this one's outputs as storage buffers and (earlier stages) as textures.
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
    glUseProgram(0);
  }

  // The result pass reduced its terms into the word (run_pass's barrier makes it visible).
  void reduce_displacement(GLuint) override {}

  static constexpr GLint kFirst = 0, kCount = 1, kReadFirst = 2;  // uniform locations in step.comp
  GLint max_x_ = 0;  // work groups along x
};

}  // namespace

std::unique_ptr<Pipeline> make_compute_pipeline(const PipelineSetup& s) {
  return std::make_unique<ComputePipeline>(s, nullptr);
}

std::unique_ptr<GlPipeline> make_compute_update(const PipelineSetup& s, SharedAllocator shared) {
  return std::make_unique<ComputePipeline>(s, shared);
}

}  // namespace deformlab::gl
