#include "shared_buffers.hpp"

#include <cuda_gl_interop.h>
#include <cuda_runtime.h>
#include <unistd.h>

#include <algorithm>
#include <utility>
#include <array>
#include <map>
#include <mutex>
#include <stdexcept>

#include "cuda_driver.hpp"
#include "cuda_kernels/check.cuh"
#include "cuda_kernels/cuda_pipeline.hpp"
#include "gl_ext.hpp"
#include "gl/context.hpp"
#include "gl/objects.hpp"
#include "vulkan_semaphore.hpp"

namespace deformlab::interop {

using cuda::check;

const char* to_string(Mode m) {
  switch (m) {
    case Mode::map: return "map";
    case Mode::external: return "external";
    case Mode::external_gpusync: return "external-gpusync";
    case Mode::staged: return "staged";
  }
  return "?";
}

std::optional<Mode> parse_mode(std::string_view s) {
  for (Mode m : kModes)
    if (s == to_string(m)) return m;
  return std::nullopt;
}

std::string mode_names() {
  std::string s;
  for (Mode m : kModes) s += (s.empty() ? "" : ", ") + std::string(to_string(m));
  return s;
}

int cuda_device_of_gl() {
  const gl::ContextInfo& ctx = gl::context();
  if (const std::string why = cuda::unavailable(); !why.empty()) throw std::invalid_argument(why);
  unsigned count = 0;
  int devices[8] = {};
  const cudaError_t e = cudaGLGetDevices(&count, devices, 8, cudaGLDeviceListAll);
  if (e != cudaSuccess || count == 0) {
    cudaGetLastError();  // not sticky: clear it for later launch checks
    throw std::invalid_argument("the OpenGL context (" + ctx.renderer + ", " + ctx.platform +
                                ") is not on a CUDA device (cudaGLGetDevices: " +
                                (e != cudaSuccess ? cudaGetErrorString(e) : "no device") + ")");
  }
  return devices[0];
}

namespace {

std::array<unsigned char, 16> device_uuid(int device) {
  cudaDeviceProp p{};
  check(cudaGetDeviceProperties(&p, device), "querying the device's UUID");
  std::array<unsigned char, 16> u{};
  std::copy(p.uuid.bytes, p.uuid.bytes + 16, reinterpret_cast<char*>(u.data()));
  return u;
}

// The timeline semaphore imported into GL and CUDA, once per process and kept until it exits
// with its Vulkan device (see vulkan_semaphore.hpp). Values only grow: each hand-off signals
// the next one.
struct SharedTimeline {
  GLuint gl = 0;
  cudaExternalSemaphore_t cuda = nullptr;
  GLuint64 value = 0;
};

SharedTimeline& shared_timeline(int device) {
  static SharedTimeline* t = [device] {
    VulkanTimeline& vk = VulkanTimeline::get(device_uuid(device));
    auto* made = new SharedTimeline;  // never deleted, like the Vulkan semaphore behind it
    // The timeline type is set on a semaphore made by glCreateSemaphoresNV, before the import.
    glext::timeline().create_semaphores(1, &made->gl);
    glext::timeline().semaphore_parameteriv(made->gl, glext::kSemaphoreType, &glext::kSemaphoreTypeTimeline);
    glImportSemaphoreFdEXT(made->gl, GL_HANDLE_TYPE_OPAQUE_FD_EXT, vk.export_fd());
    gl::check("importing the timeline semaphore into OpenGL");
    cudaExternalSemaphoreHandleDesc desc{};
    desc.type = cudaExternalSemaphoreHandleTypeTimelineSemaphoreFd;
    desc.handle.fd = vk.export_fd();
    const cudaError_t e = cudaImportExternalSemaphore(&made->cuda, &desc);
    if (e != cudaSuccess) close(desc.handle.fd);
    check(e, "importing the timeline semaphore into CUDA");
    return made;
  }();
  return *t;
}

std::string probe(Mode m) {
  try {
    const int dev = cuda_device_of_gl();
    if (m == Mode::map || m == Mode::staged) return {};
    const std::string name = to_string(m);
    if (const std::string miss = glext::missing({"GL_EXT_memory_object", "GL_EXT_memory_object_fd"}); !miss.empty())
      return name + " needs OpenGL memory objects; this driver (" + gl::context().renderer + ") lacks " + miss;
    if (const std::string why = exportable_memory_unavailable(dev); !why.empty()) return name + ": " + why;
    if (m == Mode::external) return {};
    if (const std::string miss = glext::missing({"GL_EXT_semaphore", "GL_EXT_semaphore_fd", "GL_NV_timeline_semaphore"});
        !miss.empty())
      return name + " needs OpenGL timeline semaphores; this driver (" + gl::context().renderer + ") lacks " + miss;
    shared_timeline(dev);
    return {};
  } catch (const std::exception& e) {
    return e.what();
  }
}

// ---- map: registered GL buffers, mapped per hand-off ----

class MapBuffers final : public SharedBuffers {
 public:
  MapBuffers(Mode m, int device, CUstream_st* s) : SharedBuffers(m, device, s) {}
  ~MapBuffers() override {
    if (!mapped_.empty()) cudaGraphicsUnmapResources(int(mapped_.size()), mapped_.data(), stream_);
    for (auto& [id, e] : entries_) cudaGraphicsUnregisterResource(e.resource);
  }

