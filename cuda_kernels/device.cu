// Device discovery, memory checks and the copy-bandwidth ceiling for benchmarks.
#include <algorithm>
#include <mutex>
#include <stdexcept>
#include <vector>

#include "check.cuh"
#include "cuda_pipeline.hpp"

namespace deformlab::cuda {

void fail(cudaError_t e, const std::string& what) {
  throw std::runtime_error("CUDA error while " + what + ": " + cudaGetErrorName(e) + " (" + cudaGetErrorString(e) +
                           ")");
}

std::string unavailable() {
  static std::once_flag once;
  static std::string why;
  std::call_once(once, [] {
    int count = 0;
    const cudaError_t e = cudaGetDeviceCount(&count);
    if (e != cudaSuccess)
      why = std::string("no usable CUDA driver or device (cudaGetDeviceCount: ") + cudaGetErrorString(e) + ")";
    else if (count == 0)
      why = "no CUDA device";
  });
  return why;
}

void require_device_memory(std::int64_t bytes, const std::string& what) {
  std::size_t free = 0, total = 0;
  check(cudaMemGetInfo(&free, &total), "querying free device memory");
  if (bytes > std::int64_t(free))
    throw std::invalid_argument(what + " needs " + std::to_string(bytes) + " bytes of device memory, but only " +
                                std::to_string(free) + " of " + std::to_string(total) + " bytes are free");
}

DeviceInfo device_info() {
  DeviceInfo d;
  int dev = 0;
  check(cudaGetDevice(&dev), "querying the current device");
  cudaDeviceProp p{};
  check(cudaGetDeviceProperties(&p, dev), "querying device properties");
  d.name = p.name;
  d.sm_count = p.multiProcessorCount;
  d.memory_gib = double(p.totalGlobalMem) / double(1 << 30);
  d.cc_major = p.major;
  d.cc_minor = p.minor;
  check(cudaDriverGetVersion(&d.driver_version), "querying the driver version");
  check(cudaRuntimeGetVersion(&d.runtime_version), "querying the runtime version");
  return d;
}

double copy_ms(std::int64_t bytes, int reps) {
  require_device_memory(2 * bytes, "the copy benchmark");
  Buffer<char> a, b;
  a.allocate(std::size_t(bytes), "allocating the copy source");
  b.allocate(std::size_t(bytes), "allocating the copy destination");
  check(cudaMemset(a.get(), 1, std::size_t(bytes)), "filling the copy source");
  cudaEvent_t e0, e1;
  check(cudaEventCreate(&e0), "creating a timing event");
  check(cudaEventCreate(&e1), "creating a timing event");
  std::vector<double> ms;
  for (int r = 0; r <= reps; ++r) {
    check(cudaEventRecord(e0), "recording the copy start");
    check(cudaMemcpyAsync(b.get(), a.get(), std::size_t(bytes), cudaMemcpyDeviceToDevice), "copying device memory");
    check(cudaEventRecord(e1), "recording the copy end");
    check(cudaEventSynchronize(e1), "running the copy");
    float t = 0.f;
    check(cudaEventElapsedTime(&t, e0, e1), "reading the copy timer");
    if (r > 0) ms.push_back(t);  // the first copy is a warm-up
  }
  cudaEventDestroy(e0);
  cudaEventDestroy(e1);
  std::sort(ms.begin(), ms.end());
  return ms[ms.size() / 2];
}

}  // namespace deformlab::cuda
