// glsl-tf: the paper's pipeline. One vertex per node; the two state sets are two VAOs
// (ping-pong); neighbours come through texture buffers over the state buffers; the new
// state is captured by transform feedback objects with the rasteriser discarded.
#include <map>

#include "gl_pipeline.hpp"
#include "pipelines_internal.hpp"

namespace deformlab::gl {
namespace {

class TfPipeline final : public GlPipeline {
 public:
  TfPipeline(const PipelineSetup& s, const SharedAllocator& shared, const CudaMemory& cuda = {})
      : GlPipeline(s, shared ? "hybrid" : "glsl-tf", shared, cuda) {
    require_texels(n_, "the node states (read by the vertex shader)");
    GLint separate = 0;
    glGetIntegerv(GL_MAX_TRANSFORM_FEEDBACK_SEPARATE_ATTRIBS, &separate);
    if (separate < 3) throw std::invalid_argument(name_ + " needs 3 separate transform feedback buffers");
    for (int k = 0; k < 2; ++k) {
      GLuint id = 0;
      glGenVertexArrays(1, &id);
      vao_[k] = VertexArray(id);
      glBindVertexArray(id);
      const GLuint attrs[2] = {x_[k].id, v_[k].id};
      for (GLuint a = 0; a < 2; ++a) {
        glBindBuffer(GL_ARRAY_BUFFER, attrs[a]);
        glVertexAttribPointer(a, 4, GL_FLOAT, GL_FALSE, 0, nullptr);
        glEnableVertexAttribArray(a);
      }
    }
    glBindVertexArray(0);
    glBindBuffer(GL_ARRAY_BUFFER, 0);
    init();
  }

 private:
  Program make_program(int outputs, const std::string& defines) override {
    const std::vector<std::string> out = {"o0", "o1", "o2"};
    return gl::make_program({{GL_VERTEX_SHADER, "step.vert"}}, defines, {out.begin(), out.begin() + outputs});
  }

  // One transform feedback object per set of output buffers, made on first use.
  GLuint feedback(const PassIO& io) {
    std::array<GLuint, 3> key{};
    for (int k = 0; k < io.outputs; ++k) key[k] = io.out[k]->id;
    auto& tfo = tfos_[key];
    if (!tfo) {
      GLuint id = 0;
      glGenTransformFeedbacks(1, &id);
      tfo = TransformFeedback(id);
      glBindTransformFeedback(GL_TRANSFORM_FEEDBACK, id);
      for (int k = 0; k < io.outputs; ++k) glBindBufferBase(GL_TRANSFORM_FEEDBACK_BUFFER, k, key[k]);
      glBindTransformFeedback(GL_TRANSFORM_FEEDBACK, 0);
    }
    return tfo.id();
  }

  void run_pass(GLuint program, const PassIO& io) override {
    const GLuint tfo = feedback(io);
    const GLuint tex[2] = {io.src_x->tex.id(), io.src_v->tex.id()};
    for (int k = 0; k < 2; ++k) {
      glActiveTexture(GL_TEXTURE0 + k);
      glBindTexture(GL_TEXTURE_BUFFER, tex[k]);
    }
    if (io.forces_acc) {
      glActiveTexture(GL_TEXTURE10);
      glBindTexture(GL_TEXTURE_BUFFER, io.forces_acc->tex.id());
    }
    glActiveTexture(GL_TEXTURE0);
    glUseProgram(program);
    glBindVertexArray(vao_[io.set].id());
    glEnable(GL_RASTERIZER_DISCARD);
    glBindTransformFeedback(GL_TRANSFORM_FEEDBACK, tfo);
    glBeginTransformFeedback(GL_POINTS);
    // Every pass covers all nodes: the count the previous pass captured, read on the GPU
    // (no query), once a pass has run since the state was uploaded.
    if (last_tfo_ && last_tfo_ != tfo)
      glDrawTransformFeedback(GL_POINTS, last_tfo_);
    else
      glDrawArrays(GL_POINTS, 0, n_);
    glEndTransformFeedback();
    glBindTransformFeedback(GL_TRANSFORM_FEEDBACK, 0);
    glDisable(GL_RASTERIZER_DISCARD);
    glBindVertexArray(0);
    glUseProgram(0);
    last_tfo_ = tfo;
  }

  void on_set_state() override { last_tfo_ = 0; }

  std::array<VertexArray, 2> vao_;
  std::map<std::array<GLuint, 3>, TransformFeedback> tfos_;
  GLuint last_tfo_ = 0;
};

}  // namespace

std::unique_ptr<Pipeline> make_tf_pipeline(const PipelineSetup& s, const CudaMemory& cuda) {
  return std::make_unique<TfPipeline>(s, nullptr, cuda);
}

std::unique_ptr<GlPipeline> make_tf_update(const PipelineSetup& s, SharedAllocator shared, const CudaMemory& cuda) {
  return std::make_unique<TfPipeline>(s, shared, cuda);
}

}  // namespace deformlab::gl