  GLuint add(std::size_t bytes, CudaAccess access) override {
    gl::Buffer b = gl::make_buffer(bytes);
    cudaGraphicsResource_t r = nullptr;
    check(cudaGraphicsGLRegisterBuffer(&r, b.id(),
                                       access == CudaAccess::read ? cudaGraphicsRegisterFlagsReadOnly
                                                                  : cudaGraphicsRegisterFlagsWriteDiscard),
          "registering a GL buffer with CUDA");
    const GLuint id = b.id();
    entries_[id] = {std::move(b), r, nullptr};
    return id;
  }

  void to_cuda(const std::vector<GLuint>& buffers) override {
    if (!mapped_.empty()) throw std::logic_error("map: hand-off to CUDA while buffers are mapped");
    std::vector<cudaGraphicsResource_t> resources;
    for (GLuint b : buffers) resources.push_back(entry(b).resource);
    if (resources.empty()) return;
    check(cudaGraphicsMapResources(int(resources.size()), resources.data(), stream_), "mapping GL buffers for CUDA");
    mapped_ = std::move(resources);  // only once mapped: a failed map leaves nothing to unmap
    for (GLuint b : buffers) {
      Entry& e = entry(b);
      std::size_t size = 0;
      check(cudaGraphicsResourceGetMappedPointer(&e.ptr, &size, e.resource), "getting a mapped buffer's pointer");
    }
  }

  void* cuda_ptr(GLuint b) const override {
    void* p = entries_.at(b).ptr;
    if (!p) throw std::logic_error("map: buffer not handed to CUDA");
    return p;
  }

  void to_gl() override {
    if (mapped_.empty()) return;
    check(cudaGraphicsUnmapResources(int(mapped_.size()), mapped_.data(), stream_), "unmapping GL buffers");
    mapped_.clear();
    for (auto& [id, e] : entries_) e.ptr = nullptr;
  }

 private:
  struct Entry {
    gl::Buffer buffer;
    cudaGraphicsResource_t resource = nullptr;
    void* ptr = nullptr;
  };
  Entry& entry(GLuint b) {
    auto it = entries_.find(b);
    if (it == entries_.end()) throw std::logic_error("map: not a shared buffer");
    return it->second;
  }
  std::map<GLuint, Entry> entries_;
  std::vector<cudaGraphicsResource_t> mapped_;
};

// ---- external and external-gpusync: CUDA memory imported into GL ----

class ExternalBuffers final : public SharedBuffers {
 public:
  ExternalBuffers(Mode m, int device, CUstream_st* s) : SharedBuffers(m, device, s), memory_(device) {
    if (m == Mode::external_gpusync) timeline_ = &shared_timeline(device);
  }

  ~ExternalBuffers() override {
    if (stream_) cudaStreamSynchronize(stream_);
  }

  GLuint add(std::size_t bytes, CudaAccess) override { return memory_.add(bytes); }

