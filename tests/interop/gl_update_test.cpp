// The GL update passes fed by an outside force stage and driven by the schedule runner (what
// the hybrid pipelines do with CUDA), here with the accelerations computed on the host from
// the state GL wrote, so that the GL side of the hybrid step is checked on any GL driver
// (llvmpipe in CI). Tolerance, as the match tests' (tests/match/match_cpu_test.cpp): 8 x the CPU
// float pipeline's own distance from the double reference (rounding_bound), with a floor of
// 1e-6 m and 1e-4 m/s.
#include <gtest/gtest.h>

#include "core/cpu_backend.hpp"
#include "core/stage.hpp"
#include "gl/gl_pipeline.hpp"
#include "gl/pipelines_internal.hpp"
#include "tests/support/test_states.hpp"
#include "tests/support/gpu_required.hpp"

namespace deformlab::test {
namespace {

// Accelerations on the host: the CPU pipeline's force pass (cpu_accelerations) on the state
// GL wrote.
class HostForces final : public ForceStage {
 public:
  explicit HostForces(const PipelineSetup& setup) : setup_(setup) {}

  gl::SharedAllocator allocator() {
    return [this](std::size_t bytes, gl::NodeRole) {
      buffers_.push_back(gl::make_buffer(bytes));
      return buffers_.back().id();
    };
  }
  void attach(gl::GlPipeline* gl) { gl_ = gl; }

  void forces(int src, int, double t) override {
    const auto [x, v] = gl_->slot_buffers(src);
    const std::size_t n = std::size_t(setup_.model.node_count());
    std::vector<float> xs(4 * n), vs(4 * n), a(4 * n, 0.f);
    gl::read_buffer(x, 0, xs.size() * 4, xs.data());
    gl::read_buffer(v, 0, vs.size() * 4, vs.data());
    State s;
    for (std::size_t i = 0; i < n; ++i) {
      s.x.push_back({xs[4 * i], xs[4 * i + 1], xs[4 * i + 2]});
      s.v.push_back({vs[4 * i], vs[4 * i + 1], vs[4 * i + 2]});
    }
    const std::vector<Vec3f> acc = cpu_accelerations(setup_, s, t);
    for (std::size_t i = 0; i < n; ++i) {
      a[4 * i] = acc[i].x;
      a[4 * i + 1] = acc[i].y;
      a[4 * i + 2] = acc[i].z;
    }
    glNamedBufferSubData(gl_->force_buffer(), 0, GLsizeiptr(a.size() * 4), a.data());
    ++calls;
  }

  int calls = 0;

 private:
  const PipelineSetup& setup_;
  gl::GlPipeline* gl_ = nullptr;
  std::vector<gl::Buffer> buffers_;
};

struct Case {
  bool compute;
  Integrator integrator;
};

class GlUpdatePass : public testing::TestWithParam<Case> {};

TEST_P(GlUpdatePass, MatchesTheCpuPipeline) {
  DEFORMLAB_SKIP_IF_UNAVAILABLE(gl::unavailable_reason());
  const Case& c = GetParam();
  Model m = small_cloth(16, 12);
  m.damping = {0.02f, 0.02f, 0.01f};
  const Params p = moving_params(m, c.integrator);
  const State s0 = perturbed_state(m, 11);
  const int steps = 30;
  const PipelineSetup setup{m, p, c.integrator};
  HostForces forces(setup);
  auto gpu = c.compute ? gl::make_compute_update(setup, forces.allocator()) : gl::make_tf_update(setup, forces.allocator());
  forces.attach(gpu.get());
  gpu->set_state(s0);
  const Schedule sched = make_schedule(c.integrator);
  for (int k = 0; k < steps; ++k) {
    run_passes(sched, gpu->time(), p.dt, forces, *gpu);
    gpu->finish_step();
  }
  const State g = gpu->state();
  auto f32 = make_cpu_pipeline(setup, Precision::f32, false);
  auto f64 = make_cpu_pipeline(setup, Precision::f64, false);
  const State a = advance(*f32, s0, steps), r = advance(*f64, s0, steps);
  EXPECT_EQ(forces.calls, steps * info(c.integrator).force_passes);
  EXPECT_TRUE(within_rounding(g, a, rounding_bound(a, r, {1e-6, 1e-4})));
  EXPECT_NEAR(g.t, a.t, 1e-9);
}

std::vector<Case> cases() {
  std::vector<Case> out;
  for (bool compute : {false, true})
    for (const auto& i : integrators())
      if (i.id != Integrator::backward_euler) out.push_back({compute, i.id});
  return out;
}

INSTANTIATE_TEST_SUITE_P(Gl, GlUpdatePass, testing::ValuesIn(cases()),
                         [](const testing::TestParamInfo<Case>& p) {
                           std::string s = std::string(p.param.compute ? "compute_" : "tf_") +
                                           std::string(deformlab::info(p.param.integrator).name);
                           for (char& ch : s)
                             if (ch == '-') ch = '_';
                           return s;
                         });

}  // namespace
}  // namespace deformlab::test
