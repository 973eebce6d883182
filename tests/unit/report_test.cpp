// The experiment report generated from a fixed results folder: row labels, plots, the paper's
// ratios, ceilings and stages.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "experiments/report.hpp"
#include "experiments/report_parts.hpp"
#include "sweep_support.hpp"

namespace deformlab {
namespace {

// A row's label in the report: the grid size (a lattice's cubed), or the mesh model and its node order.
TEST(Report, CellLabels) {
  EXPECT_EQ(report::cell_label(json{{"size", 2048}}, false), "2048²");
  EXPECT_EQ(report::cell_label(json{{"size", 16}}, true), "16³");
  EXPECT_EQ(report::cell_label(json{{"model", "sheet-1m"}, {"order", "rcm"}}, false), "sheet-1m rcm");
  EXPECT_EQ(report::cell_label(json{{"model", "bunny"}}, false), "bunny");
}

// A sweep timed by the frame labels its plot's axis so.
TEST_F(SweepTest, AFrameSweepsPlotIsInMsPerFrame) {
  fs::create_directories(dir_ / "cells");
  const json experiment = json::parse(R"({"name": "frames", "integrator": "explicit-euler",
      "sweep": {"sizes": [64], "pipelines": ["omp"], "time": "frame"}})");
  std::ofstream(dir_ / "manifest.json") << json{{"experiment", experiment}}.dump();
  std::ofstream(dir_ / "cells" / "omp64.json")
      << json{{"id", "omp64"},        {"size", 64},           {"pipeline", "omp"}, {"integrator", "explicit-euler"},
              {"options", json::object()}, {"nodes", 4096}, {"status", "ok"}, {"median_ms", 3.0},
              {"method", "fixed"}}
             .dump();
  write_report(dir_);
  const std::string svg = slurp(dir_ / "plot-explicit-euler.svg");
  EXPECT_NE(svg.find("ms per frame (update and a 1024 x 1024 draw)"), std::string::npos) << svg;
  EXPECT_EQ(svg.find("ms per step"), std::string::npos) << svg;
}

// The paper's ratio columns and reading compare its figures for one integrator (Table 2's:
// explicit Euler) with ours for that integrator only, and never a time of a state that went
// non-finite.
TEST_F(SweepTest, PaperRatiosTakeThePapersIntegratorAndStableCellsOnly) {
  fs::create_directories(dir_ / "cells");
  const json experiment = json::parse(R"({"name": "ratios", "integrator": "explicit-euler",
      "sweep": {"sizes": [64, 128], "pipelines": ["omp", "glsl-tf"], "integrators": ["explicit-euler",
                "semi-implicit-euler"], "paper_table": "table2"}})");
  std::ofstream(dir_ / "manifest.json") << json{{"experiment", experiment}}.dump();
  auto cell = [&](const std::string& p, const std::string& integ, int n, double ms, bool stable) {
    const std::string id = p + integ + std::to_string(n);
    std::ofstream(dir_ / "cells" / (id + ".json"))
        << json{{"id", id},          {"size", n},          {"pipeline", p},    {"integrator", integ},
                {"options", json::object()}, {"nodes", n * n}, {"status", "ok"}, {"median_ms", ms},
                {"method", "fixed"}, {"stable", stable}}
               .dump();
  };
  for (const char* integ : {"explicit-euler", "semi-implicit-euler"}) {
    cell("omp", integ, 64, 10.0, true);
    cell("glsl-tf", integ, 64, 2.0, true);
    cell("omp", integ, 128, 40.0, false);
    cell("glsl-tf", integ, 128, 4.0, true);
  }
  const std::string md = slurp(write_report(dir_));
  const std::size_t semi = md.find("## Integrator `semi-implicit-euler`");
  ASSERT_NE(semi, std::string::npos) << md;
  const std::string euler = md.substr(0, semi), other = md.substr(semi, md.find("\n## ", semi) - semi);
  EXPECT_NE(euler.find("| 64² | 4096 | 10.000 | 2.000 | 99.900 | 4.050 | 2.557 | 1.070 | 5.000 | 93.364 |"),
            std::string::npos)
      << md;
  EXPECT_NE(euler.find("| 128² | 16384 | 40.000 [1] | 4.000 | "), std::string::npos) << md;
  EXPECT_NE(euler.find(" | n/a | "), std::string::npos) << "the unstable cell's ratio" << md;
  EXPECT_EQ(other.find("a/d"), std::string::npos) << "no paper ratio for another integrator" << md;
  EXPECT_NE(md.find("a/d (omp / glsl-tf) at 64²: paper 93.364, here 5.000"), std::string::npos) << md;
  EXPECT_EQ(md.find("a/d (omp / glsl-tf) at 128²"), std::string::npos) << md;
}

