// Sweeps timed per frame: each step followed by a 1024 x 1024 draw, as the paper's Table 2.
#include <gtest/gtest.h>

#include "experiments/experiment.hpp"
#include "experiments/sweep.hpp"
#include "gl_test_support.hpp"

namespace deformlab {
namespace {

TEST(SweepFrames, CellsTimeAStepAndADraw) {
  DEFORMLAB_REQUIRE_GL();
  const Experiment x = parse_experiment(
      R"({"name": "frames", "base": "paper-drag", "sweep": {"sizes": [16], "pipelines": ["glsl-tf", "omp"],
          "time": "frame", "warmup": 2, "steps": 2, "repetitions": 3}})",
      "frames.json");
  const Sweep s = *parse_sweep(x.raw, "frames");
  ModelCache cache;
  ASSERT_EQ(cells(s).size(), 2u);
  for (const auto& c : cells(s)) {
    const auto r = run_cell(x, s, c, cache);
    ASSERT_EQ(r["status"], "ok") << r.dump();
    EXPECT_EQ(r["time"], "frame");
    EXPECT_NE(r["method"].get<std::string>().find("1024 x 1024 draw"), std::string::npos);
    EXPECT_GT(r["median_ms"].get<double>(), 0.0);
  }
}

}  // namespace
}  // namespace deformlab
