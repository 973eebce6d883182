// Killed and interrupted runs and sweeps (SIGKILL, SIGINT, SIGTERM to a real child process):
// a killed run leaves its output folder as it was, an interrupted one says so as well, a killed
// or interrupted sweep completes when run again with every cell valid, and no temporary of a
// killed process outlives the next run.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <thread>

#include "cli_support.hpp"
#include "tests/support/gpu_required.hpp"

namespace deformlab::test {
namespace {

// Starts `deformlab ARGS` (its stdout into `out`, its stderr into `err`) and sends it `sig` once
// `ready()` holds, asked every 5 ms (or lets it end first); returns whether the signal came
// before the end, and the wait status in `status`.
bool signal_when(const std::string& args, const std::function<bool()>& ready, int sig, int& status,
                 const fs::path& err = "/dev/null", const fs::path& out = "/dev/null") {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string cmd = std::string("exec ") + DEFORMLAB_EXE + " " + args + " >" + out.string() + " 2>" +
                            err.string() + " </dev/null";
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  while (!ready()) {
    if (::waitpid(pid, &status, WNOHANG) == pid) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ::kill(pid, sig);
  ::waitpid(pid, &status, 0);
  return true;
}

// signal_when `ms` milliseconds have passed.
bool signal_after(const std::string& args, int ms, int sig, int& status, const fs::path& err = "/dev/null") {
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
  return signal_when(args, [end] { return std::chrono::steady_clock::now() >= end; }, sig, status, err);
}

bool kill_after(const std::string& args, int ms) {
  int status = 0;
  return signal_after(args, ms, SIGKILL, status);
}

// Every regular file under `dir` by relative path, with its contents.
std::map<std::string, std::string> files_of(const fs::path& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) {
      std::ifstream in(e.path(), std::ios::binary);
      out[fs::relative(e.path(), dir).string()].assign(std::istreambuf_iterator<char>(in), {});
    }
  return out;
}

// Temporaries left anywhere under `dir`.
std::vector<std::string> temporaries(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.find(".deformlab-tmp-") != std::string::npos || name.rfind(".deformlab-staging-", 0) == 0) out.push_back(name);
  }
  return out;
}

TEST_F(Cli, KilledRunLeavesTheFolderAsItWas) {
  const fs::path out = dir_ / "run";
  ASSERT_EQ(run("run --pipeline cpu --grid 8x6 --steps 10 --out " + out.string()).code, 0);
  const auto before = files_of(out);
  for (int ms : {100, 400, 900}) {
    ASSERT_TRUE(kill_after("run --pipeline cpu --grid 256x256 --steps 1000000 --out " + out.string(), ms));
    auto after = files_of(out);
    std::erase_if(after, [](const auto& kv) { return kv.first.rfind(".deformlab-staging-", 0) == 0; });
    EXPECT_EQ(after, before) << "killed after " << ms << " ms";
  }
  const Result r = run("run --pipeline cpu --grid 8x6 --steps 12 --out " + out.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(temporaries(out), std::vector<std::string>{}) << "the killed runs' staging folders are reclaimed";
  EXPECT_EQ(nlohmann::json::parse(slurp(out / "manifest.json"))["result"]["steps"], 12);
}

// SIGINT or SIGTERM stops a run after its step with one line and exit 128 + the signal: a
// folder the run made is gone, an earlier run's is as it was.
TEST_F(Cli, InterruptedRunSaysSoAndLeavesTheFolderAsItWas) {
  const fs::path out = dir_ / "run", fresh = dir_ / "fresh", err = dir_ / "err.txt";
  ASSERT_EQ(run("run --pipeline cpu --grid 8x6 --steps 10 --out " + out.string()).code, 0);
  const auto before = files_of(out);
  for (const int sig : {SIGINT, SIGTERM})
    for (const fs::path& to : {out, fresh}) {
      int status = 0;
      ASSERT_TRUE(signal_after("run --pipeline cpu --grid 256x256 --steps 1000000 --out " + to.string(), 1500, sig,
                               status, err));
      ASSERT_TRUE(WIFEXITED(status)) << "ended by the signal itself";
      EXPECT_EQ(WEXITSTATUS(status), 128 + sig);
      const std::string text = slurp(err), name = sig == SIGINT ? "SIGINT" : "SIGTERM";
      EXPECT_EQ(text.rfind("deformlab: error: " + name + " at step ", 0), 0u) << text;
      EXPECT_NE(text.find(" of 1000000: the run stopped and wrote nothing\n"), std::string::npos) << text;
      EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
    }
  EXPECT_EQ(files_of(out), before);
  EXPECT_FALSE(fs::exists(fresh));
}

// A signal while a run writes its outputs (here: once its timings are staged, before or while
// its 200 MB state.ply is written, which takes the run a second or more) stops it before its
// folder changes. The omp pipeline's 2048² model and state take about 1 GB.
TEST_F(Cli, RunInterruptedWhileWritingLeavesTheFolderAsItWas) {
  const fs::path out = dir_ / "run", err = dir_ / "err.txt";
  ASSERT_EQ(run("run --pipeline cpu --grid 8x6 --steps 10 --out " + out.string()).code, 0);
  const auto before = files_of(out);
  auto timings_staged = [&] {
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(out, ec))
      if (e.path().filename().string().rfind(".deformlab-staging-", 0) == 0 && fs::exists(e.path() / "timings.csv"))
        return true;
    return false;
  };
  int status = 0;
  ASSERT_TRUE(signal_when("run --pipeline omp --grid 2048x2048 --steps 2 --out " + out.string(), timings_staged,
                          SIGTERM, status, err))
      << "the run ended before its timings were staged";
  ASSERT_TRUE(WIFEXITED(status)) << "ended by the signal itself";
  const std::string text = slurp(err);
  EXPECT_EQ(WEXITSTATUS(status), 128 + SIGTERM) << text;
  EXPECT_NE(text.find("deformlab: error: SIGTERM before writing "), std::string::npos) << text;
  EXPECT_NE(text.find(": the run stopped and wrote nothing\n"), std::string::npos) << text;
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
  EXPECT_EQ(files_of(out), before);
}

