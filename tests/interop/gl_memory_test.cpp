// The GL pipelines' node buffers on memory from CUDA's allocator (option memory=cuda) against
// GL's own buffers (memory=gl): the same shaders over the same data, so the states and the
// stop rule's displacement are bitwise equal. Where memory=cuda is unavailable (no CUDA device
// behind the GL context, as under llvmpipe) the default is gl and asking for cuda is refused.
#include <gtest/gtest.h>

#include <map>
#include <string>
#include <tuple>

#include "core/node_order.hpp"
#include "experiments/pipelines.hpp"
#include "gl/context.hpp"
#include "interop/shared_buffers.hpp"
#include "tests/support/test_states.hpp"
#include "tests/support/gpu_required.hpp"

namespace deformlab::test {
namespace {

using Chosen = std::map<std::string, std::string>;

TEST(GlMemory, DefaultChosenForThisMachineAndRecorded) {
  DEFORMLAB_SKIP_IF_UNAVAILABLE(gl::unavailable_reason());
  const std::string why = interop::cuda_memory().unavailable();
  const Model m = small_cloth(8, 8);
  const Params p = small_params();
  for (const char* name : {"glsl-compute", "glsl-tf"}) {
    SCOPED_TRACE(name);
    const PipelineEntry& e = *pipelines().find(name);
    EXPECT_EQ(e.make({m, p, Integrator::semi_implicit_euler})->chosen_options(),
              (Chosen{{"memory", why.empty() ? "cuda" : "gl"}}));
    EXPECT_TRUE(e.make({m, p, Integrator::semi_implicit_euler, {{"memory", "gl"}}})->chosen_options().empty());
    if (why.empty()) {
      EXPECT_TRUE(e.make({m, p, Integrator::semi_implicit_euler, {{"memory", "cuda"}}})->chosen_options().empty());
      continue;
    }
    try {
      e.make({m, p, Integrator::semi_implicit_euler, {{"memory", "cuda"}}});
      ADD_FAILURE() << "made with memory=cuda where it is unavailable: " << why;
    } catch (const std::invalid_argument& err) {
      EXPECT_EQ(std::string(err.what()), std::string(name) + ": memory cuda is not available: " + why);
    }
  }
}

// A cloth with contact and the drag handle, and the same springs as a general model in shuffled
// node order (the adjacency path, its neighbour reads scattered).
Model make_model(bool mesh) {
  Model m = small_cloth(37, 29);
  m.damping = {0.02f, 0.02f, 0.01f};
  if (!mesh) return m;
  m = explicit_springs(m);
  reorder(m, node_order(m, NodeOrder::shuffled, 5));
  return m;
}

class GlMemoryAgrees : public testing::TestWithParam<std::tuple<const char*, Integrator, bool>> {};

TEST_P(GlMemoryAgrees, BitwiseEqualStates) {
  const auto [name, integ, mesh] = GetParam();
  DEFORMLAB_SKIP_IF_UNAVAILABLE(gl::unavailable_reason());
  DEFORMLAB_SKIP_IF_UNAVAILABLE(interop::cuda_memory().unavailable());
  const Model m = make_model(mesh);
  Params p = moving_params(m, integ);
  p.ground = 0.995f;
  p.spheres = {{{0.f, 0.9f, 0.f}, 0.12f}};
  const State s0 = perturbed_state(m, 3);
  const PipelineEntry& e = *pipelines().find(name);
  auto on_gl = e.make({m, p, integ, {{"memory", "gl"}}});
  auto on_cuda = e.make({m, p, integ, {{"memory", "cuda"}}});
  const State a = advance(*on_gl, s0, 40), b = advance(*on_cuda, s0, 40);
  ASSERT_GT(max_position_diff(a, s0), 1e-4) << "the scene must move";
  EXPECT_TRUE(bitwise_equal(a, b)) << "|x_gl - x_cuda| = " << max_position_diff(a, b) << " m";
  EXPECT_EQ(on_gl->max_displacement(), on_cuda->max_displacement());
}

INSTANTIATE_TEST_SUITE_P(Pipelines, GlMemoryAgrees,
                         testing::Combine(testing::Values("glsl-compute", "glsl-tf"),
                                          testing::Values(Integrator::explicit_euler, Integrator::verlet,
                                                          Integrator::rk4),
                                          testing::Bool()),
                         [](const auto& info) {
                           std::string s = std::string(std::get<0>(info.param)) + "_" +
                                           std::string(deformlab::info(std::get<1>(info.param)).name) +
                                           (std::get<2>(info.param) ? "_mesh" : "_cloth");
                           for (char& c : s)
                             if (c == '-') c = '_';
                           return s;
                         });

}  // namespace
}  // namespace deformlab::test