TEST_F(SweepTest, ReportFromAFixedResultsFolder) {
  fs::create_directories(dir_ / "cells");
  const json experiment = json::parse(R"({"name": "fixed", "description": "A fixed table.", "integrator": "explicit-euler",
      "sweep": {"sizes": [64, 512, 1024], "pipelines": ["omp", "glsl-tf"], "paper_table": "table2"}})");
  std::ofstream(dir_ / "manifest.json") << json{{"experiment", experiment},
                                                {"build", {{"deformlab", "0"}, {"git", "g"}, {"compiler", "c"}, {"cuda", "none"}}},
                                                {"machine", {{"cpu", "test cpu"}, {"hardware_threads", 2}, {"os", "test os"}}},
                                                {"pipelines", {{"omp", "available"}, {"glsl-tf", "available"}}}}
                                                   .dump();
  auto cell = [&](const std::string& p, int n, double ms) {
    json c = {{"id", p + std::to_string(n)}, {"size", n}, {"pipeline", p}, {"integrator", "explicit-euler"},
              {"options", json::object()}, {"nodes", n * n}, {"status", "ok"}, {"median_ms", ms}, {"method", "fixed"},
              {"build", "g"},
              {"step_clock", p == "omp" ? "host clock" : "GL timer queries"}};
    if (p != "omp") c["chosen_options"] = {{"interop", "external-gpusync"}};  // as a hybrid would record it
    if (p != "omp")  // the GPU's clock, held down by its power cap in half of the samples
      c["sm_clock"] = {{"device", "test gpu"}, {"samples", 10}, {"sm_mhz_min", 1410}, {"sm_mhz_median", 1485},
                       {"sm_mhz_max", 1980}, {"sm_mhz_top", 1980}, {"slowed_fraction", 0.5},
                       {"slowdowns", "power cap"}, {"slowdown_bits", 4}, {"clock", "NVML"}};
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
  // 1024², in the sweep, has no cells yet (as under --max-size 512).
  EXPECT_NE(md.find("- Not measured yet: 1024² (left out by --max-size, or not reached;"), std::string::npos) << md;
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
  EXPECT_NE(md.find("- Method: fixed. "), std::string::npos) << md;
  EXPECT_EQ(md.find("cells by build"), std::string::npos) << "every cell of the manifest's build" << md;
  const std::size_t clocks = md.find("- Step clocks: ");
  ASSERT_NE(clocks, std::string::npos) << md;
  const std::string line = md.substr(clocks, md.find('\n', clocks) - clocks);
  EXPECT_NE(line.find("host clock (omp)"), std::string::npos) << line;
  EXPECT_NE(line.find("GL timer queries (glsl-tf)"), std::string::npos) << line;
  EXPECT_NE(md.find("- Options chosen for this machine where none was given: interop=external-gpusync (glsl-tf)\n"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("- GPU clock over the timed batches (NVML, sampled every 5 ms): the cells' median SM clocks 1485 "
                    "MHz; 1 of 1 cells timed while a slowdown held the clock down: glsl-tf64 (power cap in 50% of "
                    "samples, 1410-1980 MHz)\n"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("a/d (omp / glsl-tf) at 64²: paper 93.364, here 5.000: the paper's ordering holds"),
            std::string::npos)
      << md;
  const std::string svg = slurp(dir_ / "plot-explicit-euler.svg");
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("paper (d) TF"), std::string::npos);
}

// With a calibration in the manifest, each step is shown against its ceiling and each timed
// stage against its own; a hybrid's time left after its GPU stages is split per hand-off and
// set against the floor; its split is drawn as stacked bars. Figures (ceilings.hpp), 64²
// = 4096 nodes, semi-implicit Euler (one force evaluation), copy 1000 GB/s, TF 1e8
// vertices/s, floor 100 µs: cuda-fused step 64 B x 4096 / 1e12 B/s = 0.000262 ms, 2.6% of
// its 0.01 ms; hybrid force 48 B x 4096 -> 0.000197 ms (2.0% of 0.01), update 4096 / 1e8 s
// = 0.04096 ms (41% of 0.1), step ceiling 0.000197 + 0.04096 + 2 x 0.1 = 0.241 ms (48% of
// 0.5); rest 0.5 - 0.01 - 0.1 = 0.39 ms over 2 hand-offs = 195 µs, 1.95 x the floor.
TEST_F(SweepTest, ReportShowsCeilingsAndStages) {
  fs::create_directories(dir_ / "cells");
  const json experiment = json::parse(R"({"name": "lab", "integrator": "semi-implicit-euler",
      "sweep": {"sizes": [64], "pipelines": ["cuda-fused", "hybrid"], "options": [{"interop": "map"}]}})");
  const json calibration = {{"device", {{"name", "test gpu"}}},
                            {"copy", {{"GB_per_s", 1000.0}}},
                            {"compute_copy", {{"GB_per_s", 500.0}, {"memory", "cuda"}}},
                            {"compute_copy_gl_buffers", {{"GB_per_s", 400.0}}},
                            {"transform_feedback", {{"vertices_per_s", 1e8}}},
                            {"floor", {{"us_per_hand_off", 100.0}}}};
  json manifest = {{"experiment", experiment},
                   {"build", {{"deformlab", "0"}, {"git", "g"}, {"compiler", "c"}, {"cuda", "13"}}},
                   {"machine", {{"cpu", "test cpu"}, {"hardware_threads", 2}, {"os", "test os"}}},
                   {"pipelines", {{"cuda-fused", "available"}, {"hybrid", "available"}}}};
  std::ofstream(dir_ / "manifest.json") << manifest.dump();
  auto cell = [&](const std::string& p, const json& options, double ms, const json& stages) {
    json c = {{"id", p}, {"size", 64}, {"pipeline", p}, {"integrator", "semi-implicit-euler"}, {"options", options},
              {"nodes", 4096}, {"status", "ok"}, {"median_ms", ms}, {"method", "fixed"}, {"stages", stages}};
    if (p == "cuda-fused") c["build"] = "h";  // resumed by another build than the hybrid's, whose cell names none
    std::ofstream(dir_ / "cells" / (p + ".json")) << c.dump();
  };
  cell("cuda-fused", json::object(), 0.01,
       json::array({{{"name", "force+update"}, {"median_ms", 0.008}, {"clock", "CUDA events"}, {"per_step", 1}}}));
  cell("hybrid", {{"interop", "map"}}, 0.5,
       json::array({{{"name", "force"}, {"median_ms", 0.01}, {"clock", "CUDA events"}, {"per_step", 1}},
                    {{"name", "hand-off"}, {"median_ms", 0.005}, {"clock", "host clock"}, {"per_step", 2}},
                    {{"name", "update"}, {"median_ms", 0.1}, {"clock", "GL timer queries"}, {"per_step", 1}}}));

  std::string md = slurp(write_report(dir_));
  EXPECT_NE(md.find("No calibration recorded"), std::string::npos) << md;
  EXPECT_NE(md.find("- Measured cells by build: h (1), not recorded (1)\n"), std::string::npos) << md;
  EXPECT_EQ(md.find("Against the ceilings"), std::string::npos) << md;

  manifest["calibration"] = calibration;
  std::ofstream(dir_ / "manifest.json") << manifest.dump();
  md = slurp(write_report(dir_));
  EXPECT_NE(md.find("Calibration (`deformlab calibrate`, test gpu): CUDA copy 1000.0 GB/s, compute-shader copy "
                    "500.0 GB/s on memory=cuda (400.0 GB/s on GL's buffers), transform feedback"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("Against the ceilings calibrated on test gpu (cells measured on another device do not compare): "),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| grid | cuda-fused | hybrid [interop=map] |\n|---|---|---|\n| 64² | 0.000262 (2.6%) | 0.241 (48%) |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| grid | step ms | force ms | update ms | rest ms | hand-off (CPU) ms | rest per hand-off µs | "
                    "x floor |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| 64² | 0.5 | 0.01 (2.0%) | 0.1 (41%) | 0.39 | 0.005 | 195.0 | 1.950 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 64² | 0.01 | 0.008 (3.3%) | 0.002 |"), std::string::npos) << md;
  EXPECT_EQ(md.find("Under the floor"), std::string::npos) << md;
  // A rest under the floor (0.5 - 0.01 - 0.41 = 0.08 ms, 40 µs a hand-off) is marked as what it
  // is: the difference between separate measurements.
  cell("hybrid", {{"interop", "map"}}, 0.5,
       json::array({{{"name", "force"}, {"median_ms", 0.01}, {"clock", "CUDA events"}, {"per_step", 1}},
                    {{"name", "update"}, {"median_ms", 0.41}, {"clock", "GL timer queries"}, {"per_step", 1}}}));
  md = slurp(write_report(dir_));
  EXPECT_NE(md.find("| 64² | 0.5 | 0.01 (2.0%) | 0.41 (10.0%) | 0.08 | 40.000 | 0.4 \\* |\n\n\\* Under the floor: the rest is "
                    "the timed step less stages profiled in another batch (one launch at a time), set against a floor "
                    "calibrated apart, so a rest under it comes from the differences between those measurements, not "
                    "from faster hand-offs (64²: rest 16% of the step).\n"),
            std::string::npos)
      << md;
  const std::string svg = slurp(dir_ / "stages-hybrid_semi-implicit-euler__interop_map_.svg");
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("rest"), std::string::npos);
  EXPECT_NE(svg.find("64² 0.5 ms"), std::string::npos);
}

}  // namespace
}  // namespace deformlab
