// cuda::unavailable() on a device the build has no code for: this test's copy of the probe is
// compiled for compute capability 8.0 only, whose code loads on devices of major version 8.
#include <cuda_runtime_api.h>
#include <gtest/gtest.h>

#include "cuda_kernels/availability.hpp"
#include "tests/support/gpu_required.hpp"

namespace deformlab {
namespace {

TEST(CudaProbe, ADeviceWithoutThisBuildsCodeIsUnavailableWithTheSettingToAddIt) {
  int count = 0;
  if (cudaGetDeviceCount(&count) != cudaSuccess || count == 0) DEFORMLAB_SKIP_IF_UNAVAILABLE("no CUDA device");
  cudaDeviceProp p{};
  ASSERT_EQ(cudaGetDeviceProperties(&p, 0), cudaSuccess);
  const std::string why = cuda::unavailable();
  if (p.major == 8) {
    EXPECT_EQ(why, "") << "sm_80 code loads on compute capability " << p.major << "." << p.minor;
  } else {
    const std::string cc = std::to_string(p.major) + "." + std::to_string(p.minor);
    EXPECT_EQ(why.rfind(std::string("this build's CUDA code does not load on the ") + p.name + " (compute capability " +
                            cc + ": cudaError",
                        0),
              0u)
        << why;
    const std::string tail = "); configure with -DCMAKE_CUDA_ARCHITECTURES=" + std::to_string(p.major * 10 + p.minor);
    EXPECT_TRUE(why.ends_with(tail)) << why;
  }
}

}  // namespace
}  // namespace deformlab
