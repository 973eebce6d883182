#include "sweep.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <chrono>
#include <fstream>
#include <sstream>

#include "core/run.hpp"
#include "core/scene.hpp"
#include "core/state.hpp"
#include "output.hpp"
#include "pipelines.hpp"
#if DEFORMLAB_HAVE_GL
#include "gl/context.hpp"
#include "gl/render.hpp"
#endif

namespace deformlab {

namespace fs = std::filesystem;
using nlohmann::json;

std::string Cell::id() const {
  std::string s = pipeline + "__" + integrator + "__" + std::to_string(size);
  for (const auto& [k, v] : options) s += "__" + k + "-" + v;
  for (char& ch : s)
    if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '-' && ch != '_' && ch != '.') ch = '_';
  return s;
}

namespace {

[[noreturn]] void bad(const std::string& where, const std::string& what) {
  throw std::invalid_argument(where + ": " + what);
}

std::vector<std::string> strings(const json& j, const std::string& where) {
  if (!j.is_array() || j.empty()) bad(where, "expected a non-empty list of names");
  std::vector<std::string> out;
  for (const auto& e : j) {
    if (!e.is_string()) bad(where, "expected a list of names");
    out.push_back(e.get<std::string>());
  }
  return out;
}

int positive(const json& j, const std::string& where) {
  if (!j.is_number_integer() || j.get<std::int64_t>() < 1 || j.get<std::int64_t>() > 1'000'000)
    bad(where, "expected a positive integer");
  return j.get<int>();
}

}  // namespace

std::optional<Sweep> parse_sweep(const json& x, const std::string& where) {
  if (!x.contains("sweep")) return std::nullopt;
  const json& j = x["sweep"];
  const std::string w = where + ".sweep";
  if (!j.is_object()) bad(w, "expected an object");
  Sweep s;
  for (const auto& [k, v] : j.items()) {
    if (k == "sizes") {
      if (!v.is_array() || v.empty()) bad(w + ".sizes", "expected a non-empty list of sizes");
      for (const auto& n : v) s.sizes.push_back(positive(n, w + ".sizes"));
    } else if (k == "pipelines") s.pipelines = strings(v, w + ".pipelines");
    else if (k == "integrators") s.integrators = strings(v, w + ".integrators");
    else if (k == "options") {
      if (!v.is_array() || v.empty()) bad(w + ".options", "expected a non-empty list of option objects");
      for (const auto& o : v) {
        if (!o.is_object()) bad(w + ".options", "expected objects of NAME: \"VALUE\"");
        PipelineOptions po;
        for (const auto& [name, value] : o.items()) {
          if (!value.is_string()) bad(w + ".options." + name, "expected a string value");
          po[name] = value.get<std::string>();
        }
        s.option_sets.push_back(po);
      }
    } else if (k == "warmup") s.warmup = positive(v, w + ".warmup");
    else if (k == "steps") s.steps = positive(v, w + ".steps");
    else if (k == "repetitions") s.repetitions = positive(v, w + ".repetitions");
    else if (k == "cell_limit_s") {
      if (!v.is_number() || !(v.get<double>() > 0)) bad(w + ".cell_limit_s", "expected a positive number");
      s.cell_limit_s = v.get<double>();
    } else if (k == "time") {
      if (v != "update" && v != "frame") bad(w + ".time", "expected \"update\" or \"frame\" (update + render)");
      s.time = v.get<std::string>();
    } else if (k == "frames") {
      if (!v.is_number_integer() || v.get<std::int64_t>() < 0 || v.get<std::int64_t>() > 100)
        bad(w + ".frames", "expected a number of frames from 0 to 100");
      s.frames = v.get<int>();
    } else if (k == "paper_table") {
      if (v != "table1" && v != "table2" && v != "table3" && v != "")
        bad(w + ".paper_table", "expected \"table1\", \"table2\" or \"table3\"");
      s.paper_table = v.get<std::string>();
    } else
      bad(w + "." + k, "unknown key (expected sizes, pipelines, integrators, options, warmup, steps, "
                       "repetitions, cell_limit_s, time, frames, paper_table)");
  }
  if (s.sizes.empty()) bad(w, "needs sizes");
  if (s.pipelines.empty()) bad(w, "needs pipelines");
  if (s.integrators.empty()) s.integrators = {x.value("integrator", std::string("semi-implicit-euler"))};
  if (s.option_sets.empty()) s.option_sets = {PipelineOptions{}};
  for (const auto& p : s.pipelines)
    if (!pipelines().find(p)) bad(w + ".pipelines", "unknown pipeline '" + p + "' (valid: " + pipelines().names() + ")");
  for (const auto& i : s.integrators)
    if (!parse_integrator(i)) bad(w + ".integrators", "unknown integrator '" + i + "' (valid: " + integrator_names() + ")");
  return s;
}

