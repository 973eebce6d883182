#include "sweep.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <chrono>
#include <fstream>
#include <sstream>

#include "core/clock_watch.hpp"
#include "core/interrupt.hpp"
#include "core/json_file.hpp"
#include "core/run.hpp"
#include "core/scene.hpp"
#include "core/state.hpp"
#include "core/write_error.hpp"
#include "mesh/scene_model.hpp"
#include "output.hpp"
#include "pipelines.hpp"
#include "sweep_folder.hpp"
#include "sweep_models.hpp"
#if DEFORMLAB_HAVE_GL
#include "gl/context.hpp"
#include "gl/render.hpp"
#endif

namespace deformlab {

namespace fs = std::filesystem;
using nlohmann::json;

std::string Cell::id() const {
  std::string s = pipeline + "__" + integrator + "__" + (model.empty() ? std::to_string(size) : model);
  if (!order.empty()) s += "__" + order;
  for (const auto& [k, v] : options) s += "__" + k + "-" + v;
  for (char& ch : s)
    if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '-' && ch != '_' && ch != '.') ch = '_';
  return s;
}

std::string size_label(int n, bool lattice) { return std::to_string(n) + (lattice ? "³" : "²"); }

std::string Cell::label(bool lattice) const {
  if (model.empty()) return size_label(size, lattice);
  return order.empty() ? model : model + " " + order;
}

namespace {

// Whether `pipeline` reads the option `name`.
bool reads(const std::string& pipeline, const std::string& name) {
  return reads_option(*pipelines().find(pipeline), name);
}

std::vector<std::string> strings(const json& j, const std::string& where) {
  if (!j.is_array() || j.empty()) bad_value(where, "expected a non-empty list of names");
  std::vector<std::string> out;
  for (const auto& e : j) {
    if (!e.is_string()) bad_value(where, "expected a list of names");
    if (std::find(out.begin(), out.end(), e.get<std::string>()) != out.end())
      bad_value(where, "'" + e.get<std::string>() + "' is named twice");
    out.push_back(e.get<std::string>());
  }
  return out;
}

int positive(const json& j, const std::string& where) {
  if (!j.is_number_integer() || j.get<std::int64_t>() < 1 || j.get<std::int64_t>() > 1'000'000)
    bad_value(where, "expected an integer from 1 to 1000000");
  return j.get<int>();
}

}  // namespace

