// Each interop mode moves data both ways: GL writes a buffer, CUDA copies it into a buffer it
// writes, GL reads that back; repeated so that every hand-off of the cycle is exercised, with
// the values changing each round (a stale buffer or a missing wait shows as old values). GL
// touches the shared buffers with shaders only, as the pipelines do (shaders/copy.comp says why).
// Sizes below, at and off the CUDA allocation granularity (2 MiB on the H100), up to 16 MiB.
#include <gtest/gtest.h>

#include <cuda_runtime.h>

#include <string>
#include <tuple>
#include <vector>

#include "gl/objects.hpp"
#include "interop/shared_buffers.hpp"
#include "tests/support/gpu_required.hpp"

namespace deformlab::test {
namespace {

using namespace deformlab::interop;

class Modes : public testing::TestWithParam<std::tuple<Mode, int>> {};

TEST_P(Modes, RoundTripsCarryEachRoundsValues) {
  const Mode m = std::get<0>(GetParam());
  const int n = std::get<1>(GetParam());  // floats
  DEFORMLAB_SKIP_IF_UNAVAILABLE(unavailable(m));
  auto sb = make_shared_buffers(m);
  const GLuint in = sb->add(n * 4, CudaAccess::read), out = sb->add(n * 4, CudaAccess::write);
  const gl::Program copy = gl::make_program({{GL_COMPUTE_SHADER, "copy.comp"}});
  auto gpu_copy = [&](GLuint from, GLuint to) {  // n / 4 vec4
    glUseProgram(copy.id());
    glUniform1i(gl::uniform(copy.id(), "u_n"), n / 4);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, from);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, to);
    glDispatchCompute(GLuint((n / 4 + 255) / 256), 1, 1);
    glMemoryBarrier(GL_ALL_BARRIER_BITS);
    glUseProgram(0);
  };
  const gl::Buffer readback = gl::make_buffer(n * 4);
  std::vector<float> data(n), back(n);
  for (int round = 0; round < 5; ++round) {
    for (int i = 0; i < n; ++i) data[i] = float(round * n + i);
    const gl::Buffer staging = gl::make_buffer(n * 4, data.data());
    gpu_copy(staging.id(), in);
    sb->to_cuda({in, out});
    ASSERT_EQ(cudaMemcpyAsync(sb->cuda_ptr(out), sb->cuda_ptr(in), n * 4, cudaMemcpyDeviceToDevice, sb->stream()),
              cudaSuccess);
    sb->to_gl();
    gpu_copy(out, readback.id());
    glGetNamedBufferSubData(readback.id(), 0, n * 4, back.data());
    ASSERT_EQ(glGetError(), GLenum(GL_NO_ERROR));
    int wrong = 0, first = -1;
    for (int i = 0; i < n; ++i)
      if (back[i] != data[i]) {
        if (first < 0) first = i;
        ++wrong;
      }
    ASSERT_EQ(wrong, 0) << to_string(m) << ", round " << round << ": " << wrong << " of " << n
                        << " values wrong, the first at " << first << " (" << back[first] << " instead of "
                        << data[first] << ")";
  }
}

INSTANTIATE_TEST_SUITE_P(Interop, Modes,
                         testing::Combine(testing::ValuesIn(kModes),
                                          testing::Values(1 << 12, 1 << 18, 3 << 18, 1 << 22)),
                         [](const testing::TestParamInfo<std::tuple<Mode, int>>& p) {
                           std::string s = to_string(std::get<0>(p.param));
                           for (char& c : s)
                             if (c == '-') c = '_';
                           return s + "_" + std::to_string(std::get<1>(p.param) * 4 / 1024) + "KiB";
                         });

}  // namespace
}  // namespace deformlab::test
