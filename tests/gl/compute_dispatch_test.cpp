#include <gtest/gtest.h>

#include <array>
#include <cstdint>

#include "core/mesh_model.hpp"
#include "gl/gl_pipeline.hpp"
#include "gl/pipelines_internal.hpp"
#include "gl_test_support.hpp"
#include "tests/support/test_states.hpp"

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

// Storage-buffer windows: every node written once, each window's bound ranges within the
// limit and aligned, and every node a written node's springs reach inside its read range.
TEST(ComputeDispatch, WindowsCoverEveryNodeWithinTheLimit) {
  using W = gl::NodeWindow;
  const auto one = gl::node_windows(1000, 40, 1000, 1);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_TRUE(one[0].first == 0 && one[0].count == 1000 && one[0].read_first == 0 && one[0].read_count == 1000);
  for (auto [n, reach, max, align] : {std::array<std::int64_t, 4>{1001, 40, 1000, 1}, {100000, 130, 4096, 16},
                                      {268435456, 32768, 134217727, 16}, {134217728, 524288, 134217727, 2}}) {
    const std::vector<W> ws = gl::node_windows(n, reach, max, align);
    std::int64_t next = 0;
    for (const W& w : ws) {
      EXPECT_EQ(w.first, next);
      EXPECT_LE(w.read_count, max);
      EXPECT_LE(w.count, max);
      EXPECT_EQ(w.first % align, 0);
      EXPECT_EQ(w.read_first % align, 0);
      EXPECT_LE(w.read_first, std::max<std::int64_t>(0, w.first - reach));
      EXPECT_GE(std::int64_t(w.read_first) + w.read_count, std::min(n, std::int64_t(w.first) + w.count + reach));
      next = std::int64_t(w.first) + w.count;
    }
    EXPECT_EQ(next, n);
  }
  EXPECT_EQ(gl::node_windows(268435456, 32768, 134217727, 16).size(), 3u);  // a 16384² cloth on NVIDIA
  EXPECT_THROW(gl::node_windows(5000, 2040, 4096, 16), std::invalid_argument);  // the reach leaves no room
}

// glsl-compute run window by window (the option makes windows of a few rows) gives the bits of
// one window over the whole model, on a cloth and a lattice with every one-pass rule and RK4.
TEST(ComputeDispatch, WindowedPassesGiveTheSameBits) {
  DEFORMLAB_REQUIRE_GL();
  for (const Model& m : {small_cloth(37, 53), small_lattice(9, 7, 11)}) {
    const Params p = small_params();
    const State s0 = perturbed_state(m, 11);
    for (Integrator i : {Integrator::explicit_euler, Integrator::semi_implicit_euler, Integrator::verlet,
                         Integrator::rk4}) {
      auto whole = gl::make_compute_pipeline({m, p, i});
      auto windowed = gl::make_compute_pipeline({m, p, i, {{"window", "400"}}});
      const State a = advance(*whole, s0, 6), b = advance(*windowed, s0, 6);
      EXPECT_TRUE(bitwise_equal(a, b)) << m.nx << "x" << m.ny << "x" << m.nz << " " << info(i).name;
      EXPECT_EQ(whole->max_displacement(), windowed->max_displacement());
    }
  }
}

// A read queued after a step and taken after the next one (the word that step's result pass
// posts to the host) equals the read that waits for the step (a copy of the word), step by
// step, with one window and with several (only the first window's work group 0 posts); so
// does a read queued before its step is taken back. A read taken two steps late is refused.
TEST(ComputeDispatch, PostedWordsEqualWaitedWords) {
  DEFORMLAB_REQUIRE_GL();
  const Model m = small_cloth(37, 53);
  const Params p = small_params();
  const State s0 = perturbed_state(m, 5);
  for (const PipelineOptions& o : {PipelineOptions{}, PipelineOptions{{"window", "400"}}})
    for (Integrator i : {Integrator::semi_implicit_euler, Integrator::rk4}) {
      auto waited = gl::make_compute_pipeline({m, p, i, o}), lagged = gl::make_compute_pipeline({m, p, i, o});
      waited->set_state(s0);
      lagged->set_state(s0);
      lagged->step();
      for (int k = 1; k <= 6; ++k) {
        waited->step();
        const double w = waited->max_displacement();
        lagged->queue_displacement();
        lagged->step();
        EXPECT_EQ(lagged->take_displacement(), w) << info(i).name << ", step " << k << (o.empty() ? "" : ", windows");
        EXPECT_GT(w, 0.0);
      }
      waited->step();
      lagged->queue_displacement();
      lagged->step_back();
      EXPECT_EQ(lagged->take_displacement(), waited->max_displacement()) << info(i).name << ", taken back";
      lagged->step();
      lagged->queue_displacement();
      lagged->step();
      lagged->step();
      EXPECT_THROW(lagged->take_displacement(), std::logic_error);
    }
}

// A mesh's links beyond what the shaders' texture-buffer views hold are refused with the
// counts (the split itself is checked against the CPU by tests/match, option link_view).
TEST(LinkViews, TooManyViewsAndBadCountsAreRefused) {
  DEFORMLAB_REQUIRE_GL();
  Mesh mesh = triangulated_square(12, 10, 0.2f);
  repair(mesh);
  const Model m = mesh_model(mesh, Material{}, 0.f);
  const Params p = small_params();
  for (const char* name : {"glsl-tf", "glsl-compute"}) {
    for (const char* bad : {"16", "0", "x", "08", "+8", " 8"}) {
      try {
        make_gl(name, {m, p, Integrator::semi_implicit_euler, {{"link_view", bad}}});
        ADD_FAILURE() << name << " accepted link_view=" << bad;
      } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find(std::string(bad) == "16" ? "texture-buffer views" : "option link_view"),
                  std::string::npos)
            << e.what();
      }
    }
  }
}

}  // namespace
}  // namespace deformlab::test
