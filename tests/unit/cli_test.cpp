// The deformlab command end to end: the outputs of a run and what a failed run leaves
// (bad inputs: bad_input_test.cpp).
#include <nlohmann/json.hpp>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include "cli_support.hpp"
#include "core/memory.hpp"
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
// each), the whole run peaks near what the memory check counts (model, the pipeline's 6
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
  EXPECT_EQ(counted, (16 + 72 + 36) * nodes);
#ifdef __SANITIZE_ADDRESS__
  // AddressSanitizer adds a shadow byte per 8 and holds freed blocks in a 256 MiB quarantine.
  const double sanitizer = counted / 8 + (256 << 20);
#else
  const double sanitizer = 0.0;
#endif
  EXPECT_LT(mem["peak_resident_bytes"].get<double>(), counted + sanitizer + (64 << 20)) << "peak resident bytes";
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

// A dt over the integrator's bound on the linearised springs is noted (the run may still be
// stable, damped); under it, nothing is said.
TEST_F(Cli, NotesADtOverTheStabilityBound) {
  const Result over = run("run --pipeline cpu --lattice 8x8x8 --steps 5 --out " + (dir_ / "over").string());
  ASSERT_EQ(over.code, 0) << over.err;
  EXPECT_NE(over.err.find("note: dt = 0.002 s is above semi-implicit-euler's stability bound on this model's "
                          "linearised springs (0.00191 s)"),
            std::string::npos)
      << over.err;
  const Result under = run("run --pipeline cpu --lattice 8x8x8 --dt 0.0019 --steps 5 --out " + (dir_ / "under").string());
  ASSERT_EQ(under.code, 0) << under.err;
  EXPECT_EQ(under.err.find("stability bound"), std::string::npos) << under.err;
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

// More OpenMP threads than 4 a hardware thread are capped, with a note (100000 crashed the
// OpenMP runtime).
TEST_F(Cli, OpenMpThreadsPastTheHardwareAreCapped) {
  const std::string program = std::string("OMP_NUM_THREADS=100000 ") + DEFORMLAB_EXE;
  const Result r = run("run --grid 4x4 --pipeline omp --steps 5 --no-state --out " + (dir_ / "o").string(), program.c_str());
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.rfind("deformlab: note: OMP_NUM_THREADS asks for 100000 threads on ", 0), 0u) << r.err;
}

// Output that cannot reach standard output is said, exit 1: a command's, the help's and the
// bench's results.
TEST_F(Cli, AFullStandardOutputIsSaid) {
  const fs::path err = dir_ / "stderr.txt";
  for (const auto& [program, args] : std::vector<std::pair<std::string, std::string>>{
           {"deformlab", " list"}, {"deformlab", " help"}, {"deformlab", " run --help"},
           {"deformlab-bench", " cpu --sizes 8 --reps 1 --warmup 0"}, {"deformlab-bench", " --help"}}) {
    const std::string exe = program == "deformlab" ? DEFORMLAB_EXE : DEFORMLAB_BENCH_EXE;
    const int status = std::system((exe + args + " >/dev/full 2>" + err.string()).c_str());
    EXPECT_EQ(WIFEXITED(status) ? WEXITSTATUS(status) : -1, 1) << program << args;
    EXPECT_EQ(slurp(err), program + ": error: standard output could not be written (a full disk, a closed pipe?)\n")
        << program << args;
  }
}

