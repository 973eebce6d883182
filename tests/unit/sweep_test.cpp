// The experiment runner: cells, n/a with reasons, cut cells, resume, atomic files, and the
// report generated from a fixed results folder.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "experiments/experiment.hpp"
#include "experiments/pipelines.hpp"
#include "experiments/report.hpp"
#include "experiments/sweep.hpp"

namespace deformlab {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

class SweepTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("deformlab-sweep-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  static Experiment tiny(const std::string& sweep) {
    return parse_experiment(R"({"name": "tiny", "base": "paper-drag", "integrator": "midpoint",
                                "scene": {"model": {"size": [4, 4]}}, "sweep": )" + sweep + "}", "tiny.json");
  }
  static std::string slurp(const fs::path& p) {
    std::ifstream in(p);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }
  fs::path dir_;
};

TEST_F(SweepTest, RunsResumesAndRecordsUnavailableCells) {
  const Experiment x = tiny(R"({"sizes": [4, 6], "pipelines": ["cpu", "omp", "cuda-naive", "glsl-tf"],
                                "warmup": 2, "steps": 3, "repetitions": 3})");
  const Sweep s = *parse_sweep(x.raw, "tiny");
  ASSERT_EQ(cells(s).size(), 8u);
  EXPECT_EQ(run_sweep(x, s, dir_, {}, json::array()), 8);
  const auto results = load_cells(dir_);
  ASSERT_EQ(results.size(), 8u);
  for (const auto& r : results) {
    const PipelineEntry& e = *pipelines().find(r["pipeline"]);
    if (e.unavailable().empty()) {
      ASSERT_EQ(r["status"], "ok") << r.dump();
      EXPECT_GT(r["median_ms"].get<double>(), 0.0);
      EXPECT_EQ(r["samples_ms"].size(), 3u);
      EXPECT_EQ(r["integrator"], "midpoint");
    } else {
      EXPECT_EQ(r["status"], "n/a");
      EXPECT_EQ(r["reason"], e.unavailable());
    }
  }
  // Re-running skips what is measured and tries n/a cells again; a missing cell is redone.
  int na = 0;
  for (const auto& r : results) na += r["status"] == "n/a";
  EXPECT_EQ(run_sweep(x, s, dir_, {}, json::array()), na);
  fs::remove(dir_ / "cells" / (Cell{6, "omp", "midpoint", {}}.id() + ".json"));
  int seen_skipped = 0;
  SweepOptions o;
  o.on_cell = [&](const Cell&, const json&, const SweepProgress& p) { seen_skipped = p.skipped; };
  EXPECT_EQ(run_sweep(x, s, dir_, o, json::array()), 1 + na);
  EXPECT_EQ(seen_skipped, 7 - na);
  for (const auto& f : fs::recursive_directory_iterator(dir_))
    EXPECT_EQ(f.path().string().find(".tmp-"), std::string::npos) << f.path();
}

TEST_F(SweepTest, SlowCellsAreCutWithTheReason) {
  const Experiment x = tiny(R"({"sizes": [8], "pipelines": ["cpu"], "cell_limit_s": 1e-9})");
  ModelCache cache;
  const json r = run_cell(x, *parse_sweep(x.raw, "tiny"), {8, "cpu", "midpoint", {}}, cache);
  EXPECT_EQ(r["status"], "n/a");
  EXPECT_EQ(r["reason"].get<std::string>().rfind("cut: the first step took", 0), 0u) << r.dump();
}

TEST_F(SweepTest, OptionSetsGoToThePipelinesThatReadThem) {
  const Experiment x = tiny(R"({"sizes": [4], "pipelines": ["cpu", "omp"],
                                "options": [{"tile": "8x8"}, {"tile": "16x16"}]})");
  const auto cs = cells(*parse_sweep(x.raw, "tiny"));
  ASSERT_EQ(cs.size(), 2u);  // neither reads "tile": each runs once, without options
  EXPECT_TRUE(cs[0].options.empty() && cs[1].options.empty());
}

