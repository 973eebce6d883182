// The experiment runner's tests: a results folder of their own and a small experiment.
#pragma once
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "experiments/experiment.hpp"

namespace deformlab {

namespace fs = std::filesystem;
using nlohmann::json;

class SweepTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("deformlab-sweep-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  static Experiment tiny(const std::string& sweep) {
    return parse_experiment(R"({"name": "tiny", "base": "paper-drag", "integrator": "midpoint",
                                "scene": {"model": {"size": [4, 4]}}, "sweep": )" + sweep + "}", "tiny.json");
  }
  static std::string slurp(const fs::path& p) {
    std::ifstream in(p);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }
  fs::path dir_;
};

}  // namespace deformlab