std::optional<Sweep> parse_sweep(const json& x, const std::string& where) {
  if (!x.contains("sweep")) return std::nullopt;
  const json& j = x["sweep"];
  const std::string w = where + ".sweep";
  if (!j.is_object()) bad_value(w, "expected an object");
  Sweep s;
  s.where = where;
  // The experiment's model type, a base's written in (experiments/experiment.cpp).
  const json* model = x.contains("scene") && x["scene"].is_object() && x["scene"].contains("model")
                          ? &x["scene"]["model"]
                          : nullptr;
  s.lattice = model && model->is_object() && model->value("type", json()) == "lattice";
  for (const auto& [k, v] : j.items()) {
    if (k == "sizes") {
      if (!v.is_array() || v.empty()) bad_value(w + ".sizes", "expected a non-empty list of sizes");
      for (const auto& n : v) {
        const std::string at = w + ".sizes[" + std::to_string(s.sizes.size()) + "]";
        s.sizes.push_back(positive(n, at));
        if (std::count(s.sizes.begin(), s.sizes.end(), s.sizes.back()) > 1)
          bad_value(at, "size " + std::to_string(s.sizes.back()) + " is named twice");
        try {
          check_node_count(std::pow(double(s.sizes.back()), s.lattice ? 3 : 2));
        } catch (const std::invalid_argument& e) {
          bad_value(at, "size " + size_label(s.sizes.back(), s.lattice) + ": " + e.what());
        }
      }
    } else if (k == "models") s.models = parse_sweep_models(v, w + ".models");
    else if (k == "orders") s.orders = parse_sweep_orders(v, w + ".orders");
    else if (k == "pipelines") s.pipelines = strings(v, w + ".pipelines");
    else if (k == "integrators") s.integrators = strings(v, w + ".integrators");
    else if (k == "options") {
      if (!v.is_array() || v.empty()) bad_value(w + ".options", "expected a non-empty list of option objects");
      for (const auto& o : v) {
        if (!o.is_object()) bad_value(w + ".options", "expected objects of NAME: \"VALUE\"");
        PipelineOptions po;
        for (const auto& [name, value] : o.items()) {
          if (!value.is_string()) bad_value(w + ".options." + name, "expected a string value");
          po[name] = value.get<std::string>();
        }
        if (std::find(s.option_sets.begin(), s.option_sets.end(), po) != s.option_sets.end())
          bad_value(w + ".options", "an option set is named twice");
        s.option_sets.push_back(po);
      }
    } else if (k == "warmup") {
      s.warmup = positive(v, w + ".warmup");
      if (s.warmup < kBoundingSteps)
        bad_value(w + ".warmup", "expected at least " + std::to_string(kBoundingSteps) +
                                     " warm-up steps (a cell's first two steps bound its time before it is measured)");
    }
    else if (k == "steps") s.steps = positive(v, w + ".steps");
    else if (k == "repetitions") s.repetitions = positive(v, w + ".repetitions");
    else if (k == "cell_limit_s") {
      if (!v.is_number() || !(v.get<double>() >= 0.01 && v.get<double>() <= 1e6))
        bad_value(w + ".cell_limit_s", "expected a number of seconds from 0.01 to 1e6");
      s.cell_limit_s = v.get<double>();
    } else if (k == "time") {
      if (v != "update" && v != "frame") bad_value(w + ".time", "expected \"update\" or \"frame\" (update + render)");
      s.time = v.get<std::string>();
    } else if (k == "frames") {
      if (!v.is_number_integer() || v.get<std::int64_t>() < 0 || v.get<std::int64_t>() > 100)
        bad_value(w + ".frames", "expected a number of frames from 0 to 100");
      s.frames = v.get<int>();
    } else if (k == "paper_table") {
      if (v != "table1" && v != "table2" && v != "table3" && v != "")
        bad_value(w + ".paper_table", "expected \"table1\", \"table2\" or \"table3\"");
      s.paper_table = v.get<std::string>();
    } else
      bad_value(w + "." + k, "unknown key (expected sizes, models, orders, pipelines, integrators, options, warmup, "
                             "steps, repetitions, cell_limit_s, time, frames, paper_table)");
  }
  // A cell's timed steps live in memory until it ends, and are counted in an int.
  if (constexpr std::int64_t most = 10'000'000; std::int64_t(s.steps) * s.repetitions > most)
    bad_value(w + ".repetitions", std::to_string(s.repetitions) + " batches of " + std::to_string(s.steps) +
                                      " steps: a cell times at most " + std::to_string(most) + " steps");
  if (s.sizes.empty() == s.models.empty()) bad_value(w, "needs either sizes or models");
  if (!s.orders.empty() && s.models.empty()) bad_value(w + ".orders", "node orders go with models");
  if (s.pipelines.empty()) bad_value(w, "needs pipelines");
  // Without its own list the sweep takes the experiment's integrator (a base's is written into
  // the experiment's JSON), and an error names that key.
  const std::string integrators_key = s.integrators.empty() ? where + ".integrator" : w + ".integrators";
  if (s.integrators.empty()) s.integrators = {x.value("integrator", std::string("semi-implicit-euler"))};
  if (s.option_sets.empty()) s.option_sets = {PipelineOptions{}};
  for (const auto& p : s.pipelines)
    if (!pipelines().find(p))
      bad_value(w + ".pipelines", "unknown pipeline '" + p + "' (valid: " + pipelines().names() + ")");
  for (std::size_t k = 0; k < s.integrators.size(); ++k) {
    const auto i = parse_integrator(s.integrators[k]);
    if (!i)
      bad_value(integrators_key, "unknown integrator '" + s.integrators[k] + "' (valid: " + integrator_names() + ")");
    for (std::size_t e = 0; e < k; ++e)
      if (parse_integrator(s.integrators[e]) == i)
        bad_value(integrators_key, "'" + s.integrators[k] + "' names the integrator '" + s.integrators[e] + "' names");
  }
  check_models_under_orders(s, w);
  for (const auto& o : s.option_sets)
    for (const auto& entry : o) {
      const std::string& name = entry.first;
      if (std::none_of(s.pipelines.begin(), s.pipelines.end(), [&name](const std::string& p) { return reads(p, name); }))
        bad_value(w + ".options." + name, "no pipeline of this sweep reads option '" + name + "'");
    }
  // A pipeline runs a set whose every option it reads (cells): one that reads some of a set
  // would run without it.
  for (std::size_t k = 0; k < s.option_sets.size(); ++k)
    for (const auto& p : s.pipelines) {
      std::string read, unread;
      for (const auto& [name, value] : s.option_sets[k]) {
        std::string& list = reads(p, name) ? read : unread;
        list += (list.empty() ? "" : ", ") + name;
      }
      if (!read.empty() && !unread.empty())
        bad_value(w + ".options[" + std::to_string(k) + "]",
                  p + " reads " + read + " but not " + unread + ", so it would run without this set (a pipeline "
                  "runs the sets whose every option it reads: give it a set of its own)");
    }
  // Each cell's options as its model reads them: the sweep's grids (its scene's topology) or meshes;
  // its id short enough for a file name with room for its temporary's (output.hpp).
  constexpr std::size_t kMaxId = 200;
  for (const Cell& c : cells(s)) {
    if (c.id().size() > kMaxId)
      bad_value(w, "cell '" + c.id() + "' has a name of " + std::to_string(c.id().size()) + " bytes, more than " +
                       std::to_string(kMaxId) + " (its file's name): shorten its model's name or its options' values");
    try {
      check_options(*pipelines().find(c.pipeline), c.options,
                    !c.model.empty() ? Topology::general : s.lattice ? Topology::lattice : Topology::cloth_grid);
    } catch (const std::invalid_argument& e) {
      bad_value(w + ".options", e.what());
    }
  }
  return s;
}

