// The experiment runner: cells, n/a with reasons, cut cells, resume and atomic files (its
// report: report_test.cpp).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "experiments/experiment.hpp"
#include "experiments/pipelines.hpp"
#include "experiments/report.hpp"
#include "experiments/report_parts.hpp"
#include "experiments/sweep.hpp"
#include "experiments/sweep_folder.hpp"
#include "experiments/sweep_models.hpp"
#include "sweep_support.hpp"
#include "tests/support/gpu_required.hpp"

namespace deformlab {
namespace {

// A sweep's frames were not drawn: where no OpenGL context could be made or the build has none,
// not where drawing failed, and never on a run that requires its GPU stages.
void expect_no_gl_here(const json& why) {
  const std::string w = why.get<std::string>();
  EXPECT_FALSE(test::gpu_required()) << w;
  EXPECT_TRUE(w.starts_with("no OpenGL: ") || w == "this build has no OpenGL") << w;
}

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
      // GPU pipelines time their stages in a profiled batch (midpoint: two passes a step);
      // the CPU ones have no stages.
      if (r["pipeline"] == "cuda-naive") {
        ASSERT_EQ(r["stages"].size(), 2u) << r.dump();
        EXPECT_EQ(r["stages"][0]["name"], "force");
        EXPECT_EQ(r["stages"][0]["per_step"], 2.0);
        EXPECT_EQ(r["stages"][1]["name"], "update");
      } else if (r["pipeline"] == "glsl-tf") {
        ASSERT_EQ(r["stages"].size(), 1u) << r.dump();
        EXPECT_EQ(r["stages"][0]["name"], "force+update");
        EXPECT_GT(r["stages"][0]["median_ms"].get<double>(), 0.0);
      } else {
        EXPECT_FALSE(r.contains("stages")) << r.dump();
      }
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
  int seen_skipped = 0, seen_kept = 0;
  SweepOptions o;
  o.on_cell = [&](const Cell& c, const json& r, const SweepProgress& p) {
    seen_skipped = p.skipped;
    seen_kept += p.kept;
    const bool redone = c.id() == Cell{6, "omp", "midpoint", {}}.id();
    EXPECT_EQ(p.kept, r["status"] == "ok" && !redone) << c.id();
  };
  EXPECT_EQ(run_sweep(x, s, dir_, o, json::array()), 1 + na);
  EXPECT_EQ(seen_skipped, 7 - na);
  EXPECT_EQ(seen_kept, 7 - na) << "each kept cell is marked so";
  for (const auto& f : fs::recursive_directory_iterator(dir_))
    EXPECT_EQ(f.path().string().find(".deformlab-tmp-"), std::string::npos) << f.path();
  // Frames of the drag for the report: rendered once (kept on resume), or the reason why not.
  std::ifstream in(dir_ / "manifest.json");
  const json manifest = json::parse(in);
  ASSERT_TRUE(manifest.contains("frames")) << manifest.dump();
  if (manifest["frames"].contains("files")) {
    EXPECT_EQ(manifest["frames"]["files"].size(), 4u) << manifest["frames"].dump();
    for (const auto& f : manifest["frames"]["files"]) EXPECT_TRUE(fs::exists(dir_ / f.get<std::string>())) << f;
    EXPECT_NE(slurp(write_report(dir_)).find("## Frames of the drag"), std::string::npos);
  } else {
    expect_no_gl_here(manifest["frames"]["unavailable"]);
  }
}

// A folder resumed with another scene or sweep method measures its cells again; the name, the
// description and the sweep's lists of cells do not change how a cell is measured. Cells of
// another scene that a run has not measured again are not in its report.
TEST_F(SweepTest, CellsOfAnotherSceneOrMethodAreMeasuredAgain) {
  auto experiment = [](const std::string& scene, const std::string& sweep, const std::string& more = "") {
    return parse_experiment(R"({"name": "tiny", "base": "paper-drag", "integrator": "midpoint", "scene": )" + scene +
                                R"(, "sweep": )" + sweep + more + "}",
                            "tiny.json");
  };
  const std::string scene = R"({"model": {"size": [4, 4]}})", slow_scene = R"({"model": {"size": [4, 4]}, "dt": 1e-4})";
  const std::string sweep = R"({"sizes": [4, 5], "pipelines": ["cpu"], "warmup": 2, "steps": 2, "repetitions": 2})";
  const Experiment x = experiment(scene, sweep);
  const Sweep s = *parse_sweep(x.raw, "tiny");
  auto run = [&](const Experiment& e, SweepOptions o = {}) { return run_sweep(e, *parse_sweep(e.raw, "tiny"), dir_, o, json::array()); };
  ASSERT_EQ(run(x), 2);
  for (const auto& r : load_cells(dir_)) EXPECT_EQ(r["measurement"], cell_measurement(measurement(x, s), s, "")) << r.dump();
  EXPECT_EQ(run(experiment(scene, sweep, R"(, "description": "the same cells")")), 0);
  // What the cells do not take (the stop rule, the runaway check, the scene's own size) keeps them.
  EXPECT_EQ(run(experiment(R"({"model": {"size": [7, 7]}, "threshold": 0.5, "min_steps": 3, "max_steps": 9,
                               "check_every": 2, "runaway_factor": 3})", sweep)), 0);
  EXPECT_EQ(run(experiment(scene, R"({"sizes": [4, 5, 6], "pipelines": ["cpu"], "warmup": 2, "steps": 2, "repetitions": 2})")), 1);
  int remeasured = 0;
  SweepOptions o;
  o.on_cell = [&](const Cell&, const json&, const SweepProgress& p) { remeasured += p.remeasured; };
  const Experiment slower = experiment(slow_scene, sweep);
  EXPECT_EQ(run(slower, o), 2);
  EXPECT_EQ(remeasured, 2);
  const Experiment longer = experiment(slow_scene, R"({"sizes": [4, 5], "pipelines": ["cpu"], "warmup": 2, "steps": 3, "repetitions": 2})");
  EXPECT_EQ(run(longer), 2);
  EXPECT_EQ(run(longer), 0);
  // A run stopped before it measured a cell again (here by --max-size) leaves that cell out of
  // its report; so does the next run.
  SweepOptions small;
  small.max_size = 4;
  const Experiment quicker = experiment(slow_scene, R"({"sizes": [4, 5], "pipelines": ["cpu"], "warmup": 2, "steps": 2, "repetitions": 2})");
  Sweep up_to_4 = *parse_sweep(quicker.raw, "tiny");
  up_to_4.sizes = {4};  // as `experiment --max-size 4` leaves it
  EXPECT_EQ(run_sweep(quicker, up_to_4, dir_, small, json::array()), 1);
  const std::string report = slurp(write_report(dir_));
  EXPECT_NE(report.find("Not measured yet: 5²"), std::string::npos) << report;
  // Cells from before "measurement" was recorded count as measured as their manifest's
  // experiment, where that is this one; after another, they are measured again.
  auto forget_measurements = [&] {  // as cells written before they recorded one
    for (const auto& f : fs::directory_iterator(dir_ / "cells")) {
      json r = json::parse(slurp(f.path()));
      r.erase("measurement");
      std::ofstream(f.path()) << r.dump();
    }
  };
  forget_measurements();
  json manifest = json::parse(slurp(dir_ / "manifest.json"));
  manifest.erase("measurement");
  manifest.erase("frames_of");
  std::ofstream(dir_ / "manifest.json") << manifest.dump();
  EXPECT_EQ(run_sweep(quicker, up_to_4, dir_, small, json::array()), 0);
  forget_measurements();
  EXPECT_EQ(run(x), 2) << "the folder's manifest holds another experiment than x";
  // Cells the sweep no longer has (size 6, from an earlier run) are not in its report.
  EXPECT_TRUE(fs::exists(dir_ / "cells" / (Cell{6, "cpu", "midpoint", {}}.id() + ".json")));
  EXPECT_EQ(slurp(write_report(dir_)).find("| 6² |"), std::string::npos);
}

// A relative base names a file in the experiment file's folder, wherever the command runs.
TEST_F(SweepTest, ARelativeBaseIsReadFromTheExperimentsFolder) {
  fs::create_directories(dir_ / "x");
  std::ofstream(dir_ / "x" / "b.json") << R"({"scene": {"dt": 0.0005}})";
  std::ofstream(dir_ / "x" / "e.json") << R"({"base": "./b.json", "scene": {"model": {"size": [4, 4]}}})";
  EXPECT_EQ(load_experiment((dir_ / "x" / "e.json").string()).scene.params.dt, 0.0005f);
  // A name without "." or "/" that is not built in: the file of that name there, not here.
  std::ofstream(dir_ / "x" / "plainbase") << R"({"scene": {"dt": 0.0004}})";
  std::ofstream(dir_ / "x" / "p.json") << R"({"base": "plainbase"})";
  EXPECT_FALSE(fs::exists("plainbase"));
  EXPECT_EQ(load_experiment((dir_ / "x" / "p.json").string()).scene.params.dt, 0.0004f);
}

// A sweep refuses, before it runs, a folder where it would write over or remove what no
// experiment wrote.
TEST_F(SweepTest, FoldersWithOthersFilesAreRefusedBeforeTheSweep) {
  const Experiment x = tiny(R"({"sizes": [4], "pipelines": ["cpu"], "warmup": 2, "steps": 2, "repetitions": 2})");
  const Sweep s = *parse_sweep(x.raw, "tiny");
  auto refusal = [&] {
    try {
      require_sweep_folder(dir_, x, s);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(refusal(), "") << "no folder yet";
  for (const char* name : {"report.md", "plot-verlet.svg", "manifest.json", "frames/own.png"}) {
    fs::remove_all(dir_);
    fs::create_directories((dir_ / name).parent_path());
    std::ofstream(dir_ / name) << "mine";
    const std::string entry = fs::path(name).begin()->string();
    EXPECT_NE(refusal().find("holds '" + entry + "', which no experiment wrote there"), std::string::npos) << name;
  }
  fs::remove_all(dir_);
  std::ofstream((fs::create_directories(dir_), dir_ / "notes.txt")) << "mine";
  EXPECT_EQ(refusal(), "") << "a file of another name is left alone";
  ASSERT_EQ(run_sweep(x, s, dir_, {}, json::array()), 1);
  EXPECT_EQ(refusal(), "");
  std::ofstream(dir_ / "cells" / (Cell{4, "cpu", "midpoint", {}}.id() + ".json")) << "damaged";
  EXPECT_EQ(refusal(), "") << "a damaged cell of the sweep is measured again";
  std::ofstream(dir_ / "cells" / "notes.json") << "mine";
  EXPECT_NE(refusal().find("holds 'cells/notes.json', which is not a cell result"), std::string::npos);
  fs::remove(dir_ / "cells" / "notes.json");
  // Frames of this scene are kept, with whatever else is in their folder; frames of another are
  // removed, so another's file among them is refused.
  fs::create_directories(dir_ / "frames");
  std::ofstream(dir_ / "frames" / "frame_000001.png") << "a frame";
  std::ofstream(dir_ / "frames" / "own.txt") << "mine";
  json manifest = json::parse(slurp(dir_ / "manifest.json"));
  manifest["frames"] = {{"files", {"frames/frame_000001.png"}}};
  std::ofstream(dir_ / "manifest.json") << manifest.dump();
  EXPECT_EQ(refusal(), "");
  const Experiment other = parse_experiment(
      R"({"name": "tiny", "base": "paper-drag", "integrator": "midpoint", "scene": {"model": {"size": [4, 4]}, "dt": 1e-4},
          "sweep": {"sizes": [4], "pipelines": ["cpu"], "warmup": 2, "steps": 2, "repetitions": 2}})",
      "tiny.json");
  try {
    require_sweep_folder(dir_, other, s);
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("holds 'frames/own.txt', which no run writes there"), std::string::npos) << e.what();
  }
  // In cells/, any file but a cell result (or a killed run's temporary); a file where the
  // experiment writes a folder.
  std::ofstream(dir_ / "cells" / "notes.txt") << "mine";
  EXPECT_NE(refusal().find("holds 'cells/notes.txt', which is not a cell result"), std::string::npos);
  fs::remove(dir_ / "cells" / "notes.txt");
  std::ofstream(dir_ / "cells" / "x.json.deformlab-tmp-999999999") << "partial";
  EXPECT_EQ(refusal(), "");
  fs::remove_all(dir_ / "frames");
  std::ofstream(dir_ / "frames") << "my notes";
  EXPECT_NE(refusal().find("holds 'frames', where the experiment writes a folder"), std::string::npos);
  // A folder whose manifest names no experiment is not one's results, cells/ or not.
  fs::remove_all(dir_);
  fs::create_directories(dir_ / "cells");
  std::ofstream(dir_ / "cells" / "data.csv") << "mine";
  std::ofstream(dir_ / "manifest.json") << R"({"mine": 1})";
  EXPECT_NE(refusal().find("holds 'manifest.json', which no experiment wrote there"), std::string::npos);
}

// Under --max-size the experiment's own grid, if larger, leaves its frames for a later run, as
// it leaves the sweep's larger sizes; the run without it renders them (or says why it cannot).
TEST_F(SweepTest, FramesOfAGridOverMaxSizeWaitForALaterRun) {
  const Experiment x = tiny(R"({"sizes": [4], "pipelines": ["cpu"], "warmup": 2, "steps": 1, "repetitions": 1})");
  const Sweep s = *parse_sweep(x.raw, "tiny");
  SweepOptions o;
  o.max_size = 3;
  run_sweep(x, s, dir_, o, json::array());
  json frames = json::parse(slurp(dir_ / "manifest.json"))["frames"];
  EXPECT_EQ(frames["unavailable"], "the experiment's cloth 4x4 is over --max-size 3; a run without it renders them");
  EXPECT_FALSE(fs::exists(dir_ / "frames"));
  EXPECT_NE(slurp(write_report(dir_)).find("None: the experiment's cloth 4x4 is over --max-size 3"), std::string::npos);
  o.max_size = 4;  // not over it
  run_sweep(x, s, dir_, o, json::array());
  frames = json::parse(slurp(dir_ / "manifest.json"))["frames"];
  EXPECT_EQ(frames.contains("files"), fs::exists(dir_ / "frames")) << frames.dump();
  if (!frames.contains("files")) {
    expect_no_gl_here(frames["unavailable"]);
  }
}

// Mesh models x node orders: every cell measured, ids distinct, each mesh generated or read
// once and each (model, order) built once, the report's tables per model, a resumed folder
// skipping what is done.
TEST_F(SweepTest, ModelsByOrders) {
  const Experiment x = parse_experiment(R"({"name": "meshes-tiny", "base": "meshes", "sweep": {
      "models": [{"name": "sheet", "model": {"generate": {"shape": "sheet", "size": [0.2, 0.2], "cell_size": 0.02},
                                             "scale": 1, "transform": {"translate": [0, 0.3, 0]}}},
                 {"name": "bunny-shell", "model": {"file": "../data/bunny/bunny.obj", "fill": "none"}}],
      "orders": ["file", "shuffled", "rcm"], "pipelines": ["cpu", "omp"],
      "warmup": 2, "steps": 2, "repetitions": 2, "frames": 0}})", "tiny.json", builtin_experiments_dir());
  const Sweep s = *parse_sweep(x.raw, "tiny");
  const auto all = cells(s);
  ASSERT_EQ(all.size(), 12u);
  std::set<std::string> ids;
  for (const auto& c : all) EXPECT_TRUE(ids.insert(c.id()).second) << c.id();
  EXPECT_EQ(all[0].id(), "cpu__semi-implicit-euler__sheet__file");
  ModelCache cache;
  for (const auto& c : all) {
    const json r = run_cell(x, s, c, cache);
    ASSERT_EQ(r["status"], "ok") << r.dump();
    EXPECT_EQ(r["order"], c.order);
    EXPECT_EQ(r["mesh"], "surface");
    EXPECT_GT(r["bandwidth"].get<int>(), 0);
  }
  EXPECT_EQ(cache.meshes_built(), 2);
  EXPECT_EQ(cache.models_built(), 6);

  EXPECT_EQ(run_sweep(x, s, dir_, {}, json::array()), 12);
  int built = 0;
  for (const auto& r : load_cells(dir_)) built += r["model_build_s"].get<double>() > 0;
  EXPECT_EQ(built, 6);  // the second pipeline of each (model, order) reuses the first's model
  fs::remove(dir_ / "cells" / (all[5].id() + ".json"));
  EXPECT_EQ(run_sweep(x, s, dir_, {}, json::array()), 1);
  const std::string md = slurp(write_report(dir_));
  EXPECT_NE(md.find("## Model `bunny-shell`\n\nsurface, 1839 nodes"), std::string::npos) << md;
  EXPECT_NE(md.find("Node-index bandwidth (the largest difference of a spring's two node indices) by order: file "),
            std::string::npos) << md;
  EXPECT_NE(md.find("| pipeline | file | shuffled | rcm |\n|---|---|---|---|\n| cpu |"), std::string::npos) << md;
  EXPECT_NE(md.find("| pipeline | shuffled / file | rcm / file |"), std::string::npos) << md;
  EXPECT_NE(md.find("68 + 32 s/n = "), std::string::npos) << md;
  EXPECT_NE(md.find("## Reading\n\n- sheet: "), std::string::npos) << md;
  // With a calibration: each step against the mesh step's floor (1839 nodes x 252.3 B at 1000 GB/s).
  json manifest = json::parse(slurp(dir_ / "manifest.json"));
  manifest["calibration"] = {{"copy", {{"GB_per_s", 1000.0}}}};
  std::ofstream(dir_ / "manifest.json") << manifest.dump();
  const std::string with = slurp(write_report(dir_));
  EXPECT_NE(with.find("at the CUDA copy bandwidth (1000.0 GB/s): 0.000464 ms"), std::string::npos) << with;
}

