#include <gtest/gtest.h>

#include <array>
#include <cstdint>

#include "gl/pipelines_internal.hpp"

namespace deformlab::test {
namespace {

// The compute passes' work groups beyond a driver's x limit go to a second dimension with
// at most one partial row (the spec's minimum limit is 65535 groups: 16.7 M nodes).
TEST(ComputeDispatch, SplitsBeyondTheDriversLimit) {
  using A = std::array<std::uint32_t, 2>;
  EXPECT_EQ(gl::dispatch_shape(1, 65535), (A{1, 1}));
  EXPECT_EQ(gl::dispatch_shape(65535, 65535), (A{65535, 1}));
  EXPECT_EQ(gl::dispatch_shape(65536, 65535), (A{32768, 2}));         // 4096² nodes
  EXPECT_EQ(gl::dispatch_shape(262144, 65535), (A{52429, 5}));        // 8192² nodes
  EXPECT_EQ(gl::dispatch_shape(262144, 2147483647), (A{262144, 1}));  // NVIDIA's limit
  for (std::int64_t g : {1, 7, 65535, 65536, 100000, 262144, 1000003}) {
    const A d = gl::dispatch_shape(g, 65535);
    EXPECT_LE(d[0], 65535u);
    EXPECT_GE(std::int64_t(d[0]) * d[1], g);
    EXPECT_LT(std::int64_t(d[0]) * d[1] - g, std::int64_t(d[1]));
  }
}

}  // namespace
}  // namespace deformlab::test
