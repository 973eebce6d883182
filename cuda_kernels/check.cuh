// Error checks for CUDA calls and kernel launches: a failure throws, naming what was being done.
#pragma once
#include <cuda_runtime.h>

#include <atomic>
#include <cstdint>
#include <string>

namespace deformlab::cuda {

[[noreturn]] void fail(cudaError_t e, const std::string& what);

inline void check(cudaError_t e, const char* what) {
  if (e != cudaSuccess) fail(e, what);
}
// After a launch: configuration errors show here, faults in the kernel at the next check.
inline void check_launch(const char* what) { check(cudaGetLastError(), what); }

// The bytes every Buffer holds now (buffer_bytes() in cuda_pipeline.hpp reads it).
extern std::atomic<std::int64_t> g_buffer_bytes;

// Device memory owned by one object; freed on destruction.
template <class T>
class Buffer {
 public:
  Buffer() = default;
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  ~Buffer() { release(); }
  void allocate(std::size_t count, const char* what) {
    release();
    if (count == 0) return;
    check(cudaMalloc(reinterpret_cast<void**>(&p_), count * sizeof(T)), what);
    n_ = count;
    g_buffer_bytes += std::int64_t(count * sizeof(T));
  }
  void release() {
    if (p_) cudaFree(p_);
    g_buffer_bytes -= std::int64_t(n_ * sizeof(T));
    p_ = nullptr;
    n_ = 0;
  }
  T* get() const { return p_; }
  std::size_t size() const { return n_; }

 private:
  T* p_ = nullptr;
  std::size_t n_ = 0;
};

}  // namespace deformlab::cuda