// A cell's options are checked on its model before the first cell runs: a mesh's option on the
// sweep's grids is refused, as a run refuses it.
TEST(Sweep, OptionsThatWouldDoNothingOnTheCellsModelAreRefused) {
  if (!pipelines().find("glsl-tf")->idle_option) GTEST_SKIP() << "this build has no GL backend";
  const Experiment x = parse_experiment(R"({"name": "t", "sweep": {"sizes": [8], "pipelines": ["glsl-tf"],
                                            "options": [{"link_view": "64"}]}})", "t.json");
  try {
    parse_sweep(x.raw, "t.json");
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "t.json.sweep.options: glsl-tf: option link_view: a mesh's option (links per "
                                     "texture-buffer view of its adjacency), and this model is a grid");
  }
}

// A lattice's sweep knows its sizes are n^3 nodes, from its own scene or a base's, refuses those
// past the node limit before any cell runs, and labels its rows n³.
TEST_F(SweepTest, LatticeSweepsCountAndLabelTheirSizesCubed) {
  std::ofstream(dir_.string() + "-base.json") << R"({"scene": {"model": {"type": "lattice"}}})";
  const Experiment x = parse_experiment(R"({"name": "cubes", "base": ")" + dir_.string() + R"(-base.json",
      "sweep": {"sizes": [3, 4], "pipelines": ["cpu"], "warmup": 2, "steps": 1, "repetitions": 1, "frames": 0}})",
                                        "cubes.json");
  fs::remove(dir_.string() + "-base.json");
  const Sweep s = *parse_sweep(x.raw, "cubes.json");
  EXPECT_TRUE(s.lattice);
  EXPECT_EQ(cells(s)[0].label(s.lattice), "3³");
  ASSERT_EQ(run_sweep(x, s, dir_, {}, json::array()), 2);
  const std::string md = slurp(write_report(dir_));
  EXPECT_NE(md.find("| 3³ | 27 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 4³ | 64 |"), std::string::npos) << md;
  // 1025^3 nodes pass 2^30, where a 1025 x 1025 cloth does not.
  const Experiment big = parse_experiment(
      R"({"scene": {"model": {"type": "lattice"}}, "sweep": {"sizes": [4, 1025], "pipelines": ["cpu"]}})", "big.json");
  try {
    parse_sweep(big.raw, "big.json");
    ADD_FAILURE() << "a lattice sweep past 2^30 nodes was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("big.json.sweep.sizes[1]: size 1025³: a model of about"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(parse_sweep(tiny(R"({"sizes": [1025], "pipelines": ["cpu"]})").raw, "tiny")->lattice);
}

