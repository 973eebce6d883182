// glsl-compute: the same passes as glsl-tf, as compute shaders over storage buffers.
#include "gl_pipeline.hpp"
#include "pipelines_internal.hpp"

namespace deformlab::gl {

std::string compute_tile_defines() {
  return "#define TILE_X " + std::to_string(kComputeTileX) + "\n#define TILE_Y " + std::to_string(kComputeTileY) + "\n";
}

std::array<std::uint32_t, 2> dispatch_shape(std::int64_t groups, std::int64_t max_x) {
  const std::int64_t y = (groups + max_x - 1) / max_x, x = (groups + y - 1) / y;
  return {std::uint32_t(x), std::uint32_t(y)};
}

namespace {

class ComputePipeline final : public GlPipeline {
 public:
  ComputePipeline(const PipelineSetup& s, const SharedAllocator& shared, const CudaMemory& cuda = {})
      : GlPipeline(s, shared ? "hybrid-compute" : "glsl-compute", shared, cuda) {
    // step.comp's blocks: bindings 0-6, the stop-rule words (8), the posted word (9) and, with an
    // outside force stage, its accelerations (7).
    GLint blocks = 0, bindings = 0;
    glGetIntegerv(GL_MAX_COMPUTE_SHADER_STORAGE_BLOCKS, &blocks);
    glGetIntegerv(GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS, &bindings);
    const int need = shared ? 10 : 9;
    if (blocks < need || bindings < 10)
      throw std::invalid_argument(name_ + " needs " + std::to_string(need) +
                                  " storage buffers per compute shader and 10 storage buffer bindings");
    for (GLuint d = 0; d < 3; ++d) glGetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_COUNT, d, &max_groups_[d]);
    for (const NodeWindow& w : windows_) {
      const auto g = work_groups(w).groups;
      if (g[0] > std::uint32_t(max_groups_[0]) || g[1] > std::uint32_t(max_groups_[1]) ||
          g[2] > std::uint32_t(max_groups_[2]))
        throw std::invalid_argument(name_ + ": " + std::to_string(w.count) + " nodes need " + std::to_string(g[0]) +
                                    " x " + std::to_string(g[1]) + " x " + std::to_string(g[2]) +
                                    " work groups; this driver allows " + std::to_string(max_groups_[0]) + " x " +
                                    std::to_string(max_groups_[1]) + " x " + std::to_string(max_groups_[2]));
    }
    init();
  }

 private:
  Program make_program(int, const std::string& defines) override {
    return gl::make_program({{GL_COMPUTE_SHADER, "step.comp"}}, defines + compute_tile_defines());
  }

  // A window's work groups (step.comp): on grids tiles of kComputeTileX x kComputeTileY nodes
  // over the rows the window touches, tile rows along y then z; else 256 nodes a group along x
  // then y.
  struct WorkGroups {
    std::array<std::uint32_t, 3> groups;
    int first_row;
  };
  WorkGroups work_groups(const NodeWindow& w) const {
    if (!model().grid()) {
      const auto xy = dispatch_shape((std::int64_t(w.count) + 255) / 256, max_groups_[0]);
      return {{xy[0], xy[1], 1}, 0};
    }
    const int first_row = w.first / model().nx, rows = (w.first + w.count - 1) / model().nx - first_row + 1;
    const auto yz = dispatch_shape((rows + kComputeTileY - 1) / kComputeTileY, max_groups_[1]);
    return {{std::uint32_t((model().nx + kComputeTileX - 1) / kComputeTileX), yz[0], yz[1]}, first_row};
  }

  // Window by window (node_windows): the inputs bound over the nodes the window reads, the
  // outputs over the nodes it writes; step.comp offsets its indices by both.
  void run_pass(GLuint program, const PassIO& io) override {
    const NodeBuffer* in[4] = {io.s0_x, io.s0_v, io.src_x, io.src_v};
    glUseProgram(program);
    if (io.result_max) {
      glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 8, io.result_max);
      glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 9, io.posted);
      glUniform1i(kResultWord, io.result_word);
      glUniform1ui(kLaunch, io.launch);
    }
    for (const NodeWindow& w : windows_) {
      for (int k = 0; k < 4; ++k) bind_nodes(GLuint(k), *in[k], w.read_first, w.read_count);
      for (int k = 0; k < io.outputs; ++k) bind_nodes(GLuint(4 + k), *io.out[k], w.first, w.count);
      if (io.forces_acc) bind_nodes(7, *io.forces_acc, w.read_first, w.read_count);
      glUniform1i(kFirst, w.first);
      glUniform1i(kCount, w.count);
      glUniform1i(kReadFirst, w.read_first);
      const WorkGroups g = work_groups(w);
      glUniform1i(kFirstRow, g.first_row);
      glDispatchCompute(g.groups[0], g.groups[1], g.groups[2]);
    }
    // Later passes read this one's outputs as storage buffers and (earlier stages) as textures,
    // a displacement read with no step after it copies the result pass's word.
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                    (io.result_max ? GL_BUFFER_UPDATE_BARRIER_BIT : 0));
    glUseProgram(0);
  }

  // The result pass reduced its terms into the word (run_pass's barrier makes it visible), and
  // the next one posts it.
  void reduce_displacement() override {}
  bool posts_words() const override { return true; }

  // Uniform locations in step.comp.
  static constexpr GLint kFirst = 0, kCount = 1, kReadFirst = 2, kFirstRow = 3, kResultWord = 4, kLaunch = 5;
  std::array<GLint, 3> max_groups_{};  // work groups along x, y, z
};

}  // namespace

std::unique_ptr<Pipeline> make_compute_pipeline(const PipelineSetup& s, const CudaMemory& cuda) {
  return std::make_unique<ComputePipeline>(s, nullptr, cuda);
}

std::unique_ptr<GlPipeline> make_compute_update(const PipelineSetup& s, SharedAllocator shared,
                                                const CudaMemory& cuda) {
  return std::make_unique<ComputePipeline>(s, shared, cuda);
}

}  // namespace deformlab::gl
