// What only the CUDA pipelines have: graphs and tile shapes that change no bit, Verlet's
// given half-step velocity, the device's displacement reduction, memory checks,
// the registry's variants and the profiled passes. Against the CPU: tests/match.
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <limits>
#include <map>
#include <stdexcept>
#include <tuple>

#include "cuda_kernels/pipelines.hpp"
#include "cuda_test_support.hpp"

namespace deformlab::test {
namespace {

using cuda::Variant;

constexpr int kSteps = 12;

struct Shape {
  const char* name;
  int nx, ny, nz;  // nz > 0: lattice
  bool damped;     // spring damping on (exercises the neighbour-velocity loads)
};
// (Every shape of the match tests, tests/match, runs on every pipeline against the CPU there.)
const Shape kShapes[] = {
    {"2x3", 2, 3, 0, true},       {"37x53", 37, 53, 0, true},   {"130x70", 130, 70, 0, false},
    {"256x256", 256, 256, 0, true}, {"lattice7x5x6", 7, 5, 6, true},
};

Model make_model(const Shape& s) {
  Model m = s.nz > 0 ? small_lattice(s.nx, s.ny, s.nz) : small_cloth(s.nx, s.ny);
  if (s.damped) m.damping = {0.02f, 0.02f, 0.01f};
  return m;
}

Params scene_params() {
  Params p = small_params();
  p.wind = {0.002f, 0.f, -0.001f};
  return p;
}

State run_cpu(const Model& m, const Params& p, Integrator i, const State& s0, Precision prec = Precision::f32,
              double* disp = nullptr) {
  auto cpu = make_cpu_pipeline({m, p, i}, prec, true);
  State s = advance(*cpu, s0, kSteps);
  if (disp) *disp = cpu->max_displacement();
  return s;
}

const Integrator kIntegrators[] = {Integrator::explicit_euler, Integrator::semi_implicit_euler, Integrator::midpoint,
                                   Integrator::rk3, Integrator::rk4, Integrator::verlet};
const Variant kVariants[] = {Variant::naive, Variant::tiled, Variant::scatter, Variant::fused};

TEST(CudaPipeline, GatherVariantsAreBitwiseEqualRunToRun) {
  DEFORMLAB_REQUIRE_CUDA();
  for (const Shape& shape : {kShapes[3], kShapes[4]}) {
    const Model m = make_model(shape);
    const Params p = scene_params();
    const State s0 = perturbed_state(m, 7u);
    for (Variant v : {Variant::naive, Variant::tiled, Variant::fused})
      for (Integrator i : kIntegrators) {
        auto a = cuda::make_pipeline({m, p, i}, options(v, true));
        auto b = cuda::make_pipeline({m, p, i}, options(v, false));  // also: graphs change nothing
        EXPECT_TRUE(bitwise_equal(advance(*a, s0, kSteps), advance(*b, s0, kSteps)))
            << name(v) << " " << info(i).name << " " << shape.name;
        const State again = advance(*a, s0, kSteps);  // set_state restarts the same pipeline
        EXPECT_TRUE(bitwise_equal(again, advance(*b, s0, kSteps))) << name(v) << " " << info(i).name;
      }
  }
}

TEST(CudaPipeline, EveryTileShapeGivesTheSameBits) {
  DEFORMLAB_REQUIRE_CUDA();
  for (const Shape& shape : {kShapes[2], kShapes[4]}) {
    const Model m = make_model(shape);
    const Params p = scene_params();
    const State s0 = perturbed_state(m, 11u);
    const State want = run_cpu(m, p, Integrator::semi_implicit_euler, s0);
    for (cuda::Tile t : {cuda::Tile{8, 8}, cuda::Tile{16, 16}, cuda::Tile{5, 3}, cuda::Tile{64, 4}, cuda::Tile{1, 1}})
      for (Variant v : {Variant::tiled, Variant::naive, Variant::fused}) {
        auto g = cuda::make_pipeline({m, p, Integrator::semi_implicit_euler}, options(v, true, t));
        EXPECT_TRUE(bitwise_equal(advance(*g, s0, kSteps), want))
            << name(v) << " tile " << t.x << "x" << t.y << " " << shape.name;
      }
  }
}

TEST(CudaPipeline, VerletContinuesFromAHalfStepVelocity) {
  DEFORMLAB_REQUIRE_CUDA();
  const Model m = make_model(kShapes[1]);
  const Params p = scene_params();
  auto cpu = make_cpu_pipeline({m, p, Integrator::verlet}, Precision::f32, false);
  const State mid = advance(*cpu, perturbed_state(m, 5u), 4);
  ASSERT_TRUE(mid.half_step);
  const State want = advance(*cpu, mid, kSteps);
  for (Variant v : {Variant::naive, Variant::tiled, Variant::fused}) {
    auto g = cuda::make_pipeline({m, p, Integrator::verlet}, options(v));
    EXPECT_TRUE(bitwise_equal(advance(*g, mid, kSteps), want)) << name(v);
  }
}

// The stop rule's reduction runs inside the kernel that writes each step's result (update,
// combine, fused): a non-finite node makes it NaN whichever kernel that is, on grids and on
// general models.
TEST(CudaPipeline, MaxDisplacementIsNanWhenTheStateIsNotFinite) {
  DEFORMLAB_REQUIRE_CUDA();
  for (const bool general : {false, true}) {
    const Model m = general ? as_general(make_model(kShapes[1])) : make_model(kShapes[1]);
    State s = perturbed_state(m, 3u);
    s.v[100].y = std::numeric_limits<float>::quiet_NaN();
    for (Integrator i : kIntegrators)
      for (Variant v : kVariants) {
        auto g = cuda::make_pipeline({m, scene_params(), i}, options(v));
        g->set_state(s);
        EXPECT_EQ(g->max_displacement(), 0.0) << "no step yet";
        g->step();
        EXPECT_TRUE(std::isnan(g->max_displacement())) << name(v) << " " << info(i).name << " general " << general;
      }
  }
}

// Each step's largest displacement is its own and bitwise the CPU's, step after step, replayed
// as graphs or launched pass by pass, on a damped cloth whose motion dies down at some step (so
// a warp maximum left from an earlier step would show).
TEST(CudaPipeline, MaxDisplacementIsEachStepsOwn) {
  DEFORMLAB_REQUIRE_CUDA();
  const Model m = make_model(kShapes[1]);
  Params p = scene_params();
  p.gravity = p.wind = {};
  p.damping = 2.f;
  p.dt = 1e-4f;  // explicit Euler's fastest spring modes decay too
  const State s0 = perturbed_state(m, 9u, 0.f);  // springs at rest, nodes moving
  for (Integrator i : kIntegrators) {
    auto cpu = make_cpu_pipeline({m, p, i}, Precision::f32, false);
    cpu->set_state(s0);
    std::vector<double> want;
    for (int k = 0; k < kSteps; ++k) {
      cpu->step();
      want.push_back(cpu->max_displacement());
    }
    ASSERT_TRUE(std::adjacent_find(want.begin(), want.end(), std::greater<>()) != want.end())
        << info(i).name << ": the motion must slow down at some step";
    for (Variant v : {Variant::naive, Variant::tiled, Variant::fused})
      for (const bool graphs : {true, false}) {
        auto g = cuda::make_pipeline({m, p, i}, options(v, graphs));
        g->set_state(s0);
        for (int k = 0; k < kSteps; ++k) {
          g->step();
          EXPECT_EQ(g->max_displacement(), want[k]) << name(v) << " " << info(i).name << " step " << k + 1;
        }
      }
  }
}

TEST(CudaPipeline, RefusesASizeThatDoesNotFit) {
  DEFORMLAB_REQUIRE_CUDA();
  try {
    cuda::require_device_memory(std::int64_t(1) << 50, "a test buffer");
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("a test buffer needs 1125899906842624 bytes"), std::string::npos) << what;
    EXPECT_NE(what.find("bytes are free"), std::string::npos) << what;
  }
  const Model m = make_model(kShapes[3]);
  EXPECT_NO_THROW(cuda::require_device_memory(cuda::bytes_needed(m.size(), Integrator::rk4, {}), "a 256x256 cloth"));
}

// The device memory a pipeline counts before it is built (run summaries print it a node) is
// what it allocates: exactly, but for cuda-tiled on general models, whose tiles' halos it
// bounds from above.
TEST(CudaPipeline, CountedDeviceMemoryIsWhatItAllocates) {
  DEFORMLAB_REQUIRE_CUDA();
  const Model cloth = make_model(kShapes[1]), lattice = make_model(kShapes[4]), general = explicit_springs(cloth);
  for (const Model* m : {&cloth, &lattice, &general})
    for (Variant v : {Variant::naive, Variant::tiled, Variant::scatter, Variant::fused, Variant::temporal})
      for (Integrator i : kIntegrators) {
        if (!cuda::unsupported(i, v).empty() || (v == Variant::temporal && !m->grid())) continue;
        const std::int64_t before = cuda::buffer_bytes();
        const auto p = cuda::make_pipeline({*m, scene_params(), i}, options(v));
        const std::int64_t allocated = cuda::buffer_bytes() - before, counted = cuda::bytes_needed(m->size(), i, options(v));
        const std::string what = std::string(info(i).name) + " on " + cuda::to_string(v) + ", " +
                                 std::to_string(m->node_count()) + " nodes" + (m->grid() ? "" : ", general");
        if (v == Variant::tiled && !m->grid()) {  // measured on an H200: 75% of the bound
          EXPECT_LE(allocated, counted) << what;
          EXPECT_GT(allocated, counted / 2) << what;
        } else {
          EXPECT_EQ(allocated, counted) << what;
        }
      }
}

// ---- no device needed ----

TEST(CudaPipeline, BackwardEulerIsRefusedWithAReason) {
  for (Variant v : kVariants) {
    EXPECT_NE(cuda::unsupported(Integrator::backward_euler, v).find("backward-euler"), std::string::npos);
    for (Integrator i : kIntegrators) EXPECT_EQ(cuda::unsupported(i, v), "");
  }
  const Model m = make_model(kShapes[0]);
  EXPECT_THROW(cuda::make_pipeline({m, scene_params(), Integrator::backward_euler}, {}), std::invalid_argument);
}

TEST(CudaPipeline, RegistryNamesTheFiveVariants) {
  PipelineRegistry r;
  add_cuda_pipelines(r);
  ASSERT_EQ(r.all().size(), 5u);
  for (const char* n : {"cuda-naive", "cuda-tiled", "cuda-scatter", "cuda-fused", "cuda-temporal"}) {
    const PipelineEntry* e = r.find(n);
    ASSERT_NE(e, nullptr) << n;
    EXPECT_EQ(e->traits.deterministic, std::string(n) != "cuda-scatter") << n;
    EXPECT_FALSE(e->unsupported(Integrator::backward_euler).empty());
    EXPECT_EQ(e->unavailable(), cuda::unavailable());
  }
}

TEST(CudaPipeline, WithoutADeviceMakingAPipelineFailsWithTheReason) {
  if (cuda::unavailable().empty()) GTEST_SKIP() << "a CUDA device is present";
  const Model m = make_model(kShapes[0]);
  try {
    cuda::make_pipeline({m, scene_params(), Integrator::verlet}, {});
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), cuda::unavailable());
  }
}