// The built-in experiments are the source tree's experiments/*.json, each loading by its name
// as its file does by its path, and the names the CLI's help and its bad-input line give are
// theirs.
TEST(BuiltinExperiments, AreTheTreesExperimentFilesByName) {
  std::set<std::string> files;
  for (const auto& e : fs::directory_iterator(builtin_experiments_dir()))
    if (e.path().extension() == ".json") files.insert(e.path().stem().string());
  ASSERT_GE(files.size(), 11u);
  std::set<std::string> named;
  std::stringstream list(builtin_experiment_names(Builtins::sweeps) + ", " + builtin_experiment_names(Builtins::scenes));
  for (std::string n; std::getline(list >> std::ws, n, ',');) named.insert(n);
  EXPECT_EQ(named, files);
  for (const std::string& n : files) {
    const Experiment by_name = load_experiment_by_name(n);
    EXPECT_EQ(by_name.name, n);
    // Named by its path, the file reads the same scene, its mesh files from the same places.
    const Experiment by_path = load_experiment((fs::path(builtin_experiments_dir()) / (n + ".json")).string());
    EXPECT_EQ(to_json(by_path.scene), to_json(by_name.scene)) << n;
    if (const std::string& f = by_path.scene.model.mesh.file; !f.empty()) {
      EXPECT_TRUE(fs::exists(f)) << n << ": " << f;
    }
  }
  // `deformlab experiment`'s help names those with a sweep.
  std::set<std::string> swept;
  std::stringstream sweeps(builtin_experiment_names(Builtins::sweeps));
  for (std::string n; std::getline(sweeps >> std::ws, n, ',');) swept.insert(n);
  for (const std::string& n : files) {
    const Experiment x = load_experiment_by_name(n);
    EXPECT_EQ(swept.count(n), std::size_t(x.raw.contains("sweep"))) << n;
    EXPECT_NO_THROW(parse_sweep(x.raw, n)) << n << ": its sweep reads";
    if (const auto s = parse_sweep(x.raw, n)) {
      EXPECT_NO_THROW(require_size_grids(x, *s)) << n << ": its grids hold at each size";
      EXPECT_NO_THROW(require_size_scenes(x, *s)) << n << ": its scene holds at each size";
      EXPECT_NO_THROW(require_model_files(x, *s)) << n << ": its mesh models read, and floats hold its shapes";
    }
  }
  EXPECT_EQ(swept.count("paper-drag"), 0u);
  EXPECT_EQ(builtin_experiment_names(Builtins::scenes), "paper-drag");
}