std::vector<Cell> cells(const Sweep& s) {
  // Sizes outside pipelines, so that consecutive cells share one model.
  std::vector<Cell> out;
  for (const auto& integ : s.integrators)
    for (int n : s.sizes)
      for (const auto& pipe : s.pipelines) {
        // A pipeline runs the option sets whose every name it reads; with none, it runs once.
        const auto& accepted = pipelines().find(pipe)->options;
        std::vector<PipelineOptions> sets;
        for (const auto& o : s.option_sets)
          if (std::all_of(o.begin(), o.end(), [&](const auto& kv) {
                return std::find(accepted.begin(), accepted.end(), kv.first) != accepted.end();
              }) && (!o.empty() || sets.empty()))
            sets.push_back(o);
        if (sets.empty()) sets.push_back({});
        for (const auto& o : sets) out.push_back({n, pipe, integ, o});
      }
  return out;
}

json run_cell(const Experiment& x, const Sweep& s, const Cell& c, ModelCache& cache) {
  using clock = std::chrono::steady_clock;
  json r = {{"id", c.id()}, {"size", c.size}, {"pipeline", c.pipeline}, {"integrator", c.integrator},
            {"options", c.options}};
  auto na = [&](const std::string& why) {
    r["status"] = "n/a";
    r["reason"] = why;
    return r;
  };
  const PipelineEntry& e = *pipelines().find(c.pipeline);
  const Integrator integ = *parse_integrator(c.integrator);
  if (auto why = e.unavailable(); !why.empty()) return na(why);
  if (auto why = e.unsupported(integ); !why.empty()) return na(why);

  Scene scene = x.scene;
  ModelSpec& ms = scene.model;
  ms.nx = ms.ny = c.size;
  ms.nz = ms.topology == Topology::lattice ? c.size : 1;
  const auto k = ms.topology == Topology::lattice ? lattice_spring_counts(ms.nx, ms.ny, ms.nz)
                                                  : cloth_spring_counts(ms.nx, ms.ny);
  const std::int64_t nodes = std::int64_t(ms.nx) * ms.ny * ms.nz, springs = k[0] + k[1] + k[2];
  r["nodes"] = nodes;
  r["springs"] = springs;
  const std::int64_t need = model_bytes(nodes, springs), have = available_memory_bytes();
  if (nodes > (std::int64_t(1) << 30) || (have > 0 && need > have))
    return na("does not fit: needs about " + std::to_string(need >> 20) + " MiB of host memory, " +
              std::to_string(have >> 20) + " MiB available");
  try {
    if (cache.size != c.size || !cache.model) {
      cache.model.reset();  // free the old one before building the next
      cache.model = std::make_unique<Model>(build_model(scene));
      cache.size = c.size;
    }
    const Model& m = *cache.model;
    const Params p = resolve_params(scene, m);
    auto pipe = e.make({m, p, integ, c.options});
    pipe->set_state(rest_state(m));
    // "frame": every step is followed by a draw of the state at 1024 x 1024 (the paper's
    // frame); pipelines outside GL hand their state over through a read-back.
#if DEFORMLAB_HAVE_GL
    std::unique_ptr<gl::Renderer> renderer;
    if (s.time == "frame") {
      if (auto why = gl::unavailable_reason(); !why.empty()) return na("frame timing needs OpenGL: " + why);
      renderer = std::make_unique<gl::Renderer>(m);
    }
    auto step = [&] {
      pipe->step();
      if (renderer) renderer->draw(*pipe);
    };
    auto finish = [&] {
      pipe->max_displacement();
      if (renderer) renderer->take_draw_ms();  // waits for the draws
    };
#else
    if (s.time == "frame") return na("frame timing needs a build with OpenGL");
    auto step = [&] { pipe->step(); };
    auto finish = [&] { pipe->max_displacement(); };
#endif
    // One step first: it bounds the cell's time before committing to it.
    const auto t0 = clock::now();
    step();
    finish();
    const double first_s = std::chrono::duration<double>(clock::now() - t0).count();
    const double expect_s = first_s * (s.warmup + double(s.steps) * s.repetitions);
    if (expect_s > s.cell_limit_s) {
      std::ostringstream os;
      os << "cut: the first step took " << first_s << " s, the cell would need about " << expect_s
         << " s, over its limit of " << s.cell_limit_s << " s";
      return na(os.str());
    }
    for (int w = 1; w < s.warmup; ++w) step();
    finish();
    std::vector<double> ms_per_step;
    for (int rep = 0; rep < s.repetitions; ++rep) {
      const auto b0 = clock::now();
      for (int st = 0; st < s.steps; ++st) step();
      finish();  // waits for the device's last step (and draw)
      ms_per_step.push_back(std::chrono::duration<double, std::milli>(clock::now() - b0).count() / s.steps);
    }
    const double d = pipe->max_displacement();
    // One more batch with a profiler attached, for each stage's time per step; it is kept
    // out of the timed batches (a profiled CUDA pipeline runs pass by pass, not as a graph).
    Profiler prof;
    pipe->set_profiler(&prof);
    for (int st = 1; st <= s.steps; ++st) {
      prof.set_step(st);
      step();
    }
    finish();
    pipe->set_profiler(nullptr);
    json stages = json::array();
    for (const auto& g : prof.summary())
      stages.push_back({{"name", g.name},
                        {"median_ms", g.median_ms},
                        {"clock", g.clock},
                        {"per_step", double(g.spans) / g.steps}});
    if (!stages.empty()) r["stages"] = stages;
    r["status"] = "ok";
    r["median_ms"] = median(ms_per_step);
    r["min_ms"] = *std::min_element(ms_per_step.begin(), ms_per_step.end());
    r["samples_ms"] = ms_per_step;
    r["stable"] = d == d;
    r["pipeline_timing"] = pipe->timing_method();
    r["time"] = s.time;
    r["method"] = "host steady_clock around " + std::to_string(s.steps) +
                  (s.time == "frame" ? " frames (a step and a 1024 x 1024 draw each)" : " steps") +
                  " closed by the pipeline's max-displacement reduction (which waits for the device), "
                  "ms per " + (s.time == "frame" ? "frame" : "step") + ", median of " +
                  std::to_string(s.repetitions) + " batches after " + std::to_string(s.warmup) + " warm-up steps";
    return r;
  } catch (const std::invalid_argument& ex) {
    return na(ex.what());
  } catch (const std::bad_alloc&) {
    return na("does not fit: out of host memory");
  } catch (const std::exception& ex) {  // a pipeline failed (a driver error, a divergence)
    return na(std::string("failed: ") + ex.what());
  }
}

