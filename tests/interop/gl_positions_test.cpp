// A CUDA pipeline's positions copied into a GL buffer on the device (the viewer's drawing
// path): GL reads back exactly the pipeline's state, after each step.
#include <gtest/gtest.h>

#include <vector>

#include "experiments/pipelines.hpp"
#include "interop/gl_positions.hpp"
#include "tests/support/test_states.hpp"
#include "tests/support/gpu_required.hpp"

namespace deformlab::test {
namespace {

TEST(GlPositions, HoldTheCudaPipelinesPositionsAfterEachStep) {
  DEFORMLAB_SKIP_IF_UNAVAILABLE(interop::unavailable(interop::Mode::map));
  const Model m = small_cloth(33, 17);
  auto p = pipelines().find("cuda-fused")->make({m, small_params(), Integrator::semi_implicit_euler});
  p->set_state(perturbed_state(m, 3u));
  interop::GlPositions g(m.node_count());
  std::vector<float> gl(4 * std::size_t(m.node_count()));
  for (int round = 0; round < 3; ++round) {
    ASSERT_TRUE(g.update(*p));
    glGetNamedBufferSubData(g.buffer(), 0, GLsizeiptr(gl.size() * 4), gl.data());
    const State s = p->state();
    for (int i = 0; i < m.node_count(); ++i) {
      ASSERT_EQ(gl[4 * i], s.x[i].x) << "round " << round << ", node " << i;
      ASSERT_EQ(gl[4 * i + 1], s.x[i].y);
      ASSERT_EQ(gl[4 * i + 2], s.x[i].z);
      ASSERT_EQ(gl[4 * i + 3], m.inv_mass[i]);
    }
    for (int k = 0; k < 5; ++k) p->step();
  }
  auto cpu = pipelines().find("cpu")->make({m, small_params(), Integrator::semi_implicit_euler});
  EXPECT_FALSE(g.update(*cpu));
}

}  // namespace
}  // namespace deformlab::test