// A file without a "name" is named by its file name, as its results folder is.
TEST_F(SweepTest, AFileWithoutANameIsNamedByItsFile) {
  fs::create_directories(dir_);
  std::ofstream(dir_ / "my-drag.json") << R"({"base": "paper-drag"})";
  EXPECT_EQ(load_experiment_by_name((dir_ / "my-drag.json").string()).name, "my-drag");
  // Its sweep's results record that name, so another experiment is refused their folder.
  std::ofstream(dir_ / "my-sweep.json")
      << R"({"base": "paper-drag", "sweep": {"sizes": [4], "pipelines": ["cpu"], "repetitions": 1, "frames": 0}})";
  const Experiment x = load_experiment_by_name((dir_ / "my-sweep.json").string());
  run_sweep(x, *parse_sweep(x.raw, "my-sweep"), dir_ / "out", {}, json::array());
  EXPECT_EQ(json::parse(slurp(dir_ / "out" / "manifest.json"))["experiment"]["name"], "my-sweep");
  EXPECT_EQ(slurp(write_report(dir_ / "out")).rfind("# my-sweep\n", 0), 0u);
  EXPECT_THROW(require_same_experiment(dir_ / "out", "my-drag"), std::invalid_argument);
  std::ofstream(dir_ / "named.json") << R"({"name": "other", "base": "paper-drag"})";
  EXPECT_EQ(load_experiment_by_name((dir_ / "named.json").string()).name, "other");
}

