// A profiled GL pipeline: each step is one force+update span timed by the GL clock (timer
// queries on a GPU, the host clock after glFinish on llvmpipe); steps outside the profiled
// stretch are not timed.
#include <map>

#include "gl_test_support.hpp"
#include "tests/support/test_states.hpp"

namespace deformlab::test {
namespace {

TEST(GlProfile, OneForceUpdateSpanPerStep) {
  DEFORMLAB_REQUIRE_GL();
  const Model m = small_cloth(16, 12);
  const Params p = small_params();
  for (const char* name : {"glsl-tf", "glsl-compute"}) {
    SCOPED_TRACE(name);
    auto pipe = make_gl(name, {m, p, Integrator::rk4});
    auto& g = dynamic_cast<gl::GlPipeline&>(*pipe);
    pipe->set_state(perturbed_state(m, 3));
    pipe->step();  // not profiled
    Profiler prof;
    pipe->set_profiler(&prof);
    for (int k = 1; k <= 4; ++k) {
      prof.set_step(k);
      pipe->step();
    }
    pipe->set_profiler(nullptr);
    std::map<int, int> per_step;
    for (const Span& s : prof.spans()) {
      EXPECT_EQ(s.name, "force+update");
      EXPECT_EQ(s.clock, g.timing_method());
      EXPECT_GT(s.ms, 0.0);
      ++per_step[s.step];
    }
    EXPECT_EQ(per_step, (std::map<int, int>{{1, 1}, {2, 1}, {3, 1}, {4, 1}}));
    pipe->step();  // not profiled
    pipe->set_profiler(&prof);
    pipe->set_profiler(nullptr);
    EXPECT_EQ(prof.spans().size(), 4u);
  }
}

// A profiler sampling one window of 8 steps in 2: spans in steps 1-8 and 17-20 only, and the
// same state as an unprofiled run.
TEST(GlProfile, SpansOnlyInTheSampledSteps) {
  DEFORMLAB_REQUIRE_GL();
  const Model m = small_cloth(16, 12);
  const Params p = small_params();
  auto pipe = make_gl("glsl-compute", {m, p, Integrator::semi_implicit_euler});
  EXPECT_EQ(sampled_span_steps(*pipe, perturbed_state(m, 3), 20, 2),
            (std::vector<int>{1, 2, 3, 4, 5, 6, 7, 8, 17, 18, 19, 20}));
  auto plain = make_gl("glsl-compute", {m, p, Integrator::semi_implicit_euler});
  EXPECT_TRUE(bitwise_equal(advance(*plain, perturbed_state(m, 3), 20), pipe->state()));
}

}  // namespace
}  // namespace deformlab::test
