// Whether this machine can run the CUDA pipelines: a driver, a device, and code of this build
// that the device loads (asked of this file's kernel: every CUDA file of a build is compiled for
// the same architectures).
#include <cuda_runtime.h>

#include <mutex>

#include "availability.hpp"

namespace deformlab::cuda {

namespace {
// A kernel to ask the driver whether this build's code loads on the device.
__global__ void probe() {}

// The reason for a device of compute capability major.minor (named `gpu`) on which the probe
// failed with the error named `error`, naming the build setting that would add its code.
std::string no_kernel_image(const std::string& error, const std::string& gpu, int major, int minor) {
  const std::string arch = std::to_string(major) + std::to_string(minor);
  return "this build's CUDA code does not load on the " + gpu + " (compute capability " + std::to_string(major) + "." +
         std::to_string(minor) + ": " + error + "); configure with -DCMAKE_CUDA_ARCHITECTURES=" + arch;
}

}  // namespace

std::string unavailable() {
  static std::once_flag once;
  static std::string why;
  std::call_once(once, [] {
    int count = 0;
    cudaError_t e = cudaGetDeviceCount(&count);
    if (e != cudaSuccess) {
      why = std::string("no usable CUDA driver or device (cudaGetDeviceCount: ") + cudaGetErrorString(e) + ")";
      return;
    }
    if (count == 0) {
      why = "no CUDA device";
      return;
    }
    cudaFuncAttributes a{};
    if (e = cudaFuncGetAttributes(&a, probe); e == cudaSuccess) return;
    cudaGetLastError();  // clear it for later checks
    const bool no_code = e == cudaErrorNoKernelImageForDevice || e == cudaErrorInvalidDeviceFunction;
    int device = 0;
    cudaDeviceProp p{};
    if (no_code && cudaGetDevice(&device) == cudaSuccess && cudaGetDeviceProperties(&p, device) == cudaSuccess)
      why = no_kernel_image(cudaGetErrorName(e), p.name, p.major, p.minor);
    else
      why = std::string("the CUDA device cannot be used (") + cudaGetErrorName(e) + ": " + cudaGetErrorString(e) + ")";
  });
  return why;
}

}  // namespace deformlab::cuda
