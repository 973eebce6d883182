// The registry's traits: every pipeline name carries the same traits and options in every
// build, whether its backend is built or stands in as unavailable.
#include <gtest/gtest.h>

#include "experiments/pipelines.hpp"

namespace deformlab {
namespace {

TEST(Pipelines, TraitsAreTheSameInEveryBuild) {
  const PipelineRegistry& r = pipelines();
  for (const char* n : {"cpu", "omp", "cuda-naive", "cuda-tiled", "cuda-fused"})
    EXPECT_EQ(r.find(n)->traits.cpu_match, CpuMatch::bitwise) << n;
  for (const char* n : {"reference", "cuda-scatter", "glsl-tf", "glsl-compute", "hybrid", "hybrid-compute"})
    EXPECT_EQ(r.find(n)->traits.cpu_match, CpuMatch::rounding) << n;
  for (const auto& e : r.all()) EXPECT_EQ(e.traits.deterministic, e.name != "cuda-scatter") << e.name;
  for (const auto& e : r.all()) EXPECT_EQ(e.traits.hands_off(), e.name.starts_with("hybrid")) << e.name;
  EXPECT_EQ(r.find("hybrid")->traits.update, Engine::gl_transform_feedback);
  EXPECT_EQ(r.find("hybrid-compute")->traits.update, Engine::gl_compute);
  EXPECT_EQ(r.find("cpu")->traits.force, Engine::cpu);
  EXPECT_EQ(r.find("cuda-tiled")->options, std::vector<std::string>{"tile"});
  EXPECT_EQ(r.find("hybrid")->options, (std::vector<std::string>{"interop", "force", "tile"}));
}

}  // namespace
}  // namespace deformlab