TEST(CudaPipeline, TileShapeTmaAndMathArePipelineOptions) {
  PipelineRegistry r;
  add_cuda_pipelines(r);
  for (const char* n : {"cuda-naive", "cuda-tiled"})
    EXPECT_EQ(r.find(n)->options, (std::vector<std::string>{"tile", "math"})) << n;
  EXPECT_EQ(r.find("cuda-fused")->options, (std::vector<std::string>{"tile", "tma", "math"}));
  EXPECT_EQ(r.find("cuda-scatter")->options, std::vector<std::string>{"math"});
  EXPECT_EQ(r.find("cuda-temporal")->options, (std::vector<std::string>{"tile", "steps_per_launch", "math"}));
  EXPECT_EQ(cuda::options_of(cuda::Variant::fused, {{"math", "fast"}}).math, Math::fast);
  EXPECT_EQ(cuda::options_of(cuda::Variant::fused, {}).math, Math::exact);
  EXPECT_THROW(cuda::options_of(cuda::Variant::fused, {{"math", "fastest"}}), std::invalid_argument);
  EXPECT_FALSE(cuda::options_of(cuda::Variant::fused, {}).tma.has_value());
  EXPECT_EQ(cuda::options_of(cuda::Variant::fused, {{"tma", "on"}}).tma, true);
  EXPECT_EQ(cuda::options_of(cuda::Variant::fused, {{"tma", "off"}}).tma, false);
  EXPECT_THROW(cuda::options_of(cuda::Variant::fused, {{"tma", "yes"}}), std::invalid_argument);
  EXPECT_EQ(cuda::tile_option({{"tile", "32x4"}}).x, 32);
  EXPECT_EQ(cuda::tile_option({}).x, cuda::Tile{}.x);
  EXPECT_THROW(cuda::tile_option({{"tile", "0x4"}}), std::invalid_argument);
}

