// The deformlab command end to end: the outputs of a run, of `mesh` and `list`, and what a failed
// run leaves (bad inputs: bad_input_test.cpp; experiments: cli_experiment_test.cpp; view and the
// bench: cli_view_bench_test.cpp).
#include <nlohmann/json.hpp>
#include <sys/stat.h>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include "cli_support.hpp"
#include "tests/support/gpu_required.hpp"

namespace deformlab::test {
namespace {

TEST_F(Cli, RunWritesTimingsStateAndManifest) {
  const fs::path out = dir_ / "run";
  const Result r = run("run --pipeline cpu --integrator verlet --grid 8x6 --steps 10 --compare reference --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("48 nodes"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("compare: largest position error"), std::string::npos) << r.out;

  const std::string csv = slurp(out / "timings.csv");
  EXPECT_EQ(csv.rfind("step,t_s,step_ms,queue_ms,max_displacement_m\n", 0), 0u);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 11);

  const std::string ply = slurp(out / "state.ply");
  EXPECT_NE(ply.find("format binary_little_endian 1.0\n"), std::string::npos);
  EXPECT_NE(ply.find("element vertex 48\n"), std::string::npos);
  EXPECT_NE(ply.find("element face 70\n"), std::string::npos);  // 2 x 7 x 5 triangles
  const std::size_t body = ply.find("end_header\n") + 11;
  EXPECT_EQ(ply.size() - body, 48u * 24 + 70u * 13);

  const auto m = nlohmann::json::parse(slurp(out / "manifest.json"));
  EXPECT_EQ(m["pipeline"], "cpu");
  EXPECT_EQ(m["integrator"], "verlet");
  EXPECT_EQ(m["result"]["steps"], 10);
  EXPECT_EQ(m["result"]["step_clock"], "host clock");
  EXPECT_GT(m["result"]["median_step_ms"].get<double>(), 0.0);
  EXPECT_NE(r.out.find("ms/step (host clock), "), std::string::npos) << r.out;
  EXPECT_EQ(m["stages_timed_in"], "steps 1-8 of every 64");
  std::set<std::string> stages;
  for (const auto& st : m["stages"]) {
    stages.insert(st["name"].get<std::string>());
    EXPECT_EQ(st["clock"], "host clock") << st;
  }
  for (const char* name : {"force", "update", "constraints", "step"}) EXPECT_EQ(stages.count(name), 1u) << name;
  EXPECT_NE(r.out.find("passes timed in steps 1-8 of every 64"), std::string::npos) << r.out;
  EXPECT_EQ(m["scene"]["model"]["size"], nlohmann::json::array({8, 6}));
  EXPECT_EQ(m["warm_up"]["steps"], 0) << "CPU pipelines start at once";
  EXPECT_TRUE(m["result"]["sm_clock"].is_null());
  EXPECT_EQ(r.out.find("  clock:"), std::string::npos) << r.out;
  EXPECT_LT(m["compare"]["max_position_error_relative_to_extent"].get<double>(), 1e-5);
  EXPECT_TRUE(m["build"].contains("compiler"));
  EXPECT_TRUE(m["machine"].contains("hardware_threads"));
  EXPECT_FALSE(fs::exists(out / (".deformlab-staging-" + std::to_string(::getpid()))));
}

// A CSV file's header line and its rows of numbers (an empty cell as NaN).
std::pair<std::string, std::vector<std::vector<double>>> csv_rows(const std::string& text) {
  std::istringstream csv(text);
  std::string header, line;
  std::getline(csv, header);
  std::vector<std::vector<double>> rows;
  while (std::getline(csv, line)) {
    std::vector<double> row;
    std::istringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');) row.push_back(cell.empty() ? NAN : std::stod(cell));
    rows.push_back(row);
  }
  return {header, rows};
}

// --energy K: the state's energies at step 0, every K steps and the last, each row's parts adding
// up to its total, the manifest's first and last totals those of the file; a cloth released from
// rest starts with its springs at rest length and no kinetic energy.
TEST_F(Cli, RunWritesItsEnergiesEveryKSteps) {
  const fs::path out = dir_ / "run";
  const Result r = run("run --pipeline cpu --grid 8x6 --steps 130 --energy 50 --no-state --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.err;
  const auto [header, rows] = csv_rows(slurp(out / "energy.csv"));
  EXPECT_EQ(header, "step,t_s,kinetic_J,spring_J,field_J,total_J");
  for (const auto& row : rows) {
    ASSERT_EQ(row.size(), 6u);
    EXPECT_NEAR(row[2] + row[3] + row[4], row[5], 1e-9 * std::abs(row[5])) << "step " << row[0];
  }
  ASSERT_EQ(rows.size(), 4u);
  const double steps[] = {0, 50, 100, 130};
  for (std::size_t k = 0; k < rows.size(); ++k) EXPECT_EQ(rows[k][0], steps[k]);
  EXPECT_EQ(rows[0][2], 0.0) << "from rest";
  EXPECT_LT(rows[0][3], 1e-9) << "springs at rest length";
  EXPECT_GT(rows[3][2], 0.0) << "it falls";
  const auto m = nlohmann::json::parse(slurp(out / "manifest.json"));
  EXPECT_NEAR(m["energy"]["first_total_J"].get<double>(), rows[0][5], 1e-9 * std::abs(rows[0][5]));
  EXPECT_NEAR(m["energy"]["last_total_J"].get<double>(), rows[3][5], 1e-9 * std::abs(rows[3][5]));
  EXPECT_NE(r.out.find("energy: total "), std::string::npos) << r.out;
  // A GPU pipeline's states, read back mid-run, give the CPU's energies: the same bits in exact
  // math on cuda-fused and a software renderer, within rounding on NVIDIA's GL (1e-4 of the total
  // bounds it).
  for (const char* gpu : {"cuda-fused", "glsl-compute"}) {
    const fs::path at = dir_ / gpu;
    const Result g = run(std::string("run --pipeline ") + gpu + " --grid 8x6 --steps 130 --energy 50 --no-state --out " +
                         at.string());
    if (g.code == 2 && g.err.find("is not available") != std::string::npos) {
      EXPECT_FALSE(test::gpu_required()) << g.err;
      continue;
    }
    ASSERT_EQ(g.code, 0) << gpu << ": " << g.err;
    const auto gm = nlohmann::json::parse(slurp(at / "manifest.json"));
    EXPECT_NEAR(gm["energy"]["last_total_J"].get<double>(), rows[3][5], 1e-4 * std::abs(rows[3][5])) << gpu;
    EXPECT_EQ(gm["energy"]["samples"], 4) << gpu;
  }
}

// The step clock's median leaves out the steps whose passes were timed (1-8 of every 64):
// the median of the other rows of timings.csv, which keeps 9 digits.
TEST_F(Cli, TheMedianStepLeavesOutTheProfiledSteps) {
  const fs::path out = dir_ / "run";
  const Result r = run("run --pipeline cpu --grid 8x6 --steps 150 --no-state --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.err;
  std::vector<double> unprofiled;  // step_ms of steps outside 1-8 of every 64
  for (const auto& row : csv_rows(slurp(out / "timings.csv")).second)
    if ((int(row[0]) - 1) % 64 >= 8) unprofiled.push_back(row[2]);
  ASSERT_EQ(unprofiled.size(), 150u - 8 - 8 - 8);
  std::nth_element(unprofiled.begin(), unprofiled.begin() + long(unprofiled.size() / 2), unprofiled.end());
  const double expected = unprofiled[unprofiled.size() / 2];
  const auto m = nlohmann::json::parse(slurp(out / "manifest.json"));
  EXPECT_NEAR(m["result"]["median_step_ms"].get<double>(), expected, 1e-8 * expected);
}

// The node count deformlab mesh prints at the start of its second line ("  N nodes, "), or -1.
int mesh_nodes(const std::string& out) {
  const std::size_t second_line = out.find("\n  ");
  if (second_line == std::string::npos) return -1;
  std::istringstream counts(out.substr(second_line + 3));
  int nodes = -1;
  std::string unit;
  counts >> nodes >> unit;
  return unit == "nodes," ? nodes : -1;
}

// On a terminal (here the pseudo-terminal `script` gives it) a run keeps a progress line,
// written at its first step and then twice a second, and cleared before the summary; in a log
// it writes none.
TEST_F(Cli, RunKeepsAProgressLineOnATerminalOnly) {
  if (std::system("command -v script >/dev/null 2>&1") != 0) GTEST_SKIP() << "no `script` (util-linux) here";
  const fs::path log = dir_ / "terminal.txt";
  const std::string run_args = " run --pipeline cpu --steps 20 --out ";
  const std::string cmd = "script -qec '" + std::string(DEFORMLAB_EXE) + run_args + (dir_ / "a").string() + "' " +
                          log.string() + " >/dev/null 2>&1 </dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  const std::string seen = slurp(log);
  EXPECT_NE(seen.find("\r\x1b[K  step 1 of 20 (5%), "), std::string::npos) << seen;
  EXPECT_NE(seen.find(" on the host clock, about "), std::string::npos) << seen;
  EXPECT_NE(seen.find("\r\x1b[Kdeformlab run: "), std::string::npos) << "cleared before the summary:\n" << seen;
  const Result r = run(run_args + (dir_ / "b").string());
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "") << "no progress line in a log";
}

// A run whose files would not fit on its output folder's file system (here a 300 kB tmpfs,
// mounted in a mount namespace of its own) is refused before it runs.
TEST_F(Cli, RunThatWouldFillTheDiskIsRefused) {
  const fs::path small = dir_ / "small";
  fs::create_directories(small);
  const fs::path err = dir_ / "err.txt";
  const std::string cmd = "command -v unshare >/dev/null || exit 99; unshare -m sh -c 'mount -t tmpfs -o size=300k "
                          "tmpfs " + small.string() + " || exit 99; " + DEFORMLAB_EXE +
                          " run --pipeline cpu --steps 2000 --out " + (small / "r").string() + "' 2>" + err.string();
  const int status = std::system(cmd.c_str());
  if (WEXITSTATUS(status) == 99 || (WEXITSTATUS(status) == 1 && slurp(err).find("unshare") != std::string::npos))
    GTEST_SKIP() << "no tmpfs in a mount namespace here: " << slurp(err);
  EXPECT_EQ(WEXITSTATUS(status), 2);
  const std::string line = slurp(err);
  EXPECT_EQ(line.rfind("deformlab: error: output folder '" + (small / "r").string() + "': this run writes about ", 0),
            0u) << line;
  EXPECT_NE(line.find(" MiB (2000 steps' timings and spans, state.ply) and its file system has 0.2"), std::string::npos)
      << line;
  EXPECT_TRUE(line.ends_with(" MiB free: free some or give another --out\n")) << line;
}

// An old manifest that cannot be removed (here a mount point: the file bound onto itself in a
// mount namespace of the run's own) stops the commit before it changes anything: the old outputs
// the new run lacks (state.ply, with --no-state), moved aside first, are put back, the folder is
// as it was, and the run's outputs are in unsaved-run-PID.
TEST_F(Cli, AManifestThatCannotBeRemovedLeavesTheFolderAsItWas) {
  const fs::path out = dir_ / "r", err = dir_ / "err.txt";
  ASSERT_EQ(run("run --pipeline cpu --grid 8x6 --steps 10 --out " + out.string()).code, 0);
  std::map<std::string, std::string> before;
  for (const auto& e : fs::directory_iterator(out)) before[e.path().filename().string()] = slurp(e.path());
  const fs::path manifest = out / "manifest.json";
  const std::string cmd = "command -v unshare >/dev/null || exit 99; unshare -m sh -c 'mount --bind " +
                          manifest.string() + " " + manifest.string() + " || exit 99; " + DEFORMLAB_EXE +
                          " run --pipeline cpu --grid 8x6 --steps 12 --no-state --out " + out.string() +
                          " >/dev/null' 2>" + err.string();
  const int status = std::system(cmd.c_str());
  if (WEXITSTATUS(status) == 99 || (WEXITSTATUS(status) == 1 && slurp(err).find("unshare") != std::string::npos))
    GTEST_SKIP() << "no bind mount in a mount namespace here: " << slurp(err);
  EXPECT_EQ(WEXITSTATUS(status), 1);
  const std::string line = slurp(err);
  EXPECT_EQ(line.rfind("deformlab: error: cannot remove the manifest of output folder '" + out.string() + "' (", 0),
            0u) << line;
  EXPECT_EQ(std::count(line.begin(), line.end(), '\n'), 1) << line;
  std::map<std::string, std::string> after;
  fs::path kept;
  for (const auto& e : fs::directory_iterator(out))
    if (e.path().filename().string().starts_with("unsaved-run-")) kept = e.path();
    else after[e.path().filename().string()] = slurp(e.path());
  EXPECT_EQ(after, before) << "the folder as it was";
  EXPECT_TRUE(line.ends_with("; this run's outputs are in '" + kept.string() + "'\n")) << line;
  EXPECT_EQ(nlohmann::json::parse(slurp(kept / "manifest.json"))["result"]["steps"], 12);
}

// `deformlab mesh` writes the mesh an experiment's model generates; a scene naming that file in
// place of "generate" runs on it, with the nodes the command counted.
TEST_F(Cli, MeshWritesAGeneratedMeshThatARunReads) {
  write("x.json", R"({"scene": {"model": {"type": "mesh", "pins": "none",
                                         "generate": {"shape": "box", "size": [1, 1, 1], "cell_size": 1}}},
      "sweep": {"models": [{"name": "small", "model": {"generate": {"shape": "sheet", "size": [0.2, 0.1], "cell_size": 0.02}}}],
                "pipelines": ["cpu"]}})");
  const fs::path file = dir_ / "meshes" / "small.msh";
  const Result made = run("mesh --experiment " + (dir_ / "x.json").string() + " --model small --out " + file.string());
  ASSERT_EQ(made.code, 0) << made.err;
  EXPECT_NE(made.out.find("Gmsh sheet 0.2 x 0.1 m, cell 0.02 m"), std::string::npos) << made.out;
  const int node_count = mesh_nodes(made.out);
  EXPECT_GT(node_count, 50) << made.out;
  const std::string nodes = std::to_string(node_count);
  EXPECT_NE(made.out.find("triangles, made and written in"), std::string::npos) << made.out;
  EXPECT_NE(made.out.find("\n  reading it back to check the scene's pins and drag on it\n  checked in "),
            std::string::npos)
      << made.out;
  ASSERT_TRUE(fs::is_regular_file(file));
  // A folder by that name is refused, as it stands.
  fs::create_directories(dir_ / "folder.msh");
  const Result folder = run("mesh --experiment " + (dir_ / "x.json").string() + " --model small --out " +
                            (dir_ / "folder.msh").string());
  EXPECT_EQ(folder.code, 2);
  EXPECT_NE(folder.err.find("folder.msh' is a folder"), std::string::npos) << folder.err;
  EXPECT_TRUE(fs::is_empty(dir_ / "folder.msh"));