// A sweep stops between cells: those done are kept, and running it again measures the rest.
TEST_F(Cli, InterruptedSweepKeepsItsCells) {
  // About 4 s of cells on a 2-core machine: still running at the signal on a fast one.
  const fs::path file = write("stop.json", R"({"name": "stop", "base": "paper-drag", "integrator": "semi-implicit-euler",
    "sweep": {"sizes": [160, 192, 224, 256, 288, 320], "pipelines": ["cpu", "omp"],
              "warmup": 2, "steps": 16, "repetitions": 3, "frames": 0}})");
  const fs::path out = dir_ / "sweep", err = dir_ / "err.txt";
  const std::string args = "experiment " + file.string() + " --out " + out.string();
  int status = 0;
  ASSERT_TRUE(signal_after(args, 1500, SIGINT, status, err)) << "the sweep should still be running";
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  const std::string text = slurp(err);
  const std::size_t at = text.find("deformlab: error: SIGINT after ");
  ASSERT_NE(at, std::string::npos) << text;
  const int done = std::stoi(text.substr(at + 31));
  EXPECT_NE(text.find(" of 12 cells: the cells done are kept", at), std::string::npos) << text;
  EXPECT_EQ(int(files_of(out / "cells").size()), done);
  const Result r = run(args);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("ran " + std::to_string(12 - done) + " cells, kept " + std::to_string(done)), std::string::npos)
      << r.out;
}

// SIGINT while a GPU sweep calibrates the device stops the experiment once the calibration's
// measurement ends, before any cell: one line and exit 130. (Calibration needs a CUDA device.)
TEST_F(Cli, InterruptedCalibrationStopsBeforeTheCells) {
  const fs::path file = write("cal.json", R"({"name": "cal", "base": "paper-drag", "integrator": "semi-implicit-euler",
    "sweep": {"sizes": [64], "pipelines": ["cuda-fused"], "warmup": 2, "steps": 4, "repetitions": 1, "frames": 0}})");
  const fs::path out = dir_ / "sweep", log = dir_ / "out.txt", err = dir_ / "err.txt";
  int status = 0;
  const bool signalled = signal_when(
      "experiment " + file.string() + " --out " + out.string(),
      [&] { return slurp(log).find("calibrating this device") != std::string::npos; }, SIGINT, status, err, log);
  if (const std::string text = slurp(log); text.find("no calibration: ") != std::string::npos)
    DEFORMLAB_SKIP_IF_UNAVAILABLE(text.substr(text.find("no calibration: ")));
  ASSERT_TRUE(signalled) << "the experiment ended before it calibrated: " << slurp(log) << slurp(err);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  // The calibration's own lines (its measures, on stderr) come first; the error is the last line.
  const std::string text = slurp(err), line = "deformlab: error: SIGINT while calibrating: the experiment stopped "
                                              "before its cells\n";
  EXPECT_TRUE(text == line || text.ends_with("\n" + line)) << text;
  EXPECT_FALSE(fs::exists(out / "cells")) << "no cell ran";
}

TEST_F(Cli, KilledSweepCompletesWhenRunAgain) {
  const fs::path file = write("kill.json", R"({"name": "kill", "base": "paper-drag", "integrator": "semi-implicit-euler",
    "sweep": {"sizes": [160, 192, 224, 256, 288, 320], "pipelines": ["cpu", "omp"],
              "warmup": 2, "steps": 4, "repetitions": 3, "frames": 0}})");
  const fs::path out = dir_ / "sweep";
  const std::string args = "experiment " + file.string() + " --out " + out.string();
  int killed = 0;
  for (int ms : {150, 300, 500, 800, 1200, 1700}) killed += kill_after(args, ms);
  EXPECT_GE(killed, 3) << "the sweep should still be running at the first kills";
  const Result r = run(args);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto cells = files_of(out / "cells");
  EXPECT_EQ(cells.size(), 12u);
  for (const auto& [name, text] : cells) {
    const auto j = nlohmann::json::parse(text, nullptr, false);
    ASSERT_FALSE(j.is_discarded()) << name;
    EXPECT_EQ(j["status"], "ok") << name;
  }
  EXPECT_TRUE(fs::exists(out / "report.md"));
  EXPECT_EQ(temporaries(out), std::vector<std::string>{});
  // A damaged cell is redone; another experiment into this folder is refused.
  std::ofstream(out / "cells" / cells.begin()->first) << "{\"status\": ";
  ASSERT_EQ(run(args).code, 0);
  EXPECT_EQ(nlohmann::json::parse(slurp(out / "cells" / cells.begin()->first))["status"], "ok");
  expect_refused("experiment quick --out " + out.string(), "holds experiment 'kill'");
}

}  // namespace
}  // namespace deformlab::test
