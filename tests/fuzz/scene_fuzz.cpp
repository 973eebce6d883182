// libFuzzer target: scene text through the scene reader and, when it is accepted and small,
// the model builder and the drag resolution. Bad input must end in std::invalid_argument
// (the one error the command turns into exit 2); any other exception, a crash or a
// sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "core/json_file.hpp"
#include "core/scene.hpp"
#include "mesh/scene_model.hpp"
#include "experiments/output.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace deformlab;
  try {
    Scene s;
    apply_json(s, parse_json(std::string(reinterpret_cast<const char*>(data), size), "fuzz.json"), "fuzz.json");
    if (model_size(s.model).nodes <= 4096) resolve_params(s, build_model(s));
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