  void to_cuda(const std::vector<GLuint>& buffers) override {
    for (GLuint b : buffers) memory_.cuda_ptr(b);  // throws for a buffer not added here
    if (mode_ == Mode::external) {
      // The CPU waits for GL's commands so far, then queues the CUDA work.
      GLsync fence = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
      const GLenum r = glClientWaitSync(fence, GL_SYNC_FLUSH_COMMANDS_BIT, GLuint64(60) * 1000000000);
      glDeleteSync(fence);
      if (r != GL_ALREADY_SIGNALED && r != GL_CONDITION_SATISFIED)
        throw std::runtime_error("external: waiting for OpenGL before a hand-off to CUDA failed");
      return;
    }
    // GPU: GL signals the next value after its commands on these buffers; CUDA waits for it.
    std::vector<GLuint> ids = buffers;
    const GLuint64 v = ++timeline_->value;
    glSemaphoreParameterui64vEXT(timeline_->gl, glext::kTimelineSemaphoreValue, &v);
    glSignalSemaphoreEXT(timeline_->gl, GLuint(ids.size()), ids.data(), 0, nullptr, nullptr);
    glFlush();
    cudaExternalSemaphoreWaitParams w{};
    w.params.fence.value = v;
    check(cudaWaitExternalSemaphoresAsync(&timeline_->cuda, &w, 1, stream_), "CUDA waiting for OpenGL (semaphore)");
    handed_ = std::move(ids);
  }

  void* cuda_ptr(GLuint b) const override { return memory_.cuda_ptr(b); }

  void to_gl() override {
    if (mode_ == Mode::external) {
      check(cudaStreamSynchronize(stream_), "waiting for CUDA before a hand-off to OpenGL");
      return;
    }
    const GLuint64 v = ++timeline_->value;
    cudaExternalSemaphoreSignalParams s{};
    s.params.fence.value = v;
    check(cudaSignalExternalSemaphoresAsync(&timeline_->cuda, &s, 1, stream_), "CUDA signalling OpenGL (semaphore)");
    glSemaphoreParameterui64vEXT(timeline_->gl, glext::kTimelineSemaphoreValue, &v);
    glWaitSemaphoreEXT(timeline_->gl, GLuint(handed_.size()), handed_.data(), 0, nullptr, nullptr);
    handed_.clear();
  }

 private:
  CudaMemoryBuffers memory_;
  SharedTimeline* timeline_ = nullptr;  // external-gpusync
  std::vector<GLuint> handed_;
};

// ---- staged: separate buffers, copies through pinned host memory ----

class StagedBuffers final : public SharedBuffers {
 public:
  StagedBuffers(Mode m, int device, CUstream_st* s) : SharedBuffers(m, device, s) {}
  ~StagedBuffers() override {
    if (stream_) cudaStreamSynchronize(stream_);
    for (auto& [id, e] : entries_) {
      cudaFree(e.device);
      cudaFreeHost(e.host);
    }
  }

  GLuint add(std::size_t bytes, CudaAccess access) override {
    Entry e;
    e.buffer = gl::make_buffer(bytes);
    e.bytes = bytes;
    e.access = access;
    check(cudaMalloc(&e.device, bytes), "allocating a staged buffer's device copy");
    if (const cudaError_t r = cudaMallocHost(&e.host, bytes); r != cudaSuccess) {
      cudaFree(e.device);
      check(r, "allocating a staged buffer's host copy");
    }
    const GLuint id = e.buffer.id();
    entries_.emplace(id, std::move(e));
    return id;
  }

  // GL -> host -> device for the buffers CUDA reads.
  void to_cuda(const std::vector<GLuint>& buffers) override {
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    for (GLuint b : buffers) {
      Entry& e = entry(b);
      handed_.push_back(b);
      if (e.access != CudaAccess::read) continue;
      glGetNamedBufferSubData(b, 0, GLsizeiptr(e.bytes), e.host);
      check(cudaMemcpyAsync(e.device, e.host, e.bytes, cudaMemcpyHostToDevice, stream_), "copying host to device");
    }
    gl::check("staged: reading GL buffers back");
  }

  void* cuda_ptr(GLuint b) const override { return entries_.at(b).device; }

  // Device -> host -> GL for the buffers CUDA wrote.
  void to_gl() override {
    for (GLuint b : handed_) {
      const Entry& e = entry(b);
      if (e.access == CudaAccess::write)
        check(cudaMemcpyAsync(e.host, e.device, e.bytes, cudaMemcpyDeviceToHost, stream_), "copying device to host");
    }
    check(cudaStreamSynchronize(stream_), "waiting for CUDA before a hand-off to OpenGL");
    for (GLuint b : handed_) {
      const Entry& e = entry(b);
      if (e.access == CudaAccess::write) glNamedBufferSubData(b, 0, GLsizeiptr(e.bytes), e.host);
    }
    handed_.clear();
    gl::check("staged: uploading CUDA's results to GL");
  }

