// Both GL pipelines, every integrator they run: 50 steps from a perturbed, moving state on a
// 32x32 cloth and a 6x5x4 lattice, against the CPU float pipeline.
//
// Tolerance: the GL and CPU float pipelines do the same float operations, but the GPU may
// contract a*b+c into one rounding (FMA), sums a node's springs in another order (stencil
// order vs adjacency order) and its 1/x and sqrt are allowed a few ulp. These are rounding
// differences of the size float rounding itself makes, so the GL-vs-CPU difference is held
// to a small multiple of the CPU float pipeline's own distance from the double reference
// (the measure of float rounding on this very trajectory), plus a floor of a few ulp of the
// coordinates (1 m scale: 1e-6 m, 1e-4 m/s). On grids the shaders also use one rest length
// per offset where the builder's differ by the rounding of the float rest positions (an
// effect of the same size). Measured on llvmpipe the ratio is at most 2.5; the bound is 8,
// while a real fault (a missing spring, a wrong sign) shows as 1e-3 m and more.
// The "general" shape is the cloth without its grid dimensions: the adjacency-buffer path.
// Explicit Euler takes dt = 0.1 ms: at 1 ms it grows ~1.4x per step on these springs and
// 50 steps would compare two blown-up states.
#include <cmath>

#include "core/cpu_backend.hpp"
#include "gl_test_support.hpp"
#include "gl/gl_pipeline.hpp"
#include "tests/support/test_states.hpp"

namespace deformlab::test {
namespace {

enum class Shape { cloth, lattice, general };  // general: the cloth without its grid dims

struct Case {
  std::string pipeline;
  Integrator integrator;
  Shape shape;
};

std::string case_name(const testing::TestParamInfo<Case>& p) {
  static const char* shape[] = {"_cloth", "_lattice", "_general"};
  std::string s = p.param.pipeline + "_" + std::string(info(p.param.integrator).name) + shape[int(p.param.shape)];
  for (char& c : s)
    if (c == '-') c = '_';
  return s;
}

class MatchCpu : public testing::TestWithParam<Case> {};

TEST_P(MatchCpu, FiftyStepsFromAMovingState) {
  DEFORMLAB_REQUIRE_GL();
  const Case& c = GetParam();
  Model m = c.shape == Shape::lattice ? small_lattice(6, 5, 4) : small_cloth(32, 32);
  if (c.shape == Shape::general) m.topology = Topology::general;
  m.damping = {0.02f, 0.02f, 0.01f};
  Params p = small_params();
  if (c.integrator == Integrator::explicit_euler) p.dt = 1e-4f;
  p.wind = {0.002f, 0.f, -0.001f};
  p.drag.node = m.node_count() / 2 + 3;  // a free node pulled by a drag spring
  p.drag.as_spring = true;
  p.drag.stiffness = 50.f;
  p.drag.path = {{0.f, m.rest_position[p.drag.node]}, {0.1f, m.rest_position[p.drag.node] + Vec3f{0.05f, 0.02f, 0.f}}};
  const State s0 = perturbed_state(m, 7);
  const int steps = 50;

  const PipelineSetup setup{m, p, c.integrator};
  auto gpu = make_gl(c.pipeline, setup);
  EXPECT_EQ(dynamic_cast<gl::GlPipeline&>(*gpu).neighbour_mode(),
            c.shape == Shape::general ? "adjacency buffer" : "grid arithmetic");
  auto f32 = make_cpu_pipeline(setup, Precision::f32, false);
  auto f64 = make_cpu_pipeline(setup, Precision::f64, false);
  const State g = advance(*gpu, s0, steps), a = advance(*f32, s0, steps), r = advance(*f64, s0, steps);

  const double rounding_x = max_position_diff(a, r), rounding_v = max_velocity_diff(a, r);
  const double dx = max_position_diff(g, a), dv = max_velocity_diff(g, a);
  const double tol_x = std::max(8.0 * rounding_x, 1e-6), tol_v = std::max(8.0 * rounding_v, 1e-4);
  RecordProperty("position_diff_m", std::to_string(dx));
  EXPECT_LE(dx, tol_x) << "float rounding on this trajectory: " << rounding_x << " m";
  EXPECT_LE(dv, tol_v) << "float rounding on this trajectory: " << rounding_v << " m/s";
  EXPECT_NEAR(g.t, a.t, 1e-9);
  EXPECT_EQ(g.x_prev.empty(), a.x_prev.empty());
  if (!g.x_prev.empty()) {
    State gp = g, ap = a;
    gp.x = g.x_prev;
    ap.x = a.x_prev;
    EXPECT_LE(max_position_diff(gp, ap), tol_x);
  }
  std::printf("%s: |x - x_cpu| = %.3g m (tolerance %.3g), |v - v_cpu| = %.3g m/s (tolerance %.3g)\n",
              case_name({c, 0}).c_str(), dx, tol_x, dv, tol_v);
}

std::vector<Case> cases() {
  std::vector<Case> out;
  for (const char* pipe : {"glsl-tf", "glsl-compute"})
    for (const auto& i : integrators())
      if (i.id != Integrator::backward_euler)
        for (Shape shape : {Shape::cloth, Shape::lattice, Shape::general}) out.push_back({pipe, i.id, shape});
  return out;
}

INSTANTIATE_TEST_SUITE_P(Gl, MatchCpu, testing::ValuesIn(cases()), case_name);

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