  write("s.json", R"({"model": {"type": "mesh", "pins": "none", "file": "meshes/small.msh"}})");
  const Result r = run("run --pipeline cpu --steps 3 --no-state --scene " + (dir_ / "s.json").string() + " --out " +
                       (dir_ / "run").string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find(": " + nodes + " nodes, "), std::string::npos) << r.out;
}

// The mesh is written whatever the scene's pins and drag; what a run on it would refuse is noted.
TEST_F(Cli, MeshNotesWhatARunOfTheSceneWouldRefuse) {
  write("s.json", R"({"model": {"type": "mesh", "pins": [{"box": [[5, 5, 5], [6, 6, 6]]}],
                                "generate": {"shape": "sheet", "size": [0.2, 0.1], "cell_size": 0.05}}})");
  const fs::path file = dir_ / "m.msh";
  const Result made = run("mesh --scene " + (dir_ / "s.json").string() + " --out " + file.string());
  ASSERT_EQ(made.code, 0) << made.err;
  EXPECT_TRUE(fs::is_regular_file(file));
  EXPECT_EQ(made.err, "deformlab: note: a run of this scene on the mesh would refuse it: " +
                          (dir_ / "s.json").string() + ".model.pins[0]: the box holds no node of the model\n");
}

// A pipe at --out is refused before anything is read from it (reading its start had blocked).
TEST_F(Cli, MeshRefusesAPipeAtItsOut) {
  write("s.json", R"({"model": {"type": "mesh", "pins": "none",
                                "generate": {"shape": "sheet", "size": [0.2, 0.1], "cell_size": 0.05}}})");
  const fs::path fifo = dir_ / "f.msh";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const Result r = run("mesh --scene " + (dir_ / "s.json").string() + " --out " + fifo.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err, "deformlab: error: --out '" + fifo.string() + "' is not a regular file, which this would replace: "
                   "remove it or name another file\n");
  EXPECT_TRUE(fs::is_fifo(fifo));
}