std::vector<Cell> cells(const Sweep& s) {
  // Sizes (models, orders) outside pipelines, so that consecutive cells share one model.
  std::vector<Cell> models;
  for (int n : s.sizes) models.push_back({n, "", "", {}});
  for (const auto& m : s.models)
    for (const auto& o : s.orders.empty() ? std::vector<std::string>{""} : s.orders)
      models.push_back({0, "", "", {}, m.name, o});
  std::vector<Cell> out;
  for (const auto& integ : s.integrators)
    for (const Cell& model : models)
      for (const auto& pipe : s.pipelines) {
        // A pipeline runs the option sets whose every name it reads (the empty set among them);
        // with none, it runs once, with its defaults.
        std::vector<PipelineOptions> sets;
        for (const auto& o : s.option_sets)
          if (std::all_of(o.begin(), o.end(), [&](const auto& kv) { return reads(pipe, kv.first); })) sets.push_back(o);
        if (sets.empty()) sets.push_back({});
        for (const auto& o : sets) out.push_back({model.size, pipe, integ, o, model.model, model.order});
      }
  return out;
}

void size_model(ModelSpec& ms, int n) {
  ms.nx = ms.ny = n;
  ms.nz = ms.topology == Topology::lattice ? n : 1;
}

std::string size_key(const Sweep& s, int size) {
  const auto k = std::find(s.sizes.begin(), s.sizes.end(), size) - s.sizes.begin();
  return s.where + ".sweep.sizes[" + std::to_string(k) + "]: size " + size_label(size, s.lattice);
}

void require_size_grids(const Experiment& x, const Sweep& s) {
  if (x.scene.model.topology == Topology::general) return;
  for (const int n : s.sizes) {
    Scene scene = x.scene;
    size_model(scene.model, n);
    try {
      grid_spacing(scene.model);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(size_key(s, n) + ": " + e.what());
    }
  }
  if (s.frames == 0) return;
  try {
    grid_spacing(x.scene.model);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(s.where + ".scene.model (" + describe(x.scene.model) +
                                ", the experiment's own scene, whose frames its sweep draws): " + e.what());
  }
}

void require_size_scenes(const Experiment& x, const Sweep& s) {
  for (const int n : s.sizes) {
    Scene scene = x.scene;
    size_model(scene.model, n);
    if (model_size(scene.model).nodes > kCheckedNodes) continue;
    try {
      resolve_params(scene, build_model(scene));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(size_key(s, n) + ": " + e.what());
    }
  }
}

