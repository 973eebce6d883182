// Every pipeline in the registry against the CPU float pipeline (`cpu`), for every
// integrator it runs, on every model shape below: 50 steps from a perturbed, moving state
// with wind, spring damping and a drag spring (on one shape: ground, spheres and a hard drag). Pipelines that a build or machine lacks skip
// with the reason; `reference` (double) is the yardstick, not a subject.
//
// What each pipeline promises is its registry trait under the case's options (cpu_match in
// core/pipeline.hpp: math=fast compares by rounding):
// - bitwise: the same float operations in the same order as `cpu` (omp, the CUDA gather
//   kernels: no FMA contraction, the same stencil and adjacency order): equal states, bit
//   for bit, and the same stop-rule displacement;
// - rounding: the same formulas with other roundings (with math=fast GLSL may contract a*b+c,
//   approximate 1/x and sqrt and sum a dot product in another order; with math=exact it does
//   `cpu`'s operations, but a GPU may flush subnormals; the scatter kernels add in atomic
//   order). Those differences are the size float rounding itself makes, so they are held to
//   8 x the `cpu` pipeline's own distance from the double reference on this very trajectory,
//   largest and root mean square over nodes (rounding_bound), with a floor of a few ulp of the
//   coordinates (1 m scale: 1e-6 m, 1e-4 m/s). On a software renderer (llvmpipe keeps
//   subnormals) GL's exact math must give `cpu`'s bits; with math=fast llvmpipe measured at most
//   2.2x; a real fault (a missing spring, a stale buffer after a hand-off) shows as 1e-3 m and more.
// Deterministic pipelines also repeat their own bits on a second run.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "core/cpu_backend.hpp"
#include "core/node_order.hpp"
#if DEFORMLAB_HAVE_GL
#include "gl/context.hpp"
#endif
#include "experiments/pipelines.hpp"
#include "tests/support/test_states.hpp"
#include "tests/support/gpu_required.hpp"