// The check places the written mesh as a run naming it would: a generated mesh still takes the
// scene's transform, a filled one is not placed twice. Box pins around where each lies pick
// nodes only so (a missed placement would leave them empty, and a note).
TEST_F(Cli, MeshChecksThePinsOnTheMeshAsARunPlacesIt) {
  write("generated.json", R"({"model": {"type": "mesh", "transform": {"translate": [0, 5, 0]},
      "generate": {"shape": "sheet", "size": [0.2, 0.1], "cell_size": 0.05},
      "pins": [{"box": [[-1, 4.9, -1], [1, 5.1, 1]]}]}})");
  // The bunny's lowest vertex: y = -0.003149 in the file, 0.29994 m placed (0.30600 placed twice).
  write("filled.json", R"({"model": {"type": "mesh", "file": ")" DEFORMLAB_SOURCE_DIR R"(/data/bunny/bunny.obj",
      "scale": 0.02, "transform": {"translate": [0.03, 0.3, 0]}, "fill": "tetrahedra",
      "pins": [{"box": [[-1, 0.29, -1], [1, 0.303, 1]]}]}})");
  for (const char* scene : {"generated", "filled"}) {
    const Result made = run("mesh --scene " + (dir_ / (std::string(scene) + ".json")).string() + " --out " +
                            (dir_ / (std::string(scene) + ".msh")).string());
    ASSERT_EQ(made.code, 0) << scene << ": " << made.err;
    EXPECT_EQ(made.err, "") << scene;
  }
}

