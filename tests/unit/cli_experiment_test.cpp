// `deformlab experiment` end to end: results folders it finds damaged or in the way, mesh sweeps,
// a model found bad at its first cell, and frames that do not fit the host.
#include <nlohmann/json.hpp>
#include <fstream>
#include <string>

#include "cli_support.hpp"
#include "tests/support/gpu_required.hpp"

namespace deformlab::test {
namespace {

// A size that floats cannot hold is refused before a run's first cell, but a report is still
// written of the cells there are.
TEST_F(Cli, AReportIsWrittenThoughASizeNotRunIsBad) {
  const std::string scene = R"("scene": {"model": {"size": [4, 4], "height": 40}, "drag": null})";
  write("x.json", R"({"name": "tiny", )" + scene + R"(, "sweep": {"sizes": [4], "pipelines": ["cpu"], "warmup": 2,
                      "steps": 2, "repetitions": 2, "frames": 0}})");
  const std::string experiment = "experiment " + (dir_ / "x.json").string() + " --out " + (dir_ / "r").string();
  ASSERT_EQ(run(experiment).code, 0);
  write("x.json", R"({"name": "tiny", )" + scene + R"(, "sweep": {"sizes": [4, 4096], "pipelines": ["cpu"],
                      "warmup": 2, "steps": 2, "repetitions": 2, "frames": 0}})");
  const Result refused = run(experiment);
  EXPECT_EQ(refused.code, 2);
  EXPECT_NE(refused.err.find("x.json.sweep.sizes[1]: size 4096²: it lies up to 40 m from the origin"), std::string::npos)
      << refused.err;
  const Result report = run(experiment + " --report-only");
  EXPECT_EQ(report.code, 0) << report.err;
  const std::string md = slurp(dir_ / "r" / "report.md");
  EXPECT_NE(md.find("| 4² |"), std::string::npos) << md;
}

// A results folder whose files were damaged or edited: a cell whose values are of other kinds
// is named (and measured again by a run); a manifest so is one line too.
TEST_F(Cli, DamagedResultsAreNamedWithOneLine) {
  write("x.json", R"({"name": "tiny", "scene": {"model": {"size": [4, 4]}, "drag": null},
                      "sweep": {"sizes": [4], "pipelines": ["cpu"], "warmup": 2, "steps": 2, "repetitions": 2}})");
  const std::string experiment = "experiment " + (dir_ / "x.json").string() + " --out " + (dir_ / "r").string();
  ASSERT_EQ(run(experiment).code, 0);
  const fs::path cell = dir_ / "r" / "cells" / "cpu__semi-implicit-euler__4.json";
  const nlohmann::json good = nlohmann::json::parse(slurp(cell));
  // Each key the report reads is checked (a method of another kind, say, or no node count).
  nlohmann::json no_nodes = good;
  no_nodes.erase("nodes");
  std::ofstream(dir_ / "r" / "cells" / "x.json") << no_nodes.dump();
  EXPECT_NE(run(experiment + " --report-only").err.find("x.json is not a cell result (its \"nodes\" is missing)"),
            std::string::npos);
  nlohmann::json no_method = good;
  no_method["method"] = 5;
  std::ofstream(dir_ / "r" / "cells" / "x.json") << no_method.dump();
  EXPECT_NE(run(experiment + " --report-only").err.find("x.json is not a cell result (its \"method\" is of another kind)"),
            std::string::npos);
  nlohmann::json negative = good;
  negative["median_ms"] = -1e308;
  std::ofstream(dir_ / "r" / "cells" / "x.json") << negative.dump();
  EXPECT_NE(run(experiment + " --report-only").err.find("x.json is not a cell result (its \"median_ms\" is not a time a "
                                                        "step can take)"),
            std::string::npos);
  fs::remove(dir_ / "r" / "cells" / "x.json");
  nlohmann::json bad = good;
  bad["median_ms"] = "fast";
  std::ofstream(cell) << bad.dump();
  const Result report = run(experiment + " --report-only");
  EXPECT_EQ(report.code, 2);
  EXPECT_EQ(report.err, "deformlab: error: cell file " + cell.string() +
                            " is not a cell result (its \"median_ms\" is of another kind): if it is one of the sweep's "
                            "cells, running the experiment again redoes it; else remove it\n");
  const Result again = run(experiment);
  EXPECT_EQ(again.code, 0) << again.err;
  EXPECT_NE(again.out.find("ran 1 cells, kept 0"), std::string::npos) << again.out;
  EXPECT_NE(again.out.find(" ms/step (host clock)"), std::string::npos) << "each cell's time with its clock: " << again.out;
  EXPECT_TRUE(nlohmann::json::parse(slurp(cell))["median_ms"].is_number());
  nlohmann::json manifest = nlohmann::json::parse(slurp(dir_ / "r" / "manifest.json"));
  const nlohmann::json machine = manifest["machine"];
  manifest["machine"] = nullptr;
  std::ofstream(dir_ / "r" / "manifest.json") << manifest.dump();
  const Result damaged = run(experiment + " --report-only");
  EXPECT_EQ(damaged.code, 2);
  EXPECT_EQ(damaged.err.rfind("deformlab: error: a results file in " + (dir_ / "r").string() +
                                  " (its manifest.json, or a cell) holds a value of another kind than the report reads "
                                  "(cannot use value() with null)", 0),
            0u) << damaged.err;
  EXPECT_EQ(std::count(damaged.err.begin(), damaged.err.end(), '\n'), 1);
  // The frames' size, which the report indexes, is checked (an empty one read past its end).
  manifest["machine"] = machine;
  manifest["frames"] = {{"files", nlohmann::json::array()}, {"size", nlohmann::json::array()}};
  std::ofstream(dir_ / "r" / "manifest.json") << manifest.dump();
  const Result frames = run(experiment + " --report-only");
  EXPECT_EQ(frames.code, 2);
  EXPECT_EQ(frames.err, "deformlab: error: " + (dir_ / "r" / "manifest.json").string() +
                            ": frames.size: expected [width, height], as the experiment writes it\n");
}