json render_frames(const Experiment& x, const Sweep& s, const fs::path& dir) {
#if DEFORMLAB_HAVE_GL
  if (auto why = gl::unavailable_reason(); !why.empty()) return {{"unavailable", "no OpenGL: " + why}};
  const fs::path tmp = dir / ("frames.tmp-" + std::to_string(::getpid()));
  try {
    const Model m = build_model(x.scene);
    Params p = resolve_params(x.scene, m);
    const Integrator integ = *parse_integrator(x.integrator);
    const PipelineEntry& e = best_pipeline(integ);
    const int span = std::min(p.max_steps, std::max(p.min_steps, int(std::ceil(1.25 * p.drag.end_time() / p.dt))));
    const int every = std::max(1, span / s.frames);
    p.max_steps = every * s.frames;  // the last frame is the last step
    auto pipe = e.make({m, p, integ, {}});
    pipe->set_state(rest_state(m));
    fs::remove_all(tmp);
    gl::FrameWriter frames(m, tmp, every, {512, 512});
    RunOptions opt;
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
    j["files"] = files;
    return j;
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

void write_atomically(const fs::path& file, const std::string& text) {
  const fs::path tmp = file.string() + ".tmp-" + std::to_string(::getpid());
  std::ofstream out(tmp);
  out << text;
  out.close();
  if (!out) throw std::runtime_error("cannot write " + tmp.string());
  fs::rename(tmp, file);
}

json read_manifest(const fs::path& dir) {
  std::ifstream in(dir / "manifest.json");
  if (!in) return nullptr;
  json j = json::parse(in, nullptr, false);
  return j.is_discarded() ? json(nullptr) : j;
}

std::vector<json> load_cells(const fs::path& dir) {
  std::vector<json> out;
  if (!fs::is_directory(dir / "cells")) return out;
  std::vector<fs::path> files;
  for (const auto& f : fs::directory_iterator(dir / "cells"))
    if (f.path().extension() == ".json") files.push_back(f.path());
  std::sort(files.begin(), files.end());
  for (const auto& f : files) {
    std::ifstream in(f);
    out.push_back(json::parse(in));
  }
  return out;
}

int run_sweep(const Experiment& x, const Sweep& s, const fs::path& dir, const SweepOptions& o, const json& command) {
  using clock = std::chrono::steady_clock;
  fs::create_directories(dir / "cells");
  json manifest = {{"experiment", x.raw}, {"command", command}, {"build", build_info()}, {"machine", machine_info()}};
  // The calibration given, else the one an earlier run of this folder recorded; the frames
  // an earlier run rendered.
  manifest["calibration"] = o.calibration;
  if (const json old = read_manifest(dir); old.is_object()) {
    if (old.contains("calibration") && o.calibration.is_null()) manifest["calibration"] = old["calibration"];
    if (old.contains("frames") && fs::exists(dir / "frames")) manifest["frames"] = old["frames"];
  }
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
  ModelCache cache;
  for (const auto& c : all) {
    const fs::path file = dir / "cells" / (c.id() + ".json");
    // A measured cell is done; an n/a one is tried again (the build or machine may differ).
    json r;
    if (fs::exists(file)) {
      std::ifstream in(file);
      r = json::parse(in);
    }
    if (r.is_object() && r["status"] == "ok") {
      ++prog.skipped;
    } else {
      r = run_cell(x, s, c, cache);
      write_atomically(file, r.dump(2) + "\n");
      ++ran;
    }
    ++prog.done;
    prog.elapsed_s = std::chrono::duration<double>(clock::now() - start).count();
    if (o.on_cell) o.on_cell(c, r, prog);
  }
  if (s.frames > 0 && !fs::exists(dir / "frames")) {
    manifest["frames"] = render_frames(x, s, dir);
    write_atomically(dir / "manifest.json", manifest.dump(2) + "\n");
  }
  return ran;
}

}  // namespace deformlab
