// An experiment file: a scene plus how to run it (pipeline, integrator, stop rule).
#pragma once
#include <string>

#include "core/scene.hpp"

namespace deformlab {

struct Experiment {
  std::string name;
  std::string description;
  std::string pipeline = "best";  // "best": the fastest pipeline available on this machine
  std::string integrator = "semi-implicit-euler";
  bool until_converged = true;
  Scene scene;
};

// Parses experiment JSON text; `where` names it in errors (file name or "built-in ...").
Experiment parse_experiment(const std::string& text, const std::string& where);
Experiment load_experiment(const std::string& path);
// The built-in experiment that `deformlab run` runs with no arguments (experiments/paper-drag.json).
Experiment default_experiment();

}  // namespace deformlab
