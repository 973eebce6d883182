// An experiment file: a scene plus how to run it (pipeline, integrator, stop rule).
#pragma once
#include <nlohmann/json.hpp>
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
  std::string dir;     // the folder its relative mesh files are taken from
  nlohmann::json raw;  // the whole file, for parts read elsewhere (the sweep) and manifests
};

// Whether `name` may name an experiment or a sweep's model, and so a folder or file: letters,
// digits, '-', '_' and '.', not empty, not "." or "..".
bool is_plain_name(const std::string& name);
// At most 64 bytes: a cell's file name joins a model's name to its pipeline, integrator and
// options, and a file name takes 255.
constexpr std::size_t kPlainNameMax = 64;
constexpr const char* kPlainName = "expected a name of up to 64 letters, digits, '-', '_' and '.'";

// Parses experiment JSON text; `where` names it in errors (file name or "built-in ...");
// relative mesh files are taken from `dir`.
Experiment parse_experiment(const std::string& text, const std::string& where, const std::string& dir = "");
Experiment load_experiment(const std::string& path);
// A path to an experiment file, or the name of one built into the binary ("table1"). A
// built-in experiment's mesh files are taken from the source tree's experiments/
// (builtin_experiments_dir), as they are when its file there is named by its path.
// A file without a "name" is named by its file name without ".json", where that is a plain name.
// A name that is neither is bad input naming the built-in ones. A relative file is taken from
// folder `from` (an experiment file's, for its "base") where it is given.
Experiment load_experiment_by_name(const std::string& path_or_name, const std::string& from = "");
// The names of the experiments built into the binary (experiments/*.json) with a sweep
// (`deformlab experiment`'s) or without one (scenes for `deformlab run --experiment`),
// comma-separated: "gl-memory, interop, ...".
enum class Builtins { sweeps, scenes };
std::string builtin_experiment_names(Builtins which);
// The experiments/ folder of the source tree this binary was built in: the first folder above
// the running executable that holds data/ and experiments/ (a build inside a tree, wherever the
// tree was moved), else the source tree it was configured from.
std::string builtin_experiments_dir();
// The built-in experiment that `deformlab run` runs with no arguments (experiments/paper-drag.json).
Experiment default_experiment();

}  // namespace deformlab