// A filled surface (the bunny-soft scene's) written out: a scene naming the file without "fill",
// "scale" and "transform" runs on the nodes the command counted.
TEST_F(Cli, MeshWritesAFilledMeshThatARunReads) {
  const fs::path file = dir_ / "soft.msh";
  const Result made = run("mesh --scene " DEFORMLAB_SOURCE_DIR "/data/bunny/bunny-soft.json --out " + file.string());
  ASSERT_EQ(made.code, 0) << made.err;
  EXPECT_NE(made.out.find("bunny.obj filled with tetrahedra"), std::string::npos) << made.out;
  EXPECT_NE(made.out.find("after the model's scale and transform"), std::string::npos) << made.out;
  const int node_count = mesh_nodes(made.out);
  EXPECT_GT(node_count, 1839) << made.out;  // the surface's nodes and the interior's
  EXPECT_NE(made.out.find("tetrahedra, made and written in"), std::string::npos) << made.out;
  EXPECT_EQ(made.err, "") << "the scene's pins and drag node hold on the placed mesh";
  write("s.json", R"({"model": {"type": "mesh", "pins": "none", "file": "soft.msh"}})");
  const Result r = run("run --pipeline cpu --steps 3 --no-state --scene " + (dir_ / "s.json").string() + " --out " +
                       (dir_ / "run").string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find(": " + std::to_string(node_count) + " nodes, "), std::string::npos) << r.out;
}

