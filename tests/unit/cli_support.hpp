// The deformlab command run as a child process, for the CLI tests: its exit code and output,
// files written for it, and the check that a bad input is refused with one line.
#pragma once
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "core/memory.hpp"

namespace deformlab::test {

namespace fs = std::filesystem;

struct Result {
  int code;
  std::string out, err;
};

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    std::replace(name.begin(), name.end(), '/', '_');
    dir_ = fs::temp_directory_path() / ("deformlab-cli-" + std::to_string(::getpid()) + "-" + name);
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // `deformlab ARGS`, or another of the project's programs.
  Result run(const std::string& args, const char* program = DEFORMLAB_EXE) {
    const fs::path out = dir_ / "stdout.txt", err = dir_ / "stderr.txt";
    const std::string cmd = std::string(program) + " " + args + " >" + out.string() + " 2>" + err.string() + " </dev/null";
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
  // A bad input: exit 2 and one line on stderr, "deformlab: error: ..." containing `needle`.
  // Run twice, into a new output folder (not created) and into one that holds a file (kept
  // as it was); arguments that name their own --out run once, as they are.
  void expect_refused(const std::string& args, const std::string& needle) {
    const bool own_out = args.find("--out ") != std::string::npos;
    for (const char* name : {"never", "kept"}) {
      const fs::path out = dir_ / name;
      const bool existing = name == std::string("kept");
      if (existing) {
        fs::create_directories(out);
        std::ofstream(out / "notes.txt") << "mine";
      }
      const Result r = run(own_out ? args : args + " --out " + out.string());
      EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
      EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << "\n" << r.err;
      EXPECT_EQ(r.err.rfind("deformlab: error: ", 0), 0u) << r.err;
      EXPECT_NE(r.err.find(needle), std::string::npos) << args << "\nstderr: " << r.err;
      if (existing) {
        EXPECT_EQ(slurp(out / "notes.txt"), "mine") << args;
        EXPECT_EQ(std::distance(fs::directory_iterator(out), fs::directory_iterator()), 1) << args;
      } else {
        EXPECT_FALSE(fs::exists(out)) << args;
      }
      if (own_out) break;
    }
  }
  fs::path dir_;
};

// The host memory the programs count against (MemAvailable, or a tighter cgroup limit), GiB.
inline double available_gib() {
  const auto limit = host_memory_limit();
  return limit ? double(limit->bytes) / double(1LL << 30) : 1e9;
}

}  // namespace deformlab::test
