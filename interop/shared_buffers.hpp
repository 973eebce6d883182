// Buffers seen by both CUDA and OpenGL, and the hand-offs between the two APIs, under one
// interface for the four interop modes:
//   map               GL buffers registered once with CUDA (cudaGraphicsGLRegisterBuffer,
//                     read-only / write-discard flags), mapped and unmapped at each hand-off
//   external          CUDA memory (cuMemCreate) exported as a POSIX fd and imported into GL
//                     (GL_EXT_memory_object_fd); the CPU synchronises (GL fence, CUDA stream)
//   external-gpusync  the same memory; a Vulkan timeline semaphore imported into GL and CUDA
//                     orders the two on the GPU, the CPU never waits
//   staged            GL and CUDA keep their own buffers; copies go through host memory
// The GL context (gl/context.hpp) must be current on the calling thread; CUDA work
// runs on the device behind it (cudaGLGetDevices), on the stream these buffers own.
#pragma once
#define EGL_NO_X11
#include <GL/glew.h>

#include <cstddef>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "gl/gl_pipeline.hpp"

struct CUstream_st;

namespace deformlab::interop {

enum class Mode { map, external, external_gpusync, staged };
inline constexpr Mode kModes[] = {Mode::map, Mode::external, Mode::external_gpusync, Mode::staged};
const char* to_string(Mode m);
std::optional<Mode> parse_mode(std::string_view s);
std::string mode_names();  // "map, external, external-gpusync, staged"

// What CUDA does with a buffer, fixed for its life (GL may read and write it).
enum class CudaAccess { read, write };

// Empty when the mode can be used here, else which part is missing and why (no CUDA
// device, GL not on a CUDA device, a missing GL extension, no Vulkan loader, ...).
std::string unavailable(Mode m);
// The CUDA device behind the current GL context; throws std::invalid_argument if none.
int cuda_device_of_gl();

class ExportableAllocation;

// GL buffers over memory from CUDA's allocator on `device` (cuMemCreate, exported as a POSIX fd
// and imported with GL_EXT_memory_object_fd), owned here: the external modes' buffers, and the
// GL pipelines' node buffers with memory=cuda.
class CudaMemoryBuffers final : public gl::NodeMemory {
 public:
  explicit CudaMemoryBuffers(int device);
  ~CudaMemoryBuffers() override;  // waits for GL's commands (glFinish) before freeing
  GLuint add(std::size_t bytes) override;
  const char* name() const override { return "cuda"; }
  // CUDA's pointer to a buffer added here; throws std::logic_error for another.
  void* cuda_ptr(GLuint buffer) const;

 private:
  struct Entry;
  int device_;
  std::map<GLuint, std::unique_ptr<Entry>> entries_;
};

// The GL pipelines' memory=cuda: available where interop mode external is (a CUDA device behind
// the GL context, GL memory objects, exportable CUDA memory).
gl::CudaMemory cuda_memory();

class SharedBuffers {
 public:
  virtual ~SharedBuffers();  // destroys the stream
  CUstream_st* stream() const { return stream_; }

  // A new buffer of `bytes` (contents undefined); returns its GL name, valid as long as
  // this object lives. GL may use it like any buffer, except for mutable-storage calls
  // (glBufferData).
  virtual GLuint add(std::size_t bytes, CudaAccess access) = 0;
  // Hand-off to CUDA: GL commands issued so far (on these buffers) complete before CUDA
  // work queued on stream() from now on; the buffers' device pointers become valid.
  virtual void to_cuda(const std::vector<GLuint>& buffers) = 0;
  // Device pointer of a buffer handed to CUDA, valid until to_gl().
  virtual void* cuda_ptr(GLuint buffer) const = 0;
  // Hand-off to GL: CUDA work queued on stream() so far completes before GL commands
  // issued from now on (and its writes are visible to them).
  virtual void to_gl() = 0;

 protected:
  SharedBuffers(Mode m, int device, CUstream_st* s) : mode_(m), device_(device), stream_(s) {}
  Mode mode_;
  int device_;
  CUstream_st* stream_;
};

// Throws std::invalid_argument with unavailable(m)'s reason when the mode cannot be used.
std::unique_ptr<SharedBuffers> make_shared_buffers(Mode m);

}  // namespace deformlab::interop