// A run on a GPU pipeline says at what clock the GPU ran its steps (NVML, where the NVIDIA driver
// is) or that the clock was not read; a CPU run says nothing of it (above: no "clock:" line).
TEST_F(Cli, GpuRunSaysTheClockItsStepsRanAt) {
  const fs::path out = dir_ / "run";
  const Result r = run("run --pipeline glsl-compute --grid 16x16 --steps 20 --warmup-ms 0 --no-state --out " +
                       out.string());
  if (r.err.find("is not available") != std::string::npos) DEFORMLAB_SKIP_IF_UNAVAILABLE(r.err);
  ASSERT_EQ(r.code, 0) << r.err;
  // Its checks' time is the host's, waiting for the device (a CPU run's: below).
  EXPECT_NE(r.out.find("s  (host clock, waiting for the device)\n"), std::string::npos) << r.out;
  const auto m = nlohmann::json::parse(slurp(out / "manifest.json"));
  const nlohmann::json& clock = m["result"]["sm_clock"];
  if (clock.is_null()) {
    EXPECT_FALSE(test::gpu_required()) << "a run on a GPU machine's GL reads its clock (NVML)";
    EXPECT_NE(r.out.find("  clock: SM clock not read"), std::string::npos) << r.out;
    return;
  }
  EXPECT_GT(clock["samples"].get<int>(), 0);
  EXPECT_GT(clock["sm_mhz_median"].get<unsigned>(), 0u);
  EXPECT_NE(r.out.find("  clock: SM clock " + std::to_string(clock["sm_mhz_min"].get<unsigned>()) + "-"),
            std::string::npos) << r.out;
}