TEST(Sweep, TakesTheIntegratorOfItsExperimentsBase) {
  const Experiment x = parse_experiment(R"({"base": "table2", "sweep": {"sizes": [4], "pipelines": ["cpu"]}})", "b.json");
  EXPECT_EQ(x.integrator, "explicit-euler");
  EXPECT_EQ(parse_sweep(x.raw, "b.json")->integrators, std::vector<std::string>{"explicit-euler"});
}

TEST_F(SweepTest, MeshesExperimentCells) {
  const Experiment x = load_experiment_by_name("meshes");
  const auto all = cells(*parse_sweep(x.raw, "meshes"));
  EXPECT_EQ(all.size(), 6u * 4u * 13u);
  std::set<std::string> ids;
  for (const auto& c : all) EXPECT_TRUE(ids.insert(c.id()).second) << c.id();
  EXPECT_TRUE(fs::exists(x.scene.model.mesh.file)) << x.scene.model.mesh.file;
}

TEST_F(SweepTest, SlowCellsAreCutWithTheReason) {
  // 512² on cpu by midpoint: milliseconds a step, the cell's steps past the shortest limit.
  const Experiment x = tiny(R"({"sizes": [512], "pipelines": ["cpu"], "cell_limit_s": 0.01})");
  ModelCache cache;
  const json r = run_cell(x, *parse_sweep(x.raw, "tiny"), {512, "cpu", "midpoint", {}}, cache);
  EXPECT_EQ(r["status"], "n/a");
  EXPECT_EQ(r["reason"].get<std::string>().rfind("cut: the second step took", 0), 0u) << r.dump();
}