// Why the experiment's own scene, of `size`, whose frames the sweep draws on the best pipeline
// for its integrator, does not fit this host's memory, else "".
std::string frames_shortfall(const Experiment& x, const ModelSize& size) {
  const Integrator integ = *parse_integrator(x.integrator);
  return host_memory_shortfall(size, best_pipeline(integ), integ, {});
}

json render_frames(const Experiment& x, const Sweep& s, const fs::path& dir) {
#if DEFORMLAB_HAVE_GL
  if (auto why = gl::unavailable_reason(); !why.empty()) return {{"unavailable", "no OpenGL: " + why}};
  const fs::path tmp = temporary(dir / "frames");
  try {
    const Model m = build_model(x.scene);
    if (auto why = frames_shortfall(x, m.size()); !why.empty()) return {{"unavailable", "does not fit: " + why}};
    Params p = resolve_params(x.scene, m);
    const Integrator integ = *parse_integrator(x.integrator);
    const PipelineEntry& e = best_pipeline(integ);
    const int span = std::min(p.max_steps, std::max(p.min_steps, int(std::ceil(1.25 * p.drag.end_time() / p.dt))));
    const int every = std::max(1, span / s.frames);
    p.max_steps = every * s.frames;  // the last frame is the last step
    auto pipe = e.make({m, p, integ, {}});
    pipe->set_state(rest_state(m));
    fs::remove_all(tmp);
    gl::FrameWriter frames(m, tmp, every, gl::with_obstacles({512, 512}, p));
    RunOptions opt;
    opt.integrator = integ;
    opt.after_step = [&](int step) { frames.after_step(*pipe, step); };
    const RunResult r = run(*pipe, m, p, opt);
    frames.finish(*pipe, r.steps);
    fs::rename(tmp, dir / "frames");
    std::vector<std::string> files;
    for (const auto& f : fs::directory_iterator(dir / "frames"))
      if (f.path().extension() == ".png") files.push_back("frames/" + f.path().filename().string());
    std::sort(files.begin(), files.end());
    json j = frames.manifest();
    j["pipeline"] = e.name;
    j["integrator"] = x.integrator;
    j["nodes"] = m.node_count();
    j["steps"] = r.steps;
    j["dt_s"] = p.dt;
    j["drag_end_s"] = p.drag.end_time();
    j["files"] = files;
    return j;
  } catch (const Interrupted&) {  // the experiment stops: its next run renders them
    fs::remove_all(tmp);
    throw;
  } catch (const std::exception& ex) {
    fs::remove_all(tmp);
    return {{"unavailable", std::string("rendering failed: ") + ex.what()}};
  }
#else
  (void)x;
  (void)s;
  (void)dir;
  return {{"unavailable", "this build has no OpenGL"}};
#endif
}

