// The deformlab command end to end: outputs of a run, and every bad input refused with one
// line on stderr, exit code 2 and nothing written.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace {

namespace fs = std::filesystem;

struct Result {
  int code;
  std::string out, err;
};

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("deformlab-cli-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  Result run(const std::string& args) {
    const fs::path out = dir_ / "stdout.txt", err = dir_ / "stderr.txt";
    const std::string cmd = std::string(DEFORMLAB_EXE) + " " + args + " >" + out.string() + " 2>" + err.string() + " </dev/null";
    const int status = std::system(cmd.c_str());
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
  }
  static std::string slurp(const fs::path& p) {
    std::ifstream in(p);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }
  fs::path write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return dir_ / name;
  }
  // A bad input: exit 2, exactly one line on stderr containing `needle`, `out` not created.
  void expect_refused(const std::string& args, const std::string& needle) {
    const fs::path out = dir_ / "never";
    const Result r = run(args + " --out " + out.string());
    EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("deformlab: error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << args << "\nstderr: " << r.err;
    EXPECT_FALSE(fs::exists(out)) << args;
  }
  fs::path dir_;
};

TEST_F(Cli, RunWritesTimingsStateAndManifest) {
  const fs::path out = dir_ / "run";
  const Result r = run("run --pipeline cpu --integrator verlet --grid 8x6 --steps 10 --compare cpu --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("48 nodes"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("compare: largest position error"), std::string::npos) << r.out;

  const std::string csv = slurp(out / "timings.csv");
  EXPECT_EQ(csv.rfind("step,t_s,step_ms,max_displacement_m\n", 0), 0u);
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
  EXPECT_EQ(m["scene"]["model"]["size"], nlohmann::json::array({8, 6}));
  EXPECT_LT(m["compare"]["max_position_error_relative_to_extent"].get<double>(), 1e-5);
  EXPECT_TRUE(m["build"].contains("compiler"));
  EXPECT_TRUE(m["machine"].contains("hardware_threads"));
  EXPECT_FALSE(fs::exists(out / (".staging-" + std::to_string(::getpid()))));
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
  for (const char* name : {"cpu", "omp", "glsl-tf", "glsl-compute", "cuda-naive", "cuda-tiled", "cuda-scatter",
                           "cuda-fused", "hybrid", "hybrid-compute", "explicit-euler", "semi-implicit-euler",
                           "midpoint", "rk4", "verlet", "backward-euler", "implicit-euler"})
    EXPECT_NE(r.out.find(name), std::string::npos) << name;
}

TEST_F(Cli, BadInputsAreRefused) {
  expect_refused("run --pipeline warp", "unknown pipeline 'warp' (valid: best, ");
  expect_refused("run --integrator leapfrog", "unknown integrator 'leapfrog' (valid: explicit-euler, ");
  expect_refused("run --grid 0x5", "--grid '0x5'");
  expect_refused("run --grid -3x4", "--grid");
  expect_refused("run --grid abcx4", "--grid 'abcx4'");
  expect_refused("run --grid 5", "expected WxH");
  expect_refused("run --grid 5x", "expected WxH");
  expect_refused("run --lattice 2x2", "expected WxHxD");
  expect_refused("run --dt 0", "--dt must be a positive");
  expect_refused("run --dt -1", "--dt");
  expect_refused("run --dt nan", "--dt");
  expect_refused("run --dt abc", "--dt");
  expect_refused("run --steps 0", "--steps");
  expect_refused("run --compare gpu", "--compare");
  expect_refused("run --scene " + (dir_ / "missing.json").string(), "cannot open scene file");
  expect_refused("run --scene " + write("bad.json", "{\"dt\": ").string(), "is not valid JSON");
  expect_refused("run --scene " + write("key.json", "{\"dtt\": 1}").string(), "dtt: unknown key");
  expect_refused("run --experiment " + write("x.json", "{\"pipline\": \"cpu\"}").string(), "pipline: unknown key");
  expect_refused("run --pipeline cpu --option tile=8x8", "--option 'tile' is not an option of cpu");
  expect_refused("run --option tile", "expected NAME=VALUE");
  expect_refused("run --grid 100000x100000", "GiB of memory");
  expect_refused("run --lattice 2000x2000x2000", "GiB of memory");
  expect_refused("run --pipeline cpu --integrator rk4 --grid 4x4 --scene " +
                     write("drag.json", "{\"drag\": {\"node\": 99, \"path\": [[0, 0, 0, 0]]}}").string(),
                 "drag node 99 is outside the model");
  expect_refused("experiment quick --calibration " + (dir_ / "none.json").string(), "cannot read the calibration file");
  expect_refused("experiment quick --calibration " + write("cal.json", "[1, 2]").string(), "not a JSON object");
  expect_refused("experiment quick --calibration " + write("cal2.json", "{\"copy\": {\"GB_per_s\": 0}}").string(),
                 "no ceilings in it");
}

TEST_F(Cli, FailedRunLeavesTheOutputFolderAsItWas) {
  const fs::path out = dir_ / "kept";
  fs::create_directories(out);
  std::ofstream(out / "notes.txt") << "mine";
  const Result r = run("run --pipeline cpu --integrator explicit-euler --grid 8x8 --dt 0.05 --steps 500 --out " +
                       out.string());
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("diverged at step"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("stability limit"), std::string::npos) << r.err;
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(out)) left.push_back(e.path().filename().string());
  EXPECT_EQ(left, std::vector<std::string>{"notes.txt"});
  EXPECT_EQ(slurp(out / "notes.txt"), "mine");
  // A bad input into an existing folder touches nothing either.
  EXPECT_EQ(run("run --grid 0x0 --out " + out.string()).code, 2);
  EXPECT_EQ(std::distance(fs::directory_iterator(out), fs::directory_iterator()), 1);
}

}  // namespace
