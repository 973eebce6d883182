// Killed runs and sweeps (SIGKILL to a real child process at several moments): a killed run
// leaves its output folder as it was, a killed sweep completes when run again with every cell
// valid, and no temporary of a killed process outlives the next run.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <map>
#include <nlohmann/json.hpp>
#include <thread>

#include "cli_support.hpp"

namespace deformlab::test {
namespace {

// Starts `deformlab ARGS` and kills it with SIGKILL after `ms` milliseconds (or lets it
// end first); returns whether the kill came before the end.
bool kill_after(const std::string& args, int ms) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string cmd = std::string("exec ") + DEFORMLAB_EXE + " " + args + " >/dev/null 2>&1 </dev/null";
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
  int status = 0;
  while (std::chrono::steady_clock::now() < end) {
    if (::waitpid(pid, &status, WNOHANG) == pid) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ::kill(pid, SIGKILL);
  ::waitpid(pid, &status, 0);
  return true;
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