// The summary's stages: a run that checks once has its reductions in one step, and says so.
TEST_F(Cli, SummarySaysInHowManyStepsAStageRan) {
  const Result r = run("run --pipeline cpu --grid 8x6 --steps 10 --check-every 1000 --no-state --out " +
                       (dir_ / "run").string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("    reductions"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("(host clock; in 1 step)"), std::string::npos) << r.out;
  const std::size_t step = r.out.find("    step ");
  ASSERT_NE(step, std::string::npos) << r.out;
  EXPECT_EQ(r.out.substr(step, r.out.find('\n', step) - step).find("; in"), std::string::npos) << r.out;
}

// A 4096x4096 cloth (16.8 M nodes) on cpu within memory: the model is its nodes (16 bytes
// each), the whole run peaks near what the memory check counts (model, the pipeline's 5
// vectors of floats, one state) and the final state streams into state.ply.
TEST_F(Cli, LargeClothRunsWithinItsCountedMemory) {
  const fs::path out = dir_ / "large";
  const Result r = run("run --pipeline cpu --grid 4096x4096 --steps 2 --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.err;
  const auto m = nlohmann::json::parse(slurp(out / "manifest.json"));
  const double nodes = 4096.0 * 4096.0;
  EXPECT_EQ(m["model"]["host_bytes"].get<double>(), 16 * nodes);
  const auto& mem = m["memory"];
  const double counted = mem["model_host_bytes"].get<double>() + mem["pipeline_host_bytes"].get<double>() +
                         mem["state_host_bytes"].get<double>();
  EXPECT_EQ(counted, (16 + 60 + 24) * nodes);
#ifdef __SANITIZE_ADDRESS__
  // AddressSanitizer adds a shadow byte per 8 and holds freed blocks in a 256 MiB quarantine.
  const double sanitizer = counted / 8 + (256 << 20);
#else
  const double sanitizer = 0.0;
#endif
  // Beyond what is counted: the process's own (its libraries, about 50 MB in a run of an 8 x 8
  // cloth) and the output's buffers.
  EXPECT_LT(mem["peak_resident_bytes"].get<double>(), counted + sanitizer + (128 << 20)) << "peak resident bytes";
  EXPECT_GT(mem["peak_resident_bytes"].get<double>(), counted) << "peak resident bytes";
  std::string head(4096, '\0');
  std::ifstream(out / "state.ply", std::ios::binary).read(head.data(), std::streamsize(head.size()));
  EXPECT_EQ(fs::file_size(out / "state.ply"), head.find("end_header\n") + 11 + nodes * 24 + 2 * 4095.0 * 4095.0 * 13);
}

TEST_F(Cli, GridFlagOnAMeshSceneSaysItReplacesTheMesh) {
  write("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  write("s.json", R"({"model": {"type": "mesh", "file": "m.obj", "pins": "none"}})");
  const Result r = run("run --pipeline cpu --scene " + (dir_ / "s.json").string() + " --grid 8x8 --steps 2 --out " +
                       (dir_ / "g").string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "deformlab: note: --grid 8x8 replaces the scene's mesh model with a cloth\n");
  EXPECT_NE(r.out.find("cloth 8x8: 64 nodes"), std::string::npos) << r.out;
}

// A dt over the integrator's tightest bound on the linearised springs and damping is noted (the
// bound is conservative: the run may still be stable); under the bounds, nothing is said.
TEST_F(Cli, NotesADtOverTheStabilityBound) {
  const Result over =
      run("run --pipeline cpu --lattice 8x8x8 --integrator rk4 --dt 0.003 --steps 5 --out " + (dir_ / "over").string());
  ASSERT_EQ(over.code, 0) << over.err;
  EXPECT_NE(over.err.find("deformlab: note: dt = 0.003 s is above rk4's stability bound dt < 0.0027 s "
                          "on this model's linearised springs: the run may diverge\n"),
            std::string::npos)
      << over.err;
  // The scene's springs are damped (0.02 N s/m): together with the stiffness semi-implicit
  // Euler's bound is lower than the springs' alone (1.91 ms), and the note names that one.
  for (const char* dt : {"0.002", "0.0019"}) {
    const Result both = run("run --pipeline cpu --lattice 8x8x8 --dt " + std::string(dt) + " --steps 5 --out " +
                            (dir_ / "both").string());
    ASSERT_EQ(both.code, 0) << both.err;
    EXPECT_NE(both.err.find("note: dt = " + std::string(dt) + " s is above semi-implicit-euler's bound for the springs "
                            "and the damping together (dt < 0.00181 s,"),
              std::string::npos)
        << both.err;
  }
  const Result under =
      run("run --pipeline cpu --lattice 8x8x8 --dt 0.0018 --steps 5 --out " + (dir_ / "under").string());
  ASSERT_EQ(under.code, 0) << under.err;
  EXPECT_EQ(under.err.find("note: dt"), std::string::npos) << under.err;
}

// A convergence run whose stop rule would start after max_steps says so before it runs and
// after; a scene file sets max_steps low, so that the run is short.
TEST_F(Cli, NotesAStopRuleThatStartsAfterMaxSteps) {
  write("s.json", R"({"model": {"size": [8, 8]}, "dt": 0.001, "max_steps": 200,
                      "drag": {"node": "center", "path": [[0.5, 0, 1, 0]]}})");
  const Result r = run("run --pipeline cpu --scene " + (dir_ / "s.json").string() + " --out " + (dir_ / "o").string());
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string start = "the stop rule starts at step 500 (min_steps and the drag path's end at t = 0.5 s), after max_steps";
  EXPECT_NE(r.err.find("note: " + start + " (200): this run takes 200 steps and cannot converge"), std::string::npos)
      << r.err;
  EXPECT_NE(r.out.find("not converged: " + start + "\n"), std::string::npos) << r.out;
}

// --steps on an experiment that runs until converged makes a run of that many steps, as its
// summary says; with --until-converged as well, they are the most the stop rule may take.
TEST_F(Cli, StepsOnAConvergenceExperimentSayWhatTheyMake) {
  write("x.json", R"({"until_converged": true, "scene": {"model": {"size": [6, 6]}, "drag": null}})");
  const std::string x = "run --pipeline cpu --experiment " + (dir_ / "x.json").string() + " --steps 120 --out ";
  const Result fixed = run(x + (dir_ / "a").string());
  ASSERT_EQ(fixed.code, 0) << fixed.err;
  EXPECT_NE(fixed.out.find("steps: 120 (0.24 s simulated); fixed step count"), std::string::npos) << fixed.out;
  const Result capped = run(x + (dir_ / "b").string() + " --until-converged");
  ASSERT_EQ(capped.code, 0) << capped.err;
  EXPECT_EQ(capped.out.find("fixed step count"), std::string::npos) << capped.out;
}

TEST_F(Cli, PapersAliasesAndLattices) {
  const Result r = run("run --pipeline omp --integrator implicit-euler --lattice 4x3x5 --steps 5 --out " +
                       (dir_ / "lat").string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("semi-implicit-euler"), std::string::npos);
  EXPECT_NE(r.out.find("lattice 4x3x5: 60 nodes"), std::string::npos) << r.out;
}

TEST_F(Cli, ListShowsEveryPipelineAndIntegrator) {
  const Result r = run("list");
  ASSERT_EQ(r.code, 0);
  for (const char* name : {"cpu", "omp", "reference", "glsl-tf", "glsl-compute", "cuda-naive", "cuda-tiled",
                           "cuda-scatter", "cuda-fused", "cuda-temporal", "hybrid", "hybrid-compute", "explicit-euler",
                           "semi-implicit-euler", "midpoint", "rk3", "rk4", "verlet", "backward-euler",
                           "implicit-euler"})
    EXPECT_NE(r.out.find(name), std::string::npos) << name;
  // Each pipeline's options with the values they take, every option's values known.
  EXPECT_NE(r.out.find("options: tile=WxH tma=on|off math=exact|fast\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("options: tile=WxH or WxHxD steps_per_launch=1-8 math=exact|fast\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("options: interop=map|external|external-gpusync|staged force=naive|tiled|scatter"),
            std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("=VALUE"), std::string::npos) << r.out;
}

TEST_F(Cli, FailedRunLeavesTheOutputFolderAsItWas) {
  const fs::path out = dir_ / "kept";
  fs::create_directories(out);
  std::ofstream(out / "notes.txt") << "mine";
  // Files of the user's named as temporaries are named, of a process long gone.
  std::ofstream(out / "thesis.tmp-99999999") << "mine";
  fs::create_directories(out / ".staging-99999999");
  const Result r = run("run --pipeline cpu --integrator explicit-euler --grid 8x8 --dt 0.05 --steps 500 --out " +
                       out.string());
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("diverged at step"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("amplifies undamped spring oscillations at any dt"), std::string::npos) << r.err;
  auto left = [&] {
    std::set<std::string> names;
    for (const auto& e : fs::directory_iterator(out)) names.insert(e.path().filename().string());
    return names;
  };
  const std::set<std::string> mine = {".staging-99999999", "notes.txt", "thesis.tmp-99999999"};
  EXPECT_EQ(left(), mine);
  EXPECT_EQ(slurp(out / "notes.txt"), "mine");
  // A bad input into an existing folder touches nothing either.
  EXPECT_EQ(run("run --grid 0x0 --out " + out.string()).code, 2);
  EXPECT_EQ(left(), mine);
  // Nor does a failed run leave the folders it made for its outputs, also where making them
  // stopped partway (a name too long).
  EXPECT_EQ(run("run --pipeline cpu --grid 4x4 --steps 2 --out " + (out / "new" / std::string(300, 'n')).string()).code, 2);
  EXPECT_EQ(left(), mine);
  EXPECT_EQ(run("run --pipeline cpu --integrator explicit-euler --grid 8x8 --dt 0.05 --steps 500 --out " +
                (out / "new" / "sub/").string()).code, 1);
  EXPECT_EQ(left(), mine);
}

// More OpenMP threads than 4 a hardware thread are capped, with a note (100000 crashed the
// OpenMP runtime).
TEST_F(Cli, OpenMpThreadsPastTheHardwareAreCapped) {
  const std::string program = std::string("OMP_NUM_THREADS=100000 ") + DEFORMLAB_EXE;
  const Result r = run("run --grid 4x4 --pipeline omp --steps 5 --no-state --out " + (dir_ / "o").string(), program.c_str());
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.rfind("deformlab: note: OMP_NUM_THREADS asks for 100000 threads on ", 0), 0u) << r.err;
}

// cuda-temporal holds steps until a launch can take k of them; a check flushes what it holds,
// so checks at other than multiples of k cut its launches short, which the run notes.
TEST_F(Cli, TemporalRunNotesChecksThatCutItsLaunches) {
  const std::string args = "run --pipeline cuda-temporal --integrator verlet --grid 24x24 --steps 8 --no-state --out ";
  const Result every = run(args + (dir_ / "every").string());
  if (every.err.find("is not available") != std::string::npos) DEFORMLAB_SKIP_IF_UNAVAILABLE(every.err);
  EXPECT_EQ(every.code, 0) << every.err;
  EXPECT_NE(every.err.find("note: cuda-temporal runs 2 steps a launch; checking the stop rule every 1 step(s)"),
            std::string::npos) << every.err;
  const Result whole = run(args + (dir_ / "whole").string() + " --check-every 2");
  EXPECT_EQ(whole.code, 0) << whole.err;
  EXPECT_EQ(whole.err.find("note:"), std::string::npos) << whole.err;
}

TEST_F(Cli, TemporalRunNotesThatLatticesRunFasterOnCudaFused) {
  const std::string args = "run --pipeline cuda-temporal --integrator semi-implicit-euler --steps 4 --check-every 2 "
                           "--no-state --out ";
  const Result lattice = run(args + (dir_ / "lattice").string() + " --lattice 9x8x7");
  if (lattice.err.find("is not available") != std::string::npos) DEFORMLAB_SKIP_IF_UNAVAILABLE(lattice.err);
  EXPECT_EQ(lattice.code, 0) << lattice.err;
  EXPECT_NE(lattice.err.find("note: on lattices cuda-temporal took longer a step than cuda-fused"), std::string::npos)
      << lattice.err;
  const Result cloth = run(args + (dir_ / "cloth").string() + " --grid 24x24");
  EXPECT_EQ(cloth.code, 0) << cloth.err;
  EXPECT_EQ(cloth.err.find("note:"), std::string::npos) << cloth.err;
}

}  // namespace
}  // namespace deformlab::test
