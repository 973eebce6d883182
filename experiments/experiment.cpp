#include "experiment.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "core/integrator.hpp"
#include "core/json_file.hpp"

#include "experiment_files.hpp"
#include "pipelines.hpp"

namespace deformlab {

using nlohmann::json;

bool is_plain_name(const std::string& name) {
  return !name.empty() && name.size() <= kPlainNameMax && name != "." && name != ".." && std::all_of(name.begin(), name.end(), [](char ch) {
    return std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' || ch == '_' || ch == '.';
  });
}

namespace {

// Experiments read inside one another through "base" now: a chain longer than this is a loop.
thread_local int bases_open = 0;
constexpr int kMaxBases = 16;

Experiment from_json(const json& j, const std::string& where, const std::string& dir = "") {
  if (!j.is_object()) throw std::invalid_argument(where + ": expected a JSON object");
  Experiment x;
  // "base": start from another experiment's scene and settings (a built-in name or a file).
  if (j.contains("base")) {
    if (!j["base"].is_string() || j["base"].get<std::string>().empty())
      throw std::invalid_argument(where + ".base: expected an experiment name");
    if (bases_open == kMaxBases)
      throw std::invalid_argument(where + ".base: more than " + std::to_string(kMaxBases) +
                                  " experiments based on one another (a loop?)");
    struct Open {
      Open() { ++bases_open; }
      ~Open() { --bases_open; }
    } open;
    Experiment b;
    try {
      b = load_experiment_by_name(j["base"].get<std::string>(), dir);
    } catch (const std::invalid_argument& e) {  // named here only where no file of the chain names it
      const std::string what = e.what();
      const bool unnamed = what.starts_with("no experiment file or built-in") || what.starts_with("cannot open");
      throw std::invalid_argument(unnamed ? where + ".base: " + what : what);
    }
    x.pipeline = b.pipeline;
    x.integrator = b.integrator;
    x.until_converged = b.until_converged;
    x.scene = b.scene;
  }
  x.dir = dir;
  for (const auto& [k, v] : j.items()) {
    auto str = [&, &v = v, &k = k] {
      if (!v.is_string()) throw std::invalid_argument(where + "." + k + ": expected a string");
      return v.get<std::string>();
    };
    if (k == "name") {
      x.name = str();
      if (!is_plain_name(x.name)) throw std::invalid_argument(where + ".name: " + kPlainName);
    } else if (k == "description") x.description = str();
    else if (k == "pipeline") {
      x.pipeline = str();
      if (x.pipeline != "best" && !pipelines().find(x.pipeline))  // also where a sweep names its own, as above
        throw std::invalid_argument(where + ".pipeline: unknown pipeline '" + x.pipeline + "' (valid: best, " +
                                    pipelines().names() + ")");
    }
    else if (k == "integrator") {
      x.integrator = str();
      if (!parse_integrator(x.integrator))  // also where a sweep names its own: a frame or a run takes this one
        throw std::invalid_argument(where + ".integrator: unknown integrator '" + x.integrator + "' (valid: " +
                                    integrator_names() + ")");
    }
    else if (k == "until_converged") {
      if (!v.is_boolean()) throw std::invalid_argument(where + ".until_converged: expected true or false");
      x.until_converged = v.get<bool>();
    } else if (k == "scene") apply_json(x.scene, v, where + ".scene", dir);
    else if (k == "sweep" || k == "base") continue;  // read by parse_sweep / above
    else {
      const std::string hint = "; a scene's key: put it under \"scene\" (a file that is a scene goes to --scene)";
      throw std::invalid_argument(where + "." + k +
                                  ": unknown key (expected name, description, pipeline, integrator, "
                                  "until_converged, base, scene, sweep)" + (is_scene_key(k) ? hint : ""));
    }
  }
  x.raw = j;
  // A sweep without its own integrators reads the experiment's from here: a base's, written in;
  // and the same for a lattice's type, which makes its sizes n^3.
  if (!j.contains("integrator")) x.raw["integrator"] = x.integrator;
  if (x.scene.model.topology == Topology::lattice) x.raw["scene"]["model"]["type"] = "lattice";
  return x;
}

}  // namespace

Experiment parse_experiment(const std::string& text, const std::string& where, const std::string& dir) {
  return from_json(parse_json(text, "experiment file '" + where + "'"), where, dir);
}

Experiment load_experiment(const std::string& path) {
  Experiment x = from_json(read_json_file(path, "experiment file"), path, std::filesystem::path(path).parent_path().string());
  if (const std::string stem = std::filesystem::path(path).stem().string(); x.name.empty() && is_plain_name(stem)) {
    x.name = stem;
    x.raw["name"] = stem;  // as the manifests and reports record it
  }
  return x;
}

Experiment load_experiment_by_name(const std::string& path_or_name, const std::string& from) {
  const std::filesystem::path name(path_or_name);
  const std::string file = name.is_relative() && !from.empty() ? (std::filesystem::path(from) / name).string() : path_or_name;
  if (path_or_name.find_first_of("/.") == std::string::npos) {
    if (const auto text = experiment_files::find(path_or_name + ".json"))
      return parse_experiment(std::string(*text), "built-in " + path_or_name + ".json", builtin_experiments_dir());
    std::error_code ec;
    if (!std::filesystem::exists(file, ec))
      throw std::invalid_argument("no experiment file or built-in experiment '" + path_or_name + "' (built in: " +
                                  builtin_experiment_names(Builtins::sweeps) + "; without a sweep, for `run "
                                  "--experiment`: " + builtin_experiment_names(Builtins::scenes) + ")");
  }
  return load_experiment(file);
}

std::string builtin_experiment_names(Builtins which) {
  std::string names;
  for (std::string_view file : experiment_files::names()) {
    if (!file.ends_with(".json")) continue;
    const bool sweep = json::parse(*experiment_files::find(file)).contains("sweep");
    if (sweep != (which == Builtins::sweeps)) continue;
    names += (names.empty() ? "" : ", ") + std::string(file.substr(0, file.size() - 5));
  }
  return names;
}

std::string builtin_experiments_dir() {
  namespace fs = std::filesystem;
  std::error_code ec;
  for (fs::path p = fs::read_symlink("/proc/self/exe", ec); !ec && p.has_relative_path(); p = p.parent_path())
    if (fs::is_directory(p / "data", ec) && fs::is_directory(p / "experiments", ec))
      return (p / "experiments").string();
  return DEFORMLAB_SOURCE_DIR "/experiments";
}

Experiment default_experiment() {
  return parse_experiment(std::string(experiment_files::paper_drag_json), "built-in paper-drag.json", builtin_experiments_dir());
}

}  // namespace deformlab
