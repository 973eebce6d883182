// Options, unsupported integrators and the errors where a mode or the whole pipeline is
// unavailable; these run on every machine.
#include <gtest/gtest.h>

#include "cuda_kernels/cuda_pipeline.hpp"
#include "gl/context.hpp"
#include "interop/hybrid.hpp"
#include "interop/pipelines.hpp"
#include "tests/support/test_states.hpp"

namespace deformlab::test {
namespace {

using namespace deformlab::interop;

TEST(InteropOptions, ModesParseByTheirExperimentNames) {
  for (Mode m : kModes) EXPECT_EQ(parse_mode(to_string(m)), m);
  EXPECT_EQ(mode_names(), "map, external, external-gpusync, staged");
  EXPECT_FALSE(parse_mode("mapped").has_value());
}

TEST(InteropOptions, HybridOptionsReadInteropAndForce) {
  const HybridOptions d = hybrid_options({}, Update::compute);
  EXPECT_FALSE(d.mode.has_value());  // default_mode(), chosen where the pipeline is made
  EXPECT_EQ(d.force, cuda::Variant::naive);
  EXPECT_EQ(d.update, Update::compute);
  const HybridOptions o = hybrid_options({{"interop", "external-gpusync"}, {"force", "scatter"}}, Update::transform_feedback);
  EXPECT_EQ(o.mode, Mode::external_gpusync);
  EXPECT_EQ(o.force, cuda::Variant::scatter);
  EXPECT_THROW(hybrid_options({{"interop", "dma"}}, Update::compute), std::invalid_argument);
  EXPECT_THROW(hybrid_options({{"force", "fused"}}, Update::compute), std::invalid_argument);
  EXPECT_EQ(hybrid_options({{"tile", "32x4"}}, Update::compute).tile.x, 32);
  EXPECT_THROW(hybrid_options({{"tile", "32"}}, Update::compute), std::invalid_argument);
}

TEST(InteropOptions, RegistryDeclaresTheOptionsAndRefusesBackwardEuler) {
  PipelineRegistry r;
  add_hybrid_pipelines(r);
  for (const char* name : {"hybrid", "hybrid-compute"}) {
    const PipelineEntry* e = r.find(name);
    ASSERT_NE(e, nullptr) << name;
    EXPECT_EQ(e->options, (std::vector<std::string>{"interop", "force", "tile", "math"}));
    EXPECT_NE(e->unsupported(Integrator::backward_euler).find("linear solve"), std::string::npos);
    EXPECT_TRUE(e->unsupported(Integrator::rk4).empty());
  }
}

// Without a CUDA device (or a GL context on one) every mode says why, and making a hybrid
// pipeline fails with that reason as a std::invalid_argument (exit code 2 in the command).
TEST(InteropErrors, NoCudaDeviceGivesAClearError) {
  if (cuda::unavailable().empty() && gl::unavailable_reason().empty())
    GTEST_SKIP() << "CUDA and OpenGL are both here";
  const Model m = small_cloth(4, 4);
  const Params p = small_params();
  for (Mode mode : kModes) {
    const std::string why = unavailable(mode);
    EXPECT_FALSE(why.empty()) << to_string(mode);
    try {
      make_hybrid_pipeline({m, p, Integrator::semi_implicit_euler}, {Update::transform_feedback, mode});
      ADD_FAILURE() << "made a hybrid pipeline without CUDA";
    } catch (const std::invalid_argument& e) {
      const std::string msg = e.what();
      EXPECT_TRUE(msg.find("CUDA") != std::string::npos || msg.find("OpenGL") != std::string::npos) << msg;
      std::printf("%s: %s\n", to_string(mode), msg.c_str());
    }
  }
}

}  // namespace
}  // namespace deformlab::test