namespace {

// What keeps a cell's JSON from being one as cells are written ("its \"method\" is missing or
// not text"), or empty: the report reads these keys as such. A cell edited by hand or damaged
// is measured again by a run, not read.
std::string cell_problem(const json& c) {
  if (!c.is_object() || !c.contains("status") || !c.contains("id")) return "it has no \"status\" and \"id\"";
  using T = json::value_t;
  const std::initializer_list<T> text = {T::string}, whole = {T::number_unsigned, T::number_integer},
                                 real = {T::number_float, T::number_unsigned, T::number_integer}, object = {T::object},
                                 list = {T::array};
  auto kind = [](const json& v, std::initializer_list<T> kinds) {
    return std::find(kinds.begin(), kinds.end(), v.type()) != kinds.end();
  };
  const bool ok = c["status"] == "ok", mesh = c.contains("model");  // a mesh model's cell, else a grid size's
  struct Key {
    const char* name;
    std::initializer_list<T> kinds;
    bool required;
  };
  for (const Key& k : {Key{"id", text, true}, Key{"status", text, true}, Key{"pipeline", text, true},
                       Key{"integrator", text, true}, Key{"options", object, true}, Key{"model", text, false},
                       Key{"order", text, false}, Key{"reason", text, !ok}, Key{"method", text, ok},
                       Key{"step_clock", text, false}, Key{"build", text, false}, Key{"mesh", text, mesh && ok},
                       Key{"size", whole, !mesh}, Key{"nodes", whole, ok}, Key{"springs", whole, mesh && ok},
                       Key{"bandwidth", whole, false}, Key{"chosen_options", object, false},
                       Key{"measurement", object, false}, Key{"sm_clock", {T::object, T::null}, false},
                       Key{"stable", {T::boolean}, false}, Key{"median_ms", real, ok}, Key{"min_ms", real, false},
                       Key{"samples_ms", list, false}, Key{"stages", list, false}})
    if (c.contains(k.name) ? !kind(c[k.name], k.kinds) : k.required)
      return std::string("its \"") + k.name + "\" is " + (c.contains(k.name) ? "of another kind" : "missing");
  for (const char* k : {"options", "chosen_options"})
    if (c.contains(k))
      for (const auto& value : c[k])
        if (!value.is_string()) return std::string("its \"") + k + "\" holds a value that is not text";
  if (c.contains("sm_clock")) try {
      clock_summary(c["sm_clock"]);  // as the report reads it
    } catch (const json::exception&) {
      return "its \"sm_clock\" is not a clock summary";
    }
  // Times a step can take: not negative, and finite (a report would print any number it read).
  const auto time = [](const json& v) { return v.is_number() && v.get<double>() >= 0 && v.get<double>() < 1e30; };
  for (const char* k : {"median_ms", "min_ms"})
    if (c.contains(k) && !time(c[k])) return std::string("its \"") + k + "\" is not a time a step can take";
  for (const json& v : c.contains("samples_ms") ? c["samples_ms"] : json::array())
    if (!time(v)) return "its \"samples_ms\" holds a value that is not a time a step can take";
  for (const json& st : c.contains("stages") ? c["stages"] : json::array())
    if (!st.is_object() || !st.contains("name") || !st["name"].is_string() || !st.contains("clock") ||
        !st["clock"].is_string() || !st.contains("median_ms") || !st["median_ms"].is_number() ||
        (st.contains("per_step") && !st["per_step"].is_number()))
      return "its \"stages\" hold an entry that is not a stage";
  return "";
}

// The cell in `file`, or what keeps it from being one.
std::pair<json, std::string> parse_cell(const fs::path& file) {
  std::ifstream in(file);
  std::ostringstream text;
  text << in.rdbuf();
  try {
    json j = parse_json(text.str(), "it");
    if (std::string problem = cell_problem(j); !problem.empty()) return {nullptr, problem};
    return {std::move(j), ""};
  } catch (const std::invalid_argument& e) {
    return {nullptr, e.what()};
  }
}

}  // namespace

json read_cell(const fs::path& file) { return parse_cell(file).first; }

std::vector<json> load_cells(const fs::path& dir) {
  std::vector<json> out;
  if (!fs::is_directory(dir / "cells")) return out;
  std::vector<fs::path> files;
  for (const auto& f : fs::directory_iterator(dir / "cells"))
    if (f.path().extension() == ".json") files.push_back(f.path());
  std::sort(files.begin(), files.end());
  for (const auto& f : files) {
    auto [j, problem] = parse_cell(f);
    if (j.is_null())
      throw std::invalid_argument("cell file " + f.string() + " is not a cell result (" + problem +
                                  "): if it is one of the sweep's cells, running the experiment again redoes it; else "
                                  "remove it");
    out.push_back(std::move(j));
  }
  return out;
}

void require_same_experiment(const fs::path& dir, const std::string& name) {
  const json old = read_manifest(dir);
  const json was = old.is_object() && old.contains("experiment") && old["experiment"].is_object()
                       ? old["experiment"].value("name", json())
                       : json();
  if (was.is_string() && was.get<std::string>() != name)
    throw std::invalid_argument("results folder " + dir.string() + " holds experiment '" + was.get<std::string>() +
                                "', not '" + name + "': give this one another --out");
}

namespace {

// Whether the experiment's own scene is a grid over --max-size, whose frames are then not drawn.
bool over_max_size(const Experiment& x, std::optional<int> max_size) {
  const ModelSpec& m = x.scene.model;
  return max_size && m.topology != Topology::general && std::max({m.nx, m.ny, m.nz}) > *max_size;
}

}  // namespace

