#include "objects.hpp"

#include <algorithm>
#include <sstream>
#include <stdexcept>

namespace deformlab::gl {

void delete_buffer(GLuint id) { glDeleteBuffers(1, &id); }
void delete_texture(GLuint id) { glDeleteTextures(1, &id); }
void delete_vertex_array(GLuint id) { glDeleteVertexArrays(1, &id); }
void delete_transform_feedback(GLuint id) { glDeleteTransformFeedbacks(1, &id); }
void delete_framebuffer(GLuint id) { glDeleteFramebuffers(1, &id); }
void delete_renderbuffer(GLuint id) { glDeleteRenderbuffers(1, &id); }
void delete_program(GLuint id) { glDeleteProgram(id); }

// Immutable storage: no buffer is re-specified or mapped; the host writes with
// glNamedBufferSubData, the GPU with its passes. Storage takes at least one byte.
Buffer make_buffer(std::size_t bytes, const void* data) {
  GLuint id = 0;
  glCreateBuffers(1, &id);
  glNamedBufferStorage(id, GLsizeiptr(std::max<std::size_t>(bytes, 1)), bytes > 0 ? data : nullptr,
                       GL_DYNAMIC_STORAGE_BIT);
  Buffer b(id);
  check("allocating a buffer of " + std::to_string(bytes) + " bytes");
  return b;
}

Texture make_texture_buffer(GLuint buffer, GLenum format, std::int64_t offset, std::int64_t bytes) {
  GLuint id = 0;
  glGenTextures(1, &id);
  glBindTexture(GL_TEXTURE_BUFFER, id);
  if (bytes < 0) glTexBuffer(GL_TEXTURE_BUFFER, format, buffer);
  else glTexBufferRange(GL_TEXTURE_BUFFER, format, buffer, GLintptr(offset), GLsizeiptr(bytes));
  glBindTexture(GL_TEXTURE_BUFFER, 0);
  return Texture(id);
}

void read_buffer(GLuint buffer, std::size_t offset, std::size_t bytes, void* out) {
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glBindBuffer(GL_COPY_READ_BUFFER, buffer);
  glGetBufferSubData(GL_COPY_READ_BUFFER, GLintptr(offset), GLsizeiptr(bytes), out);
  glBindBuffer(GL_COPY_READ_BUFFER, 0);
  check("reading a buffer back");
}

namespace {

// `#include "x"` lines replaced by file x, each file's lines numbered as its own source
// string (#line N S) so that driver logs point into the right file.
std::string expand(const std::string& text, std::vector<std::string>& names) {
  const int self = int(names.size()) - 1;
  std::istringstream in(text);
  std::string out, line;
  for (int n = 1; std::getline(in, line); ++n) {
    const auto q0 = line.find('"');
    if (line.rfind("#include", 0) == 0 && q0 != std::string::npos) {
      const std::string inc = line.substr(q0 + 1, line.find('"', q0 + 1) - q0 - 1);
      names.push_back(inc);
      out += "#line 1 " + std::to_string(names.size() - 1) + "\n" + expand(shader_file(inc), names);
      out += "#line " + std::to_string(n + 1) + " " + std::to_string(self) + "\n";
    } else {
      out += line + "\n";
    }
  }
  return out;
}

// The defines go right after the #version line, which must stay first.
std::string assemble(const std::string& file, const std::string& defines, std::vector<std::string>& names) {
  names = {file};
  const std::string text = expand(shader_file(file), names);
  const auto eol = text.find('\n');
  return text.substr(0, eol + 1) + defines + "#line 2 0\n" + text.substr(eol + 1);
}

std::string source_names(const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t k = 0; k < names.size(); ++k) s += (k ? ", " : "") + std::to_string(k) + " = " + names[k];
  return s;
}

GLuint compile(GLenum type, const std::string& name, const std::string& source, const std::string& map) {
  const GLuint sh = glCreateShader(type);
  const char* src = source.c_str();
  glShaderSource(sh, 1, &src, nullptr);
  glCompileShader(sh);
  GLint ok = 0, len = 0;
  glGetShaderiv(sh, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    glGetShaderiv(sh, GL_INFO_LOG_LENGTH, &len);
    std::string log(std::size_t(std::max(len, 1)), '\0');
    glGetShaderInfoLog(sh, len, nullptr, log.data());
    glDeleteShader(sh);
    throw std::runtime_error("shader " + name + " failed to compile (sources: " + map + "):\n" + log.c_str());
  }
  return sh;
}

Program link(const std::vector<GLuint>& shaders, const std::string& name, const std::vector<std::string>& varyings) {
  Program p(glCreateProgram());
  for (GLuint s : shaders) glAttachShader(p.id(), s);
  if (!varyings.empty()) {
    std::vector<const char*> v;
    for (const auto& s : varyings) v.push_back(s.c_str());
    glTransformFeedbackVaryings(p.id(), GLsizei(v.size()), v.data(), GL_SEPARATE_ATTRIBS);
  }
  glLinkProgram(p.id());
  for (GLuint s : shaders) glDeleteShader(s);
  GLint ok = 0, len = 0;
  glGetProgramiv(p.id(), GL_LINK_STATUS, &ok);
  if (!ok) {
    glGetProgramiv(p.id(), GL_INFO_LOG_LENGTH, &len);
    std::string log(std::size_t(std::max(len, 1)), '\0');
    glGetProgramInfoLog(p.id(), len, nullptr, log.data());
    throw std::runtime_error("program " + name + " failed to link:\n" + log.c_str());
  }
  check("building program " + name);
  return p;
}

}  // namespace

Program make_program(const std::vector<ShaderStage>& stages, const std::string& defines,
                     const std::vector<std::string>& varyings) {
  std::vector<GLuint> shaders;
  std::string name;
  try {
    for (const auto& st : stages) {
      std::vector<std::string> names;
      const std::string src = assemble(st.file, defines, names);
      name += (name.empty() ? "" : "+") + st.file;
      shaders.push_back(compile(st.type, st.file, src, source_names(names)));
    }
  } catch (...) {
    for (GLuint s : shaders) glDeleteShader(s);
    throw;
  }
  return link(shaders, name, varyings);
}

Program make_program_from_source(GLenum type, const std::string& name, const std::string& source) {
  return link({compile(type, name, source, "0 = " + name)}, name, {});
}

GLint uniform(GLuint program, const char* name) { return glGetUniformLocation(program, name); }

}  // namespace deformlab::gl