 private:
  struct Entry {
    gl::Buffer buffer;
    std::size_t bytes = 0;
    CudaAccess access = CudaAccess::read;
    void* device = nullptr;
    void* host = nullptr;
  };
  Entry& entry(GLuint b) {
    auto it = entries_.find(b);
    if (it == entries_.end()) throw std::logic_error("staged: not a shared buffer");
    return it->second;
  }
  std::map<GLuint, Entry> entries_;
  std::vector<GLuint> handed_;
};

}  // namespace

struct CudaMemoryBuffers::Entry {
  ExportableAllocation memory;
  GLuint gl_memory = 0;
  gl::Buffer buffer;  // declared after gl_memory: deleted before it
  Entry(int device, std::size_t bytes) : memory(device, bytes) {}
  ~Entry() {
    buffer = gl::Buffer();
    if (gl_memory) glDeleteMemoryObjectsEXT(1, &gl_memory);
  }
};

CudaMemoryBuffers::CudaMemoryBuffers(int device) : device_(device) {}

CudaMemoryBuffers::~CudaMemoryBuffers() {
  glFinish();
  entries_.clear();
}

GLuint CudaMemoryBuffers::add(std::size_t bytes) {
  auto e = std::make_unique<Entry>(device_, bytes);
  glCreateMemoryObjectsEXT(1, &e->gl_memory);
  // cuMemCreate memory is one allocation per buffer: GL must be told so. Imported without
  // this flag, the NVIDIA driver accepts the fd without an error but the GL buffer does not
  // see CUDA's memory (seen on the H100 at every size).
  const GLint dedicated = GL_TRUE;
  glMemoryObjectParameterivEXT(e->gl_memory, GL_DEDICATED_MEMORY_OBJECT_EXT, &dedicated);
  glImportMemoryFdEXT(e->gl_memory, e->memory.size(), GL_HANDLE_TYPE_OPAQUE_FD_EXT, e->memory.export_fd());
  GLuint id = 0;
  glCreateBuffers(1, &id);
  e->buffer = gl::Buffer(id);
  glNamedBufferStorageMemEXT(id, GLsizeiptr(bytes), e->gl_memory, 0);
  gl::check("importing CUDA memory into an OpenGL buffer (GL_EXT_memory_object_fd)");
  entries_.emplace(id, std::move(e));
  return id;
}

void* CudaMemoryBuffers::cuda_ptr(GLuint buffer) const {
  const auto it = entries_.find(buffer);
  if (it == entries_.end()) throw std::logic_error("not a buffer over CUDA's memory");
  return it->second->memory.ptr();
}

gl::CudaMemory cuda_memory() {
  return {[] { return unavailable(Mode::external); },
          [] {
            const int dev = cuda_device_of_gl();
            check(cudaSetDevice(dev), "selecting the CUDA device behind the OpenGL context");
            return std::make_unique<CudaMemoryBuffers>(dev);
          }};
}

SharedBuffers::~SharedBuffers() {
  if (stream_) cudaStreamDestroy(stream_);
}

std::string unavailable(Mode m) {
  static std::mutex mu;
  static std::map<Mode, std::string> known;
  std::lock_guard<std::mutex> lock(mu);
  auto it = known.find(m);
  if (it == known.end()) it = known.emplace(m, probe(m)).first;
  return it->second;
}

std::unique_ptr<SharedBuffers> make_shared_buffers(Mode m) {
  if (const std::string why = unavailable(m); !why.empty())
    throw std::invalid_argument(std::string("interop mode ") + to_string(m) + " is not available: " + why);
  const int dev = cuda_device_of_gl();
  check(cudaSetDevice(dev), "selecting the CUDA device behind the OpenGL context");
  cudaStream_t s = nullptr;
  check(cudaStreamCreateWithFlags(&s, cudaStreamNonBlocking), "creating the interop stream");
  // The base class owns the stream from here (also when a constructor throws).
  switch (m) {
    case Mode::map: return std::make_unique<MapBuffers>(m, dev, s);
    case Mode::external:
    case Mode::external_gpusync: return std::make_unique<ExternalBuffers>(m, dev, s);
    case Mode::staged: return std::make_unique<StagedBuffers>(m, dev, s);
  }
  throw std::logic_error("unknown interop mode");
}

}  // namespace deformlab::interop