// A folder where an experiment writes a file (a cell's, the report) is refused before any cell
// runs, and by --report-only, which writes the report.
TEST_F(Cli, AFolderInAResultFilesPlaceIsRefusedFirst) {
  write("x.json", R"({"name": "tiny", "scene": {"model": {"size": [4, 4]}, "drag": null},
                      "sweep": {"sizes": [4, 5], "pipelines": ["cpu"], "warmup": 2, "steps": 2, "repetitions": 2}})");
  const std::string experiment = "experiment " + (dir_ / "x.json").string() + " --out " + (dir_ / "r").string();
  ASSERT_EQ(run(experiment).code, 0);
  const fs::path cell = dir_ / "r" / "cells" / "cpu__semi-implicit-euler__5.json";
  fs::remove(cell);
  fs::create_directory(cell);
  const Result r = run(experiment);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, "deformlab: error: results folder '" + (dir_ / "r").string() +
                       "' holds 'cells/cpu__semi-implicit-euler__5.json', where the experiment writes a cell's file: "
                       "move it or give another --out\n");
  EXPECT_EQ(r.out.find("[1/2]"), std::string::npos) << r.out;
  fs::remove(cell);
  fs::remove(dir_ / "r" / "report.md");
  fs::create_directory(dir_ / "r" / "report.md");
  const Result report = run(experiment + " --report-only");
  EXPECT_EQ(report.code, 2);
  EXPECT_NE(report.err.find("holds 'report.md', where the experiment writes a file"), std::string::npos) << report.err;
}

// A sweep of mesh models that names no node orders: each cell records the order its model took
// (the file's), and the report finds the cells all the same.
TEST_F(Cli, AMeshSweepWithoutOrdersReportsItsCells) {
  write("x.json", R"({"name": "sheets", "scene": {"model": {"type": "mesh", "pins": "none",
                          "generate": {"shape": "sheet", "size": [1, 1], "cell_size": 0.25}}},
      "sweep": {"models": [{"name": "s1", "model": {"generate": {"shape": "sheet", "size": [1, 1], "cell_size": 0.2}}}],
                "pipelines": ["cpu"], "warmup": 2, "steps": 2, "repetitions": 2}})");
  const std::string experiment = "experiment " + (dir_ / "x.json").string() + " --out " + (dir_ / "r").string();
  ASSERT_EQ(run(experiment).code, 0);
  const fs::path cell = dir_ / "r" / "cells" / "cpu__semi-implicit-euler__s1.json";
  const nlohmann::json good = nlohmann::json::parse(slurp(cell));
  EXPECT_EQ(good["order"], "file");
  const std::string report = slurp(dir_ / "r" / "report.md");
  const std::size_t row = report.find("\n| cpu | ");
  ASSERT_NE(row, std::string::npos) << report;
  EXPECT_TRUE(std::isdigit(static_cast<unsigned char>(report[row + 9]))) << report;  // a time, not "-"
  // Its mesh's counts are keys the report reads.
  nlohmann::json no_springs = good;
  no_springs.erase("springs");
  std::ofstream(cell) << no_springs.dump();
  EXPECT_NE(run(experiment + " --report-only").err.find("is not a cell result (its \"springs\" is missing)"),
            std::string::npos);
}