// The viewer checks its flags, files, names and model before it opens a window (no display
// needed for these).
TEST_F(Cli, ViewRefusesFlagsItCannotKeep) {
  const fs::path deep = dir_ / "deep.json", outside = dir_ / "outside.json";
  std::ofstream(deep) << R"({"model": {"size": [4, 4], "height": -3}, "ground": 0})";
  std::ofstream(outside) << R"({"model": {"size": [4, 4]}, "drag": {"node": 99, "path": [[0, 0, 0, 0]]}})";
  for (const auto& [args, error] : std::vector<std::pair<std::string, std::string>>{
           {"--steps-per-frame 2147483647", "--steps-per-frame must be in 1 to 10000"},
           {"--size 200x1 --record " + (dir_ / "x.mp4").string(), "--record needs a window 2 pixels high or more"},
           {"--record " + (dir_ / "x.txt").string(), "--record '" + (dir_ / "x.txt").string() +
                                                       "': expected a file name ending in .mp4"},
           // From here, checks that a build without a viewer does not reach.
           {"--pipeline nope", "unknown pipeline 'nope' (valid: best, "},
           {"--scene " + (dir_ / "none.json").string(), "cannot open scene file '" + (dir_ / "none.json").string()},
           {"--integrator leap", "unknown integrator 'leap'"},
           {"--pipeline cpu --option tile=8x8", "option 'tile' is not an option of cpu (it has none)"},
           {"--option bogus=1", "--option 'bogus=1': no pipeline has an option 'bogus'"},
           {"--option =", "--option '=': expected NAME=VALUE"},
           {"--option window=4 --option tile=8x8", "--option: no pipeline has all of the options tile, window"},
           {"--option math=quick", "--option: no pipeline reads these values ("},
           {"--pipeline glsl-tf --integrator backward-euler", "integrator 'backward-euler' is not available on glsl-tf"},
           {"--lattice 2000x2000x2000", "a model of about 8e+09 nodes exceeds the limit of 2^30 nodes"},
           {"--pipeline cpu --lattice 2000x2000x2000", "a model of about 8e+09 nodes exceeds the limit of 2^30 nodes"},
           {"--scene " + deep.string(), "node 1 starts 3 m below the ground, deeper than a step may move a node"},
           {"--scene " + outside.string(), outside.string() + ".drag.node: node 99 is outside the model (0..15)"}}) {
    const Result r = run("view " + args);
    if (r.err.find("view needs a build with") != std::string::npos) GTEST_SKIP() << r.err;
    EXPECT_EQ(r.code, 2) << args;
    EXPECT_EQ(r.err.rfind("deformlab: error: " + error, 0), 0u) << r.err;
  }
}

// With `best`, an option only pipelines unavailable here read is refused before the window, with
// the reason (cuda-temporal alone reads steps_per_launch); where they are available, the check
// passes and the window is next (run with no display, so that none opens).
TEST_F(Cli, ViewRefusesAnOptionOnlyUnavailablePipelinesRead) {
  const Result probe = run("run --pipeline cuda-temporal --grid 8x8 --steps 1 --no-state --out " + (dir_ / "p").string());
  const std::string headless = std::string("env -u DISPLAY -u WAYLAND_DISPLAY ") + DEFORMLAB_EXE;
  const Result r = run("view --option steps_per_launch=2", headless.c_str());
  if (r.err.find("view needs a build with") != std::string::npos) GTEST_SKIP() << r.err;
  const std::string refused = "deformlab: error: pipeline 'cuda-temporal' is not available: ";
  EXPECT_EQ(r.code, 2);
  if (probe.err.rfind(refused, 0) == 0 && probe.err.back() == '\n')
    EXPECT_EQ(r.err, "deformlab: error: --option: no pipeline available here has all of the options steps_per_launch "
                     "(cuda-temporal: " + probe.err.substr(refused.size(), probe.err.size() - refused.size() - 1) + ")\n");
  else
    EXPECT_EQ(r.err.rfind("deformlab: error: view needs a display", 0), 0u) << r.err;
}

// --gl-device picks the GPU of a run's OpenGL context: a pipeline with no GL pass makes one only
// to draw --frames.
TEST_F(Cli, GlDeviceNeedsAGlPassOrFrames) {
  const std::string args = "run --pipeline cpu --grid 8x8 --steps 2 --no-state --gl-device 0 --out ";
  const Result bare = run(args + (dir_ / "bare").string());
  if (bare.err.find("need a build with OpenGL") != std::string::npos) GTEST_SKIP() << bare.err;
  EXPECT_EQ(bare.code, 2);
  EXPECT_EQ(bare.err, "deformlab: error: --gl-device: pipeline 'cpu' runs no OpenGL pass, and no --frames are drawn\n");
  EXPECT_FALSE(fs::exists(dir_ / "bare"));
  const Result framed = run(args + (dir_ / "framed").string() + " --frames 2");
  if (framed.err.find("OpenGL unavailable") != std::string::npos) DEFORMLAB_SKIP_IF_UNAVAILABLE(framed.err);
  EXPECT_EQ(framed.code, 0) << framed.err;
  EXPECT_TRUE(fs::exists(dir_ / "framed" / "frames")) << framed.err;
}

// The host memory the programs count against (MemAvailable, or a tighter cgroup limit), GiB.
double available_gib() {
  const auto limit = host_memory_limit();
  return limit ? double(limit->bytes) / double(1LL << 30) : 1e9;
}

