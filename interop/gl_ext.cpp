#include "gl_ext.hpp"

#include <EGL/egl.h>

#include <cstring>

namespace deformlab::interop::glext {
namespace {

// Entry points each extension needs (GLEW's pointers, loaded with the context).
bool entry_points(const std::string& ext) {
  if (ext == "GL_EXT_memory_object")
    return glCreateMemoryObjectsEXT && glDeleteMemoryObjectsEXT && glNamedBufferStorageMemEXT;
  if (ext == "GL_EXT_memory_object_fd") return glImportMemoryFdEXT != nullptr;
  if (ext == "GL_EXT_semaphore")
    return glGenSemaphoresEXT && glDeleteSemaphoresEXT && glSemaphoreParameterui64vEXT && glWaitSemaphoreEXT &&
           glSignalSemaphoreEXT;
  if (ext == "GL_EXT_semaphore_fd") return glImportSemaphoreFdEXT != nullptr;
  if (ext == "GL_NV_timeline_semaphore") return timeline().create_semaphores && timeline().semaphore_parameteriv;
  return true;
}

}  // namespace

bool has(const char* extension) {
  GLint n = 0;
  glGetIntegerv(GL_NUM_EXTENSIONS, &n);
  for (GLint k = 0; k < n; ++k) {
    const auto* e = reinterpret_cast<const char*>(glGetStringi(GL_EXTENSIONS, GLuint(k)));
    if (e && std::strcmp(e, extension) == 0) return true;
  }
  return false;
}

std::string missing(const std::vector<const char*>& extensions) {
  std::string out;
  for (const char* e : extensions) {
    const char* why = !has(e) ? "" : !entry_points(e) ? " (listed, but its entry points did not load)" : nullptr;
    if (why) out += (out.empty() ? "" : ", ") + std::string(e) + why;
  }
  return out;
}

const Timeline& timeline() {
  static const Timeline t = [] {
    Timeline r;
    r.create_semaphores = reinterpret_cast<CreateSemaphoresNV>(eglGetProcAddress("glCreateSemaphoresNV"));
    r.semaphore_parameteriv =
        reinterpret_cast<SemaphoreParameterivNV>(eglGetProcAddress("glSemaphoreParameterivNV"));
    return r;
  }();
  return t;
}

}  // namespace deformlab::interop::glext
