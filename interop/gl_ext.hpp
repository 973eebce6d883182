// The GL extensions the external modes need, checked on the current context, and the
// GL_NV_timeline_semaphore entry points (GLEW 2.2 does not load them: eglGetProcAddress does).
#pragma once
#define EGL_NO_X11
#include <GL/glew.h>

#include <string>
#include <vector>

namespace deformlab::interop::glext {

bool has(const char* extension);
// Empty when every extension is there with its entry points, else which are missing.
std::string missing(const std::vector<const char*>& extensions);

// GL_NV_timeline_semaphore (not in GLEW 2.2's headers).
inline constexpr GLenum kTimelineSemaphoreValue = 0x9595;  // GL_TIMELINE_SEMAPHORE_VALUE_NV
inline constexpr GLenum kSemaphoreType = 0x95B3;           // GL_SEMAPHORE_TYPE_NV
inline constexpr GLint kSemaphoreTypeTimeline = 0x95B5;    // GL_SEMAPHORE_TYPE_TIMELINE_NV
using CreateSemaphoresNV = void(GLAPIENTRY*)(GLsizei n, GLuint* semaphores);
using SemaphoreParameterivNV = void(GLAPIENTRY*)(GLuint semaphore, GLenum pname, const GLint* params);

struct Timeline {
  CreateSemaphoresNV create_semaphores = nullptr;
  SemaphoreParameterivNV semaphore_parameteriv = nullptr;
};
// Loaded once; null members where the driver does not have them.
const Timeline& timeline();

}  // namespace deformlab::interop::glext