TEST_F(SweepTest, OptionSetsGoToThePipelinesThatReadThem) {
  const Experiment x = tiny(R"({"sizes": [4], "pipelines": ["cpu", "cuda-tiled"],
                                "options": [{"tile": "8x8"}, {"tile": "16x16"}]})");
  const auto cs = cells(*parse_sweep(x.raw, "tiny"));
  ASSERT_EQ(cs.size(), 3u);  // cpu reads no "tile": it runs once, without options
  EXPECT_EQ(cs[0].pipeline, "cpu");
  EXPECT_TRUE(cs[0].options.empty());
  EXPECT_EQ(cs[1].options.at("tile"), "8x8");
  EXPECT_EQ(cs[2].options.at("tile"), "16x16");
  // The empty set (defaults) runs on every pipeline, wherever the list has it.
  for (const char* options : {R"([{"tile": "8x8"}, {}])", R"([{}, {"tile": "8x8"}])"}) {
    const Experiment y = tiny(R"({"sizes": [4], "pipelines": ["cpu", "cuda-tiled"], "options": )" + std::string(options) + "}");
    const auto with_defaults = cells(*parse_sweep(y.raw, "tiny"));
    ASSERT_EQ(with_defaults.size(), 3u) << options;
    EXPECT_EQ(std::count_if(with_defaults.begin(), with_defaults.end(), [](const Cell& c) { return c.options.empty(); }), 2)
        << options;
  }
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
  EXPECT_NE(error(R"({"sizes": [4, 0], "pipelines": ["cpu"]})").find("sweep.sizes[1]: expected"), std::string::npos);
  EXPECT_NE(error(R"({"sizes": [4, 8, 4], "pipelines": ["cpu"]})").find("sweep.sizes[2]: size 4 is named twice"),
            std::string::npos);
  EXPECT_NE(error(R"({"sizes": [4], "pipelines": ["cpu", "cpu"]})").find("sweep.pipelines: 'cpu' is named twice"),
            std::string::npos);
  EXPECT_NE(error(R"({"sizes": [4], "pipelines": ["cpu"], "integrators": ["verlet", "verlet"]})")
                .find("sweep.integrators: 'verlet' is named twice"),
            std::string::npos);
  EXPECT_NE(error(R"({"sizes": [4], "pipelines": ["cpu"], "integrators": ["verlet", "midpoint-verlet"]})")
                .find("sweep.integrators: 'midpoint-verlet' names the integrator 'verlet' names"),
            std::string::npos);
  EXPECT_NE(error(R"({"sizes": [4], "pipelines": ["cuda-tiled"], "options": [{"tile": "8x8"}, {"tile": "8x8"}]})")
                .find("sweep.options: an option set is named twice"),
            std::string::npos);
  EXPECT_NE(error(R"({"sizes": [4], "pipelines": ["cpu"], "reps": 3})").find("sweep.reps: unknown key"),
            std::string::npos);
  EXPECT_NE(error(R"({"sizes": [4], "pipelines": ["cpu", "omp"], "options": [{"tile": "8x8"}]})")
                .find("sweep.options.tile: no pipeline of this sweep reads option 'tile'"),
            std::string::npos);
  // A value is read before any cell runs (where this build has the backend that reads it).
  if (pipelines().find("glsl-compute")->read_options) {
    EXPECT_NE(error(R"({"sizes": [4], "pipelines": ["cpu", "glsl-compute"], "options": [{"math": "rough"}]})")
                  .find("sweep.options: glsl-compute: option math 'rough' is not exact or fast"),
              std::string::npos);
  }
}

}  // namespace
}  // namespace deformlab