// deformlab-bench checks a size against the host's memory before it builds the model. Its
// largest cloth, 32768 x 32768 (2^30 nodes), needs 52 GiB for that.
TEST_F(Cli, BenchRefusesASizeThatDoesNotFitTheHost) {
  if (available_gib() > 50) GTEST_SKIP() << "this host has room for the bench's largest cloth";
  const Result r = run("cpu --sizes 32768 --reps 1 --warmup 0", DEFORMLAB_BENCH_EXE);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err.rfind("deformlab-bench: error: --sizes: size 32768: a 32768 x 32768 cloth needs ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find(" of host memory for its model and state; "), std::string::npos) << r.err;
}

// deformlab-bench's --csv file is replaced once the bench has ended well: bad input found
// partway (a size past the node limit, after a smaller size ran) leaves the old file.
TEST_F(Cli, BenchReplacesItsCsvOnlyWhenItEndsWell) {
  const fs::path csv = dir_ / "old.csv";
  std::ofstream(csv) << "precious,data\n";
  const std::string args = "cpu --reps 2 --warmup 0 --csv " + csv.string() + " --sizes 8";
  const Result bad = run(args + " 100000", DEFORMLAB_BENCH_EXE);
  EXPECT_EQ(bad.code, 2) << bad.err;
  EXPECT_EQ(slurp(csv), "precious,data\n");
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find("old.csv."), std::string::npos) << e.path();  // no temporary left
  const Result good = run(args, DEFORMLAB_BENCH_EXE);
  EXPECT_EQ(good.code, 0) << good.err;
  EXPECT_EQ(slurp(csv).rfind("grid,nodes,pipeline,median_ms", 0), 0u) << slurp(csv);
}

// The cpu bench counts its pipelines' own host memory too: an 18000 x 18000 cloth's model and
// state take 15.7 GiB, with the cpu pipeline's buffers 37.4 (the kernel had killed it).
TEST_F(Cli, BenchCountsItsPipelinesHostMemory) {
  if (available_gib() > 37 || available_gib() < 16) GTEST_SKIP() << "this host's memory is not between the two needs";
  const Result r = run("cpu --sizes 18000 --reps 1 --warmup 0", DEFORMLAB_BENCH_EXE);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err.rfind("deformlab-bench: error: --sizes: size 18000: a model of 324000000 nodes on cpu needs 37.4 GiB "
                        "of host memory",
                        0),
            0u)
      << r.err;
}

// The bench checks every size and its pipelines' integrator before it prints or times anything:
// a size past the node limit after one that runs, a size named twice, an integrator a pipeline
// does not run, a flag of a table it skips, a name or number a flag does not take.
TEST_F(Cli, BenchRefusesBadInputBeforeItPrints) {
  for (const auto& [args, error] :
       {std::pair{"cpu --reps 1 --warmup 0 --sizes 4 100000", "--sizes: size 100000: a model of about 1e+10 nodes exceeds "
                                                              "the limit of 2^30 nodes"},
        std::pair{"cpu --reps 1 --warmup 0 --sizes 4 8 4", "--sizes: size 4 is named twice"},
        std::pair{"cpu --reps 1 --warmup 0 --sizes 4 --csv ''", "--csv: an empty file name"},
        std::pair{"gl --reps 1 --warmup 0 --sizes 4 --integrator backward-euler", "glsl-tf: backward-euler needs"},
        std::pair{"cuda --sizes 64 --graph-sizes 1", "--graph-sizes: size 1: expected 2 or more"},
        // a table's flags where the table is skipped
        std::pair{"cuda --tile-size 0 --tiles 8x8", "--tiles: --tile-size 0 skips the tile sweep"},
        std::pair{"cuda --temporal-sizes 0 --steps-per-launch 2", "--steps-per-launch: --temporal-sizes none or 0 skips"},
        std::pair{"hybrid --modes telepathy", "--modes: 'telepathy' is not one of map, external, external-gpusync, staged"},
        std::pair{"hybrid --updates vertex", "--updates: vertex not in {tf,compute}"},
        std::pair{"hybrid --floor-us nan", "--floor-us: 'nan' is not in 0 to 1000000"}}) {
    const Result r = run(args, DEFORMLAB_BENCH_EXE);
    if (r.err.starts_with("deformlab-bench: error: unknown command '")) continue;  // a build without that backend
    EXPECT_EQ(r.code, 2) << args;
    EXPECT_EQ(r.out, "") << args;
    EXPECT_EQ(r.err.rfind(std::string("deformlab-bench: error: ") + error, 0), 0u) << args << ": " << r.err;
  }
}

// An experiment draws frames of its own scene after its cells: a grid of 2^30 nodes (52 GiB on a
// CUDA pipeline, 124 on omp) is refused before the first cell, with nothing written.
TEST_F(Cli, ExperimentRefusesFramesOfASceneThatDoesNotFitTheHost) {
  if (available_gib() > 50) GTEST_SKIP() << "this host has room for the scene";
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