TEST(CudaPipeline, FusedDefaultBlocksFollowTopology) {
  using cuda::Variant;
  const Model cloth = small_cloth(8, 8), lattice = small_lattice(4, 4, 4);
  auto tile = [](Variant v, const PipelineOptions& o, const Model& m) {
    return cuda::to_string(cuda::tile_for(cuda::options_of(v, o), m));
  };
  EXPECT_EQ(tile(Variant::fused, {{"math", "fast"}}, cloth), "32x8");
  EXPECT_EQ(tile(Variant::fused, {{"math", "fast"}}, lattice), "16x16");
  EXPECT_EQ(tile(Variant::fused, {}, lattice), "16x16");
  EXPECT_EQ(tile(Variant::fused, {}, cloth), "32x8");
  EXPECT_EQ(tile(Variant::naive, {}, lattice), "16x8");
  EXPECT_EQ(tile(Variant::naive, {{"math", "fast"}}, cloth), "16x8");
  EXPECT_EQ(tile(Variant::tiled, {{"math", "fast"}}, cloth), "16x8");
  EXPECT_EQ(tile(Variant::fused, {{"math", "fast"}, {"tile", "16x8"}}, cloth), "16x8");  // the option wins
}

// cuda-fused's cloth kernel through the tensor memory accelerator: taken by default in exact
// math on 32x8 blocks where the device has the accelerator (the run records the choice), on
// request in fast math; tma=on where it cannot run is refused with the reason. Its bits are
// fused_grid's: the match tests run both against cpu.
TEST(CudaPipeline, FusedClothsTakeTheTmaWhereItRuns) {
  DEFORMLAB_REQUIRE_CUDA();
  const Model cloth = make_model(kShapes[1]), lattice = make_model(kShapes[4]);
  auto make = [&](const Model& m, Integrator i, const PipelineOptions& o) {
    return cuda::make_pipeline({m, scene_params(), i}, cuda::options_of(Variant::fused, o));
  };
  auto refusal = [&](const Model& m, Integrator i, const PipelineOptions& o) -> std::string {
    try {
      make(m, i, o);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(not refused)";
  };
  const bool has_tma = cuda::device_info().cc_major >= 9;
  using Chosen = std::map<std::string, std::string>;
  EXPECT_EQ(make(cloth, Integrator::verlet, {})->chosen_options(), (Chosen{{"tma", has_tma ? "on" : "off"}}));
  // Nothing chosen by the machine where the option is given or exact math's default cannot take it.
  for (const PipelineOptions& o : {PipelineOptions{{"math", "fast"}}, {{"tma", "off"}}, {{"tile", "16x8"}}})
    EXPECT_TRUE(make(cloth, Integrator::verlet, o)->chosen_options().empty());
  EXPECT_TRUE(make(lattice, Integrator::verlet, {})->chosen_options().empty());
  EXPECT_TRUE(make(cloth, Integrator::rk4, {})->chosen_options().empty());
  if (has_tma) EXPECT_TRUE(make(cloth, Integrator::verlet, {{"tma", "on"}, {"math", "fast"}})->chosen_options().empty());
  else EXPECT_NE(refusal(cloth, Integrator::verlet, {{"tma", "on"}}).find("compute capability"), std::string::npos);
  EXPECT_NE(refusal(cloth, Integrator::verlet, {{"tma", "on"}, {"tile", "16x8"}}).find("32x8"), std::string::npos);
  EXPECT_NE(refusal(lattice, Integrator::verlet, {{"tma", "on"}}).find("grid cloths"), std::string::npos);
  EXPECT_NE(refusal(cloth, Integrator::rk4, {{"tma", "on"}}).find("one-kernel steps"), std::string::npos);
}

TEST(CudaPipeline, ParsesTileShapes) {
  EXPECT_EQ(cuda::parse_tile("16x8").x, 16);
  EXPECT_EQ(cuda::parse_tile("16x8").y, 8);
  EXPECT_EQ(cuda::parse_tile("1024x1").x, 1024);
  EXPECT_EQ(cuda::parse_tile("32x32").y, 32);
  for (const char* bad : {"", "16", "0x8", "x8", "16x", "64x64", "1025x1", "33x32", "8x8x", "a8x8", "016x8", "16x08",
                          "+16x8", " 16x8"})
    EXPECT_THROW(cuda::parse_tile(bad), std::invalid_argument) << bad;
}

// Profiled steps: the split pipelines time their force and update passes apart (midpoint:
// two of each per step), cuda-fused its one force+update kernel, all by CUDA events; a
// profiled run (pass by pass) ends in the same state as an unprofiled one (graph replays).
// (The variants here are deterministic; cuda-scatter's atomics are not bitwise repeatable.)
TEST(CudaProfile, SpansPerPassAndTheSameState) {
  DEFORMLAB_REQUIRE_CUDA();
  const Model m = small_cloth(24, 20);
  const Params p = small_params();
  const State s0 = perturbed_state(m, 5);
  for (const auto& [variant, integ, expect] :
       {std::tuple{cuda::Variant::naive, Integrator::midpoint, std::map<std::string, int>{{"force", 2}, {"update", 2}}},
        std::tuple{cuda::Variant::tiled, Integrator::semi_implicit_euler,
                   std::map<std::string, int>{{"force", 1}, {"update", 1}}},
        std::tuple{cuda::Variant::fused, Integrator::verlet, std::map<std::string, int>{{"force+update", 1}}}}) {
    SCOPED_TRACE(cuda::to_string(variant));
    auto profiled = cuda::make_pipeline({m, p, integ}, {variant});
    Profiler prof;
    profiled->set_state(s0);
    profiled->set_profiler(&prof);
    constexpr int steps = 6;
    for (int k = 1; k <= steps; ++k) {
      prof.set_step(k);
      profiled->step();
    }
    profiled->set_profiler(nullptr);  // collects the pending spans
    std::map<std::string, int> count;
    for (const Span& s : prof.spans()) {
      ++count[s.name];
      EXPECT_EQ(s.clock, "CUDA events");
      EXPECT_GT(s.ms, 0.0) << s.name;
      EXPECT_GE(s.step, 1);
    }
    std::map<std::string, int> per_step;
    for (const auto& [name, n] : expect) per_step[name] = n * steps;
    EXPECT_EQ(count, per_step);
    auto plain = cuda::make_pipeline({m, p, integ}, {variant});
    EXPECT_TRUE(bitwise_equal(advance(*plain, s0, steps), profiled->state()));
  }
}

// A profiler sampling one window of 8 steps in 2: spans in steps 1-8 and 17-24 only (the
// steps between replay the step graph), and the same state as an unprofiled run.
TEST(CudaProfile, SpansOnlyInTheSampledSteps) {
  DEFORMLAB_REQUIRE_CUDA();
  const Model m = small_cloth(24, 20);
  const Params p = small_params();
  const State s0 = perturbed_state(m, 5);
  for (const auto integ : {Integrator::semi_implicit_euler, Integrator::verlet}) {
    SCOPED_TRACE(info(integ).name);
    auto profiled = cuda::make_pipeline({m, p, integ}, {cuda::Variant::fused});
    EXPECT_EQ(sampled_span_steps(*profiled, s0, 24, 2),
              (std::vector<int>{1, 2, 3, 4, 5, 6, 7, 8, 17, 18, 19, 20, 21, 22, 23, 24}));
    auto plain = cuda::make_pipeline({m, p, integ}, {cuda::Variant::fused});
    EXPECT_TRUE(bitwise_equal(advance(*plain, s0, 24), profiled->state()));
  }
}

}  // namespace
}  // namespace deformlab::test
