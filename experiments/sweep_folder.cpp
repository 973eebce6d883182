#include "sweep_folder.hpp"

#include <set>
#include <stdexcept>

#include "output.hpp"
#include "report.hpp"

namespace deformlab {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {
// The scene as its cells take it: a fixed number of steps (no stop rule, no runaway check) and,
// on a sweep of sizes, each cell's own size.
json measured_scene(const Experiment& x, const Sweep& s) {
  json j = to_json(x.scene);
  for (const char* k : {"threshold", "min_steps", "max_steps", "check_every", "runaway_factor"}) j.erase(k);
  if (!s.sizes.empty()) j["model"].erase("size");
  return j;
}
}  // namespace

json measurement(const Experiment& x, const Sweep& s) {
  return {{"scene", measured_scene(x, s)},
          {"sweep", {{"warmup", s.warmup}, {"steps", s.steps}, {"repetitions", s.repetitions},
                     {"cell_limit_s", s.cell_limit_s}, {"time", s.time}}}};
}

json cell_measurement(const json& measurement, const Sweep& s, const std::string& model) {
  json m = measurement;
  for (const SweepModel& sm : s.models)
    if (sm.name == model) m["model"] = sm.model;
  return m;
}

bool measured_as(const json& cell, const json& measurement, const Sweep& s) {
  return !cell.contains("measurement") ||
         cell["measurement"] == cell_measurement(measurement, s, cell.value("model", std::string()));
}

json frames_measurement(const Experiment& x, const Sweep& s) {
  return {{"scene", to_json(x.scene)}, {"integrator", x.integrator}, {"frames", s.frames}};
}

namespace {
// Whether manifest `old` holds experiment `x` as written now (a manifest from before the
// measurements were recorded says no more).
bool same_experiment_json(const json& old, const Experiment& x) {
  return old.is_object() && old.contains("experiment") && old["experiment"] == x.raw;
}
}  // namespace

bool frames_kept(const fs::path& dir, const json& old, const Experiment& x, const Sweep& s) {
  // Frames rendered, not the reason why there were none (a run under --max-size).
  std::error_code ec;
  if (!old.is_object() || !old.contains("frames") || !old["frames"].is_object() || !old["frames"].contains("files") ||
      !fs::is_directory(dir / "frames", ec))
    return false;
  return old.contains("frames_of") ? old["frames_of"] == frames_measurement(x, s) : same_experiment_json(old, x);
}

void record_earlier_measurements(const fs::path& dir, const json& old, const Experiment& x, const Sweep& s) {
  std::error_code ec;
  const json now = measurement(x, s);
  const bool same = same_experiment_json(old, x);
  for (const auto& f : fs::directory_iterator(dir / "cells", ec)) {
    if (f.path().extension() != ".json") continue;
    json cell = read_cell(f.path());
    if (cell.is_null() || cell.contains("measurement")) continue;
    cell["measurement"] = same ? cell_measurement(now, s, cell.value("model", std::string()))
                               : json{{"earlier_experiment", old.is_object() ? old.value("experiment", json()) : json()}};
    write_atomically(f.path(), cell.dump(2) + "\n");
  }
}

namespace {

[[noreturn]] void refuse(const fs::path& dir, const std::string& entry, const std::string& why) {
  throw std::invalid_argument("results folder '" + dir.string() + "' holds '" + entry + "', " + why +
                              ": move it or give another --out");
}

}  // namespace

void require_report_targets(const fs::path& dir) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if ((is_report_file(name) || name == "manifest.json") && !e.is_regular_file(ec))
      refuse(dir, name, "where the experiment writes a file");
  }
}

void require_sweep_folder(const fs::path& dir, const Experiment& x, const Sweep& s) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return;
  const json old = read_manifest(dir);
  const bool results = old.is_object() && old.contains("experiment") && old["experiment"].is_object();
  if (!results)
    for (const auto& e : fs::directory_iterator(dir, ec)) {
      const std::string name = e.path().filename().string();
      if (is_report_file(name) || name == "frames" || name == "manifest.json")
        refuse(dir, name, "which no experiment wrote there");
    }
  require_report_targets(dir);
  for (const char* folder : {"cells", "frames"})
    if (fs::exists(fs::symlink_status(dir / folder, ec)) && !fs::is_directory(fs::symlink_status(dir / folder, ec)))
      refuse(dir, folder, "where the experiment writes a folder");
  std::set<std::string> ids;
  if (results)
    for (const auto& c : cells(s)) ids.insert(c.id() + ".json");  // a damaged one is measured again
  for (const auto& f : fs::directory_iterator(dir / "cells", ec)) {
    const std::string name = f.path().filename().string();
    if (is_temporary(name)) continue;  // a killed run's, reclaimed by the next
    if (f.path().extension() != ".json" || (!ids.count(name) && read_cell(f.path()).is_null()))
      refuse(dir, "cells/" + name, "which is not a cell result");
    if (!f.is_regular_file(ec)) refuse(dir, "cells/" + name, "where the experiment writes a cell's file");
  }
  if (frames_kept(dir, old, x, s)) return;
  if (const std::string e = foreign_frames_entry(dir / "frames"); !e.empty()) refuse(dir, "frames/" + e, "which no run writes there");
}

}  // namespace deformlab
