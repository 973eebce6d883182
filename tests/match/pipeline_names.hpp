// The parameters of the tests run on every registered pipeline: its name, shown in the test's
// name with dashes as underscores.
#pragma once
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "experiments/pipelines.hpp"

namespace deformlab::test {

inline std::vector<std::string> pipeline_names() {
  std::vector<std::string> out;
  for (const auto& e : pipelines().all()) out.push_back(e.name);
  return out;
}

inline std::string pipeline_test_name(const testing::TestParamInfo<std::string>& info) {
  std::string s = info.param;
  for (char& c : s)
    if (c == '-') c = '_';
  return s;
}

}  // namespace deformlab::test