void require_frames_fit(const Experiment& x, const Sweep& s, const fs::path& dir, std::optional<int> max_size) {
  if (s.frames == 0 || x.scene.model.topology == Topology::general || over_max_size(x, max_size)) return;
  const std::string why = frames_shortfall(x, model_size(x.scene.model));
  if (why.empty() || frames_kept(dir, read_manifest(dir), x, s)) return;
#if DEFORMLAB_HAVE_GL
  if (!gl::unavailable_reason().empty()) return;  // no frames drawn here
  throw std::invalid_argument("the experiment's own scene, whose frames its sweep draws (sweep.frames): " + why);
#endif
}

int run_sweep(const Experiment& x, const Sweep& s, const fs::path& dir, const SweepOptions& o, const json& command) {
  using clock = std::chrono::steady_clock;
  require_same_experiment(dir, x.name);
  const bool created = !fs::exists(dir);
  fs::create_directories(dir / "cells");
  reclaim_temporaries(dir);
  reclaim_temporaries(dir / "cells");
  json manifest = {{"experiment", x.raw}, {"command", command}, {"build", build_info()}, {"machine", machine_info()}};
  const json old = read_manifest(dir);
  record_earlier_measurements(dir, old, x, s);
  const json method = measurement(x, s);
  manifest["measurement"] = method;
  manifest["frames_of"] = frames_measurement(x, s);
  // The calibration given, else the one an earlier run of this folder recorded; the frames
  // an earlier run rendered of this scene.
  manifest["calibration"] = o.calibration;
  if (old.is_object() && old.contains("calibration") && o.calibration.is_null()) manifest["calibration"] = old["calibration"];
  if (frames_kept(dir, old, x, s)) manifest["frames"] = old["frames"];
  // Frames that no manifest records come from a run killed in between, or show another scene
  // (require_sweep_folder has seen that they hold nothing else): render them again.
  if (!manifest.contains("frames")) fs::remove_all(dir / "frames");
  json devices = json::object();
  for (const auto& p : s.pipelines)
    if (const auto* e = pipelines().find(p)) devices[p] = e->unavailable().empty() ? "available" : e->unavailable();
  manifest["pipelines"] = devices;
  write_atomically(dir / "manifest.json", manifest.dump(2) + "\n");

  const auto all = cells(s);
  SweepProgress prog;
  prog.total = int(all.size());
  const auto start = clock::now();
  int ran = 0;
  ModelCache cache;  // freed before the frames are rendered
  for (const auto& c : all) {
    const fs::path file = dir / "cells" / (c.id() + ".json");
    // A measured cell is done; an n/a one is tried again (the build or machine may differ).
    json r = fs::exists(file) ? read_cell(file) : json();  // a damaged cell file is redone
    const bool earlier = r.is_object() && !measured_as(r, method, s);  // of another scene or method
    prog.kept = r.is_object() && r["status"] == "ok" && !earlier;
    prog.remeasured = earlier;
    if (prog.kept) {
      ++prog.skipped;
    } else {
      try {
        r = run_cell(x, s, c, cache);
      } catch (const std::invalid_argument&) {  // bad input found at the cell: the sweep stops
        if (created && ran == 0) fs::remove_all(dir);  // nothing measured: the folder this run made goes
        throw;
      }
      r["measurement"] = cell_measurement(method, s, c.model);
      write_atomically(file, r.dump(2) + "\n");
      ++ran;
    }
    ++prog.done;
    prog.elapsed_s = std::chrono::duration<double>(clock::now() - start).count();
    if (o.on_cell) o.on_cell(c, r, prog);
    if (const int sig = InterruptCatcher::caught())
      throw Interrupted(sig, signal_name(sig) + " after " + std::to_string(prog.done) + " of " +
                                 std::to_string(prog.total) + " cells: the cells done are kept, and the experiment "
                                 "run again measures the rest");
  }
  cache = {};
  if (s.frames > 0 && !fs::exists(dir / "frames")) {
    if (over_max_size(x, o.max_size))
      manifest["frames"] = {{"unavailable", "the experiment's " + describe(x.scene.model) + " is over --max-size " +
                                                std::to_string(*o.max_size) + "; a run without it renders them"}};
    else
      manifest["frames"] = render_frames(x, s, dir);
    write_atomically(dir / "manifest.json", manifest.dump(2) + "\n");
  }
  return ran;
}

}  // namespace deformlab
