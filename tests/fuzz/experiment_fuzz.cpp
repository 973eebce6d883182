// libFuzzer target: experiment text through the experiment and sweep readers (with
// "base" resolving to the built-in experiments). As for scene_fuzz.cpp, only
// std::invalid_argument may end a bad input.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "experiments/experiment.hpp"
#include "experiments/sweep.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace deformlab;
  try {
    const Experiment x = parse_experiment(std::string(reinterpret_cast<const char*>(data), size), "fuzz.json");
    if (const auto s = parse_sweep(x.raw, x.name)) cells(*s);
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
