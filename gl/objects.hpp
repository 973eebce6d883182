// Owning wrappers for GL objects (moved, never copied), plus programs built from the
// embedded shaders with their compile and link logs.
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "context.hpp"

namespace deformlab::gl {

template <void (*Delete)(GLuint)>
class Handle {
 public:
  Handle() = default;
  explicit Handle(GLuint id) : id_(id) {}
  ~Handle() { if (id_) Delete(id_); }
  Handle(Handle&& o) noexcept : id_(std::exchange(o.id_, 0)) {}
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) { if (id_) Delete(id_); id_ = std::exchange(o.id_, 0); }
    return *this;
  }
  GLuint id() const { return id_; }
  explicit operator bool() const { return id_ != 0; }

 private:
  GLuint id_ = 0;
};

void delete_buffer(GLuint id);
void delete_texture(GLuint id);
void delete_vertex_array(GLuint id);
void delete_transform_feedback(GLuint id);
void delete_framebuffer(GLuint id);
void delete_renderbuffer(GLuint id);
void delete_program(GLuint id);

using Buffer = Handle<delete_buffer>;
using Texture = Handle<delete_texture>;
using VertexArray = Handle<delete_vertex_array>;
using TransformFeedback = Handle<delete_transform_feedback>;
using Framebuffer = Handle<delete_framebuffer>;
using Renderbuffer = Handle<delete_renderbuffer>;
using Program = Handle<delete_program>;

// A buffer of `bytes` (data may be null): immutable storage the host writes with
// glNamedBufferSubData.
Buffer make_buffer(std::size_t bytes, const void* data = nullptr);
// A texture-buffer view of `buffer` with the given texel format (GL_RGBA32F, GL_R32I, ...):
// the whole buffer, or `bytes` from `offset` (a multiple of GL_TEXTURE_BUFFER_OFFSET_ALIGNMENT).
Texture make_texture_buffer(GLuint buffer, GLenum format, std::int64_t offset = 0, std::int64_t bytes = -1);
void read_buffer(GLuint buffer, std::size_t offset, std::size_t bytes, void* out);

struct ShaderStage {
  GLenum type;       // GL_VERTEX_SHADER, GL_FRAGMENT_SHADER, GL_COMPUTE_SHADER
  std::string file;  // shader file name, e.g. "step.vert"
};
// Compiles and links the stages, each source preceded by `defines` (lines "#define ...")
// and with `#include "x"` lines replaced by file x; `varyings` are captured by transform
// feedback (separate buffers). Throws std::runtime_error with the file name and the log.
Program make_program(const std::vector<ShaderStage>& stages, const std::string& defines = "",
                     const std::vector<std::string>& varyings = {});
// Same, from source text already assembled (tests use it for broken sources).
Program make_program_from_source(GLenum type, const std::string& name, const std::string& source);

GLint uniform(GLuint program, const char* name);  // location, -1 if absent (optimised away)

}  // namespace deformlab::gl
