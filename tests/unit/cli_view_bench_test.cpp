// `deformlab view`'s checks before its window, --gl-device, deformlab-bench's refusals and a full
// standard output, end to end.
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "cli_support.hpp"
#include "tests/support/gpu_required.hpp"

namespace deformlab::test {
namespace {

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
           {"--summary /proc/x.json", "--summary '/proc/x.json': no file can be made there ("},
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
           {"--lattice 2000x2000x2000", "--lattice (lattice 2000x2000x2000): a model of about 8e+09 nodes exceeds the limit of 2^30 nodes"},
           {"--pipeline cpu --lattice 2000x2000x2000", "--lattice (lattice 2000x2000x2000): a model of about 8e+09 nodes exceeds the limit of 2^30 nodes"},
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

// deformlab-bench checks a size against the host's memory before it builds the model. Its
// largest cloth, 32768 x 32768 (2^30 nodes), needs 40 GiB for that.
TEST_F(Cli, BenchRefusesASizeThatDoesNotFitTheHost) {
  if (available_gib() > 38) GTEST_SKIP() << "this host has room for the bench's largest cloth";
  const Result r = run("cpu --sizes 32768 --reps 1 --warmup 0", DEFORMLAB_BENCH_EXE);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err.rfind("deformlab-bench: error: --sizes: size 32768: a 32768 x 32768 cloth needs ", 0), 0u) << r.err;
  EXPECT_NE(r.err.find(" of host memory for its model and state; "), std::string::npos) << r.err;
}

// deformlab-bench's --csv file is replaced once the bench has ended well: bad input found
// partway (a size past the node limit, after a smaller size ran) leaves the old file, and makes
// no folder for a new one. A file that is no CSV of that bench (another bench's, a run's
// manifest) is refused before it starts.
TEST_F(Cli, BenchReplacesItsCsvOnlyWhenItEndsWell) {
  const fs::path csv = dir_ / "old.csv";
  const std::string args = "cpu --reps 2 --warmup 0 --csv " + csv.string() + " --sizes 8";
  ASSERT_EQ(run(args, DEFORMLAB_BENCH_EXE).code, 0);
  const std::string old = slurp(csv);
  ASSERT_EQ(old.rfind("grid,nodes,pipeline,median_ms", 0), 0u) << old;
  const Result bad = run(args + " 100000", DEFORMLAB_BENCH_EXE);
  EXPECT_EQ(bad.code, 2) << bad.err;
  EXPECT_EQ(slurp(csv), old);
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find("old.csv."), std::string::npos) << e.path();  // no temporary left
  const Result good = run(args + " 10", DEFORMLAB_BENCH_EXE);
  EXPECT_EQ(good.code, 0) << good.err;
  EXPECT_NE(slurp(csv).find("\n10x10,"), std::string::npos) << slurp(csv);
  const fs::path deep = dir_ / "new" / "deeper" / "b.csv";
  EXPECT_EQ(run("cpu --reps 2 --warmup 0 --sizes 8 100000 --csv " + deep.string(), DEFORMLAB_BENCH_EXE).code, 2);
  EXPECT_FALSE(fs::exists(dir_ / "new"));
  const Result made = run("cpu --reps 2 --warmup 0 --sizes 8 --csv " + deep.string(), DEFORMLAB_BENCH_EXE);
  EXPECT_EQ(made.code, 0) << made.err;
  EXPECT_EQ(slurp(deep).rfind("grid,nodes,pipeline,median_ms", 0), 0u) << slurp(deep);

  const fs::path mine = dir_ / "mine.csv";
  std::ofstream(mine) << "precious,data\n";
  const Result refused = run("cpu --reps 2 --warmup 0 --sizes 8 --csv " + mine.string(), DEFORMLAB_BENCH_EXE);
  EXPECT_EQ(refused.code, 2);
  EXPECT_EQ(refused.err.rfind("deformlab-bench: error: --csv '" + mine.string() +
                                  "' holds a file whose first line is not this bench's header (grid,nodes,pipeline,",
                              0),
            0u)
      << refused.err;
  EXPECT_EQ(std::count(refused.err.begin(), refused.err.end(), '\n'), 1) << refused.err;
  EXPECT_EQ(slurp(mine), "precious,data\n");
}

// The cpu bench counts its pipelines' own host memory too: an 18000 x 18000 cloth's model and
// state take 12.1 GiB, with the cpu pipeline's buffers 30.2 (the kernel had killed it).
TEST_F(Cli, BenchCountsItsPipelinesHostMemory) {
  if (available_gib() > 30 || available_gib() < 13) GTEST_SKIP() << "this host's memory is not between the two needs";
  const Result r = run("cpu --sizes 18000 --reps 1 --warmup 0", DEFORMLAB_BENCH_EXE);
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(r.err.rfind("deformlab-bench: error: --sizes: size 18000: a model of 324000000 nodes on cpu needs 30.2 GiB "
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
        std::pair{"cpu --reps 2147483647 --sizes 4", "--reps: '2147483647' is not in 1 to 10000000"},
        std::pair{"cpu --reps 1 --warmup 0 --sizes 4 --csv ''", "--csv: an empty file name"},
        std::pair{"cpu --reps 1 --warmup 0 --sizes 4 --csv /proc/x.csv",
                  "--csv '/proc/x.csv': no file can be made there"},
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

}  // namespace
}  // namespace deformlab::test