namespace deformlab::test {
namespace {

struct Shape {
  const char* name;
  int nx, ny, nz;  // nz > 0: lattice
  bool damped;
  bool general = false;  // the same springs without the grid: the adjacency paths
  bool contact = false;  // ground and spheres cutting the cloth, the drag node held on its path
  enum { grid, surface, volume } mesh = grid;  // meshes: jittered, shuffled node order (the adjacency paths at their worst)
};
const Shape kShapes[] = {
    {"cloth32", 32, 32, 0, true},       {"cloth37x53", 37, 53, 0, false},  // not a multiple of any tile
    {"cloth2x3", 2, 3, 0, true},        {"lattice6x5x4", 6, 5, 4, true},
    {"lattice3x4x5", 3, 4, 5, false},  // too narrow for the interior stencil anywhere
    {"general32", 32, 32, 0, true, true},       {"contact37x53", 37, 53, 0, true, false, true},
    {"surface30x20", 30, 20, 0, true, true, false, Shape::surface},
    {"volume8x6x5", 8, 6, 5, true, true, false, Shape::volume},
    {"general11x7", 11, 7, 0, false, true},  // undamped adjacency: no neighbour velocities read
    {"cloth1x1", 1, 1, 0, false},  // one free node and no springs
};

// Option values tried beyond the defaults, by option name (PipelineEntry::options), the
// shapes (kShapes) they are tried on, the integrators (by default one and several force
// passes) and other options set with them.
struct OptionValues {
  const char* option;
  std::vector<std::string> values;
  std::vector<int> shapes;
  std::vector<Integrator> integrators = {Integrator::semi_implicit_euler, Integrator::rk4};
  PipelineOptions with = {};
};
// The one-pass rules of the fused kernels (each its own update code), and a multi-pass one.
const std::vector<Integrator> kOnePass = {Integrator::explicit_euler, Integrator::semi_implicit_euler,
                                          Integrator::verlet};
const std::vector<Integrator> kOnePassAndRk4 = {Integrator::explicit_euler, Integrator::semi_implicit_euler,
                                                Integrator::verlet, Integrator::rk4};
const OptionValues kOptionValues[] = {
    {"force", {"tiled", "scatter"}, {0, 3, 7, 8, 9}},
    // each mode (the default, external-gpusync where the driver has it, else map, runs above)
    {"interop", {"map", "external", "external-gpusync", "staged"}, {0, 3}},
    {"tile", {"8x4"}, {1, 7, 8}},       // blocks off the grid's sizes; 32-node mesh tiles
    {"link_view", {"2048"}, {7, 8}},  // a mesh's links in 3-4 texture-buffer views
    {"window", {"400"}, {0, 6}, kOnePassAndRk4},  // glsl-compute's passes window by window (grids)
    // cuda-temporal: launches of 1 and 3 steps (50 = 16 x 3 + 2)
    {"steps_per_launch", {"1", "3"}, {1, 3, 6}, kOnePassAndRk4},
    {"math", {"fast"}, {0, 6, 7, 9}, kOnePassAndRk4},  // exact is the default: every case above runs it
    // cuda-fused's cloths: exact math's default kernel (the TMA copy, on a device of compute
    // capability 9.0 or more) left out, and taken in fast math
    {"tma", {"off"}, {0, 1, 6}, kOnePass},
    {"tma", {"on"}, {0, 1, 6}, kOnePass, {{"math", "fast"}}},
    // GL's own buffers: the default where CUDA's memory can be imported (every case above there)
    {"memory", {"gl"}, {0, 6, 8}},
};

struct Case {
  std::string pipeline;
  Integrator integrator;
  int shape;
  PipelineOptions options = {};
};

std::string case_name(const testing::TestParamInfo<Case>& p) {
  const Case& c = p.param;
  std::string s = c.pipeline + "_" + std::string(info(c.integrator).name) + "_" + kShapes[c.shape].name;
  for (const auto& [k, v] : c.options) s += "_" + k + "_" + v;
  for (char& ch : s)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return s;
}

Model make_model(const Shape& s) {
  if (s.mesh != Shape::grid) {
    Mesh mesh = s.mesh == Shape::surface ? triangulated_square(s.nx, s.ny, 0.25f) : tetrahedralised_box(s.nx, s.ny, s.nz, 0.25f);
    repair(mesh);
    Model m = mesh_model(mesh, Material{}, 0.f);
    m.damping = {0.02f, 0.02f, 0.01f};
    pin(m, {0, s.nx - 1});
    reorder(m, node_order(m, NodeOrder::shuffled, 11));
    return m;
  }
  Model m = s.nz > 0 ? small_lattice(s.nx, s.ny, s.nz) : small_cloth(s.nx, s.ny, s.nx * s.ny > 1);  // 1x1: free
  if (s.damped) m.damping = {0.02f, 0.02f, 0.01f};
  return s.general ? explicit_springs(m) : m;
}

Params make_params(const Shape& s, const Model& m, Integrator i) {
  Params p = moving_params(m, i);
  if (s.contact) {
    p.ground = 0.995f;  // just under the cloth: gravity and the perturbation push nodes below
    p.spheres = {{{0.f, 0.9f, 0.f}, 0.12f}, {{0.5f, 0.97f, 0.3f}, 0.06f}};  // both cut the cloth from below
    p.drag.as_spring = false;
  }
  return p;
}

constexpr int kSteps = 50;

// Whether `e` with options `o` runs every pass in GL with exact math on a software renderer,
// which keeps subnormals where a GPU may flush them: there it does `cpu`'s operations bit for bit.
bool gl_exact_on_software(const PipelineEntry& e, const PipelineOptions& o) {
#if DEFORMLAB_HAVE_GL
  return is_gl(e.traits.force) && is_gl(e.traits.update) && math_option(o) == Math::exact && gl::context().software;
#else
  (void)e, (void)o;
  return false;
#endif
}

class MatchCpu : public testing::TestWithParam<Case> {};

TEST_P(MatchCpu, FiftyStepsFromAMovingState) {
  const Case& c = GetParam();
  const PipelineEntry& e = *pipelines().find(c.pipeline);
  DEFORMLAB_SKIP_IF_UNAVAILABLE(e.unavailable());
  const Model m = make_model(kShapes[c.shape]);
  const Params p = make_params(kShapes[c.shape], m, c.integrator);
  const State s0 = perturbed_state(m, 7u + unsigned(c.shape));
  const PipelineSetup setup{m, p, c.integrator, c.options};
  if (c.options.contains("tma") && c.options.at("tma") == "on") {
    // Where exact math's default leaves the accelerator out, the device or the build lacks it: a
    // skip, or a failure where every GPU stage is required.
    const auto chosen = e.make({m, p, c.integrator})->chosen_options();
    DEFORMLAB_SKIP_IF_UNAVAILABLE(chosen.contains("tma") && chosen.at("tma") == "on"
                                      ? ""
                                      : "no tensor memory accelerator here (a device of compute capability 9.0 or "
                                        "more, a build for architectures 90 and up)");
  }

  auto subject = e.make(setup);
  const State g = advance(*subject, s0, kSteps);
  const double g_disp = subject->max_displacement();
  auto cpu = make_cpu_pipeline(setup, Precision::f32, false);
  const State a = advance(*cpu, s0, kSteps);
  const double a_disp = cpu->max_displacement();
  ASSERT_GT(max_position_diff(a, s0), 1e-4) << "the scene must move";

  const bool scatter = c.options.contains("force") && c.options.at("force") == "scatter";
  if (cpu_match(e, c.options) == CpuMatch::bitwise || gl_exact_on_software(e, c.options)) {
    EXPECT_TRUE(bitwise_equal(g, a)) << "|x - x_cpu| = " << max_position_diff(g, a) << " m, |v - v_cpu| = "
                                     << max_velocity_diff(g, a) << " m/s";
    EXPECT_EQ(g_disp, a_disp);
  } else {
    auto ref = make_cpu_pipeline(setup, Precision::f64, false);
    const RoundingBound b = rounding_bound(a, advance(*ref, s0, kSteps), {1e-6, 1e-4});
    const testing::AssertionResult near = within_rounding(g, a, b);
    EXPECT_TRUE(near);
    EXPECT_LE(std::abs(g_disp - a_disp), 2 * b.max.x);
    EXPECT_EQ(g.t, a.t);
    std::printf("%s: %s\n", case_name({c, 0}).c_str(), near.message());
  }
  if (e.traits.deterministic && !scatter) {
    auto again = e.make(setup);
    EXPECT_TRUE(bitwise_equal(advance(*again, s0, kSteps), g)) << "a second run differs";
    // What a warm-up relies on: set_state after steps starts the run again.
    EXPECT_TRUE(bitwise_equal(advance(*subject, s0, kSteps), g)) << "a run from set_state after steps differs";
  }
}

// Whether pipeline e runs shape s (grids_only: not general models).
bool runs(const PipelineEntry& e, int s) {
  return !e.traits.grids_only || (!kShapes[s].general && kShapes[s].mesh == Shape::grid);
}

Topology topology(const Shape& s) {
  if (s.general || s.mesh != Shape::grid) return Topology::general;
  return s.nz > 0 ? Topology::lattice : Topology::cloth_grid;
}

// The registry's pipelines x the integrators each runs x the shapes, with default options;
// each non-default option value on its integrators and shapes, where it acts (a run refuses
// one that would do nothing on the model: check_options).
std::vector<Case> cases() {
  std::vector<Case> out;
  for (const PipelineEntry& e : pipelines().all()) {
    if (e.name == "cpu" || e.name == "reference") continue;
    if (const std::string why = e.unavailable(); !why.empty() && e.unsupported(Integrator::semi_implicit_euler) == why) {
      out.push_back({e.name, Integrator::semi_implicit_euler, 0});  // not in this build: one case, which skips saying so
      continue;
    }
    for (const IntegratorInfo& i : integrators()) {
      if (!e.unsupported(i.id).empty()) continue;
      for (int s = 0; s < int(std::size(kShapes)); ++s)
        if (runs(e, s)) out.push_back({e.name, i.id, s});
    }
    for (const auto& [option, values, shapes, integs, with] : kOptionValues) {
      if (!reads_option(e, option)) continue;
      for (const std::string& v : values)
        for (Integrator i : integs)
          for (int s : shapes) {
            PipelineOptions o = with;
            o[option] = v;
            const bool idle = e.idle_option && !e.idle_option(o, topology(kShapes[s])).empty();
            if (runs(e, s) && e.unsupported(i).empty() && !idle) out.push_back({e.name, i, s, o});
          }
    }
  }
  return out;
}

INSTANTIATE_TEST_SUITE_P(Pipelines, MatchCpu, testing::ValuesIn(cases()), case_name);

}  // namespace
}  // namespace deformlab::test