TEST_F(SweepTest, BadSweepsAreNamed) {
  auto error = [](const std::string& sweep) {
    try {
      const Experiment x = tiny(sweep);
      parse_sweep(x.raw, "tiny");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error(R"({"sizes": [4], "pipelines": ["warp"]})").find("unknown pipeline 'warp'"), std::string::npos);
  EXPECT_NE(error(R"({"sizes": [4], "pipelines": ["cpu"], "integrators": ["leap"]})").find("unknown integrator"),
            std::string::npos);
  EXPECT_NE(error(R"({"sizes": [0], "pipelines": ["cpu"]})").find("sweep.sizes"), std::string::npos);
  EXPECT_NE(error(R"({"sizes": [4], "pipelines": ["cpu"], "reps": 3})").find("sweep.reps: unknown key"),
            std::string::npos);
}

TEST_F(SweepTest, ReportFromAFixedResultsFolder) {
  fs::create_directories(dir_ / "cells");
  const json experiment = json::parse(R"({"name": "fixed", "description": "A fixed table.", "integrator": "explicit-euler",
      "sweep": {"sizes": [64, 512], "pipelines": ["omp", "glsl-tf"], "paper_table": "table2"}})");
  std::ofstream(dir_ / "manifest.json") << json{{"experiment", experiment},
                                                {"build", {{"deformlab", "0"}, {"git", "g"}, {"compiler", "c"}, {"cuda", "none"}}},
                                                {"machine", {{"cpu", "test cpu"}, {"hardware_threads", 2}, {"os", "test os"}}},
                                                {"pipelines", {{"omp", "available"}, {"glsl-tf", "available"}}}}
                                                   .dump();
  auto cell = [&](const std::string& p, int n, double ms) {
    json c = {{"id", p + std::to_string(n)}, {"size", n}, {"pipeline", p}, {"integrator", "explicit-euler"},
              {"options", json::object()}, {"nodes", n * n}, {"status", "ok"}, {"median_ms", ms}, {"method", "fixed"}};
    std::ofstream(dir_ / "cells" / (p + std::to_string(n) + ".json")) << c.dump();
  };
  cell("omp", 64, 10.0);
  cell("glsl-tf", 64, 2.0);
  cell("omp", 512, 40.0);
  {  // a cell whose state went non-finite while it was timed
    std::ifstream in(dir_ / "cells" / "omp512.json");
    json c = json::parse(in);
    c["stable"] = false;
    std::ofstream(dir_ / "cells" / "omp512.json") << c.dump();
  }
  std::ofstream(dir_ / "cells" / "glsl-tf512.json")
      << json{{"id", "x"}, {"size", 512}, {"pipeline", "glsl-tf"}, {"integrator", "explicit-euler"},
              {"options", json::object()}, {"status", "n/a"}, {"reason", "cut: too slow"}}
             .dump();
  const std::string md = slurp(write_report(dir_));
  EXPECT_NE(md.find("| grid | nodes | omp | glsl-tf | paper (a) CPU | paper (b) CUDA | paper (c) CUDA shared | "
                    "paper (d) TF | a/d | paper a/d |"),
            std::string::npos)
      << md;
  // 64²: ours 10 and 2 ms, the paper's 99.90 ... 1.07 ms; a/d = 5 here, 93.36 there.
  EXPECT_NE(md.find("| 64² | 4096 | 10.000 | 2.000 | 99.900 | 4.050 | 2.557 | 1.070 | 5.000 | 93.364 |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| 512² | 262144 | 40.000 [1] | n/a [2] |"), std::string::npos) << md;
  EXPECT_NE(md.find("[1] the state was not finite after the timed steps: the time of a wrong result (omp 512²)"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("[2] cut: too slow (glsl-tf 512²)"), std::string::npos) << md;
  EXPECT_NE(md.find("a/d (omp / glsl-tf) at 64²: paper 93.364, here 5.000: the paper's ordering holds"),
            std::string::npos)
      << md;
  const std::string svg = slurp(dir_ / "plot-explicit-euler.svg");
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("paper (d) TF"), std::string::npos);
}

}  // namespace
}  // namespace deformlab