// A generated or filled model is built only for its cells: one whose pins pick no node of it
// stops the experiment at its first cell with one line and exit 2, keeping the cells before
// (with none, the folder the experiment made is removed).
TEST_F(Cli, AFilledModelWhosePinsPickNothingStopsTheExperiment) {
  write("t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  write("x.json", R"({"name": "filled",
      "scene": {"model": {"type": "mesh", "file": "t.obj", "pins": "none"}, "drag": null},
      "sweep": {"models": [{"name": "a", "model": {"pins": "none"}},
                           {"name": "b", "model": {"fill": "tetrahedra", "cell_size": 0.3,
                                                   "pins": [{"box": [[5, 5, 5], [6, 6, 6]]}]}}],
                "pipelines": ["cpu"], "warmup": 2, "steps": 2, "repetitions": 2, "frames": 0}})");
  const Result r = run("experiment " + (dir_ / "x.json").string() + " --out " + (dir_ / "r").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, "deformlab: error: " + (dir_ / "x.json").string() +
                       ".sweep.models[1].model.pins[0]: the box holds no node of the model\n");
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "r" / "cells" / "cpu__semi-implicit-euler__a.json"))["status"], "ok");
  EXPECT_FALSE(fs::exists(dir_ / "r" / "cells" / "cpu__semi-implicit-euler__b.json"));
  // With no cell measured, the folder it made is gone.
  nlohmann::json x = nlohmann::json::parse(slurp(dir_ / "x.json"));
  x["sweep"]["models"].erase(0);
  write("y.json", x.dump());
  const Result first = run("experiment " + (dir_ / "y.json").string() + " --out " + (dir_ / "s").string());
  EXPECT_EQ(first.code, 2);
  EXPECT_NE(first.err.find("y.json.sweep.models[0].model.pins[0]: the box holds no node"), std::string::npos) << first.err;
  EXPECT_FALSE(fs::exists(dir_ / "s"));
}

// A model too large for this machine is a cell that does not fit, as a grid size is, and the
// sweep goes on.
TEST_F(Cli, AGeneratedModelOverTheHostsMemoryIsACellThatDoesNotFit) {
  write("t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  write("x.json", R"({"name": "big",
      "scene": {"model": {"type": "mesh", "file": "t.obj", "pins": "none"}, "drag": null},
      "sweep": {"models": [{"name": "box",
                            "model": {"generate": {"shape": "box", "size": [1, 1, 1], "cell_size": 0.00085}}},
                           {"name": "a", "model": {"pins": "none"}}],
                "pipelines": ["cpu"], "warmup": 2, "steps": 2, "repetitions": 2, "frames": 0}})");
  const Result r = run("experiment " + (dir_ / "x.json").string() + " --out " + (dir_ / "r").string());
  EXPECT_EQ(r.code, 0) << r.err;
  const nlohmann::json box = nlohmann::json::parse(slurp(dir_ / "r" / "cells" / "cpu__semi-implicit-euler__box.json"));
  EXPECT_EQ(box["status"], "n/a");
  const std::string why = box["reason"];
  EXPECT_EQ(why.rfind("does not fit: generated box of about 9.85e+08 nodes: its model needs", 0), 0u) << why;
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "r" / "cells" / "cpu__semi-implicit-euler__a.json"))["status"], "ok");
}

// An experiment draws frames of its own scene after its cells: a grid of 2^30 nodes (40 GiB on a
// CUDA pipeline, 100 on omp) is refused before the first cell, with nothing written.
TEST_F(Cli, ExperimentRefusesFramesOfASceneThatDoesNotFitTheHost) {
  if (available_gib() > 38) GTEST_SKIP() << "this host has room for the scene";
  write("x.json", R"({"name": "big-frames", "scene": {"model": {"size": [32768, 32768]}},
                      "sweep": {"sizes": [4], "pipelines": ["cpu"], "warmup": 2, "steps": 2, "repetitions": 2, "frames": 1}})");
  const Result r = run("experiment " + (dir_ / "x.json").string() + " --out " + (dir_ / "r").string());
  if (r.code == 0 && slurp(dir_ / "r" / "manifest.json").find("OpenGL") != std::string::npos)
    DEFORMLAB_SKIP_IF_UNAVAILABLE("no OpenGL here: no frames are drawn");
  EXPECT_EQ(r.code, 2);
  const std::string line = r.err.substr(r.err.rfind("deformlab: error: "));
  EXPECT_EQ(line.rfind("deformlab: error: the experiment's own scene, whose frames its sweep draws (sweep.frames): a "
                       "model of 1073741824 nodes on ", 0), 0u) << r.err;
  EXPECT_EQ(std::count(line.begin(), line.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "r"));
}

}  // namespace
}  // namespace deformlab::test
