#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <regex>
#include <sstream>

#include "commands.hpp"
#include "core/cpu_backend.hpp"
#include "core/run.hpp"
#include "experiments/experiment.hpp"
#include "experiments/output.hpp"
#include "experiments/pipelines.hpp"
#if DEFORMLAB_GL_RENDER
#include "gl/context.hpp"
#include "gl/render.hpp"
#endif

namespace deformlab::app {
namespace {

struct BadInput : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// "128x96" -> {128, 96}; `dims` numbers, each a positive integer.
std::vector<int> parse_size(const std::string& s, int dims, const char* flag) {
  const std::string pat = dims == 2 ? "WxH" : "WxHxD";
  std::vector<int> out;
  std::stringstream ss(s);
  for (std::string part; std::getline(ss, part, 'x');) {
    if (part.empty() || !std::all_of(part.begin(), part.end(), ::isdigit))
      throw BadInput(std::string(flag) + " '" + s + "': expected " + pat + " with positive integers");
    const long long v = std::stoll(part.size() > 12 ? std::string("9999999999999") : part);
    if (v <= 0 || v > 1'000'000'000)
      throw BadInput(std::string(flag) + " '" + s + "': each size must be between 1 and 10^9");
    out.push_back(int(v));
  }
  if (int(out.size()) != dims || s.back() == 'x')
    throw BadInput(std::string(flag) + " '" + s + "': expected " + pat);
  return out;
}

// Largest |x - x_ref| over nodes, relative to the reference state's bounding-box diagonal.
double relative_position_error(const State& s, const State& ref) {
  double err = 0.0;
  Vec3d lo = Vec3d(ref.x[0]), hi = lo;
  for (std::size_t i = 0; i < ref.x.size(); ++i) {
    const Vec3d r(ref.x[i]);
    for (int c = 0; c < 3; ++c) { lo[c] = std::min(lo[c], r[c]); hi[c] = std::max(hi[c], r[c]); }
    err = std::max(err, norm(Vec3d(s.x[i]) - r));
  }
  return err / std::max(norm(hi - lo), 1e-12);
}

}  // namespace

int run_command(const RunArgs& a) {
  return report_errors([&] {
    // 1. Everything is read and checked before anything is written (bad input: exit 2).
    Experiment x;
    const PipelineEntry* entry = nullptr;
    Integrator integ{};
    Model model;
    Params params;
    bool until_converged = false;
    PipelineOptions options;
    {
#if DEFORMLAB_GL_RENDER
      if (a.gl_device) gl::configure({.device = *a.gl_device});
      if (a.frames && *a.frames < 1) throw BadInput("--frames must be at least 1");
#else
      if (a.frames || a.gl_device) throw BadInput("--frames and --gl-device need a build with OpenGL");
#endif
      x = a.experiment ? load_experiment(*a.experiment) : default_experiment();
      if (a.scene) {
        Scene s = load_scene(*a.scene);
        x.scene = s;
      }
      if (a.pipeline) x.pipeline = *a.pipeline;
      if (a.integrator) x.integrator = *a.integrator;
      const auto i = parse_integrator(x.integrator);
      if (!i) throw BadInput("unknown integrator '" + x.integrator + "' (valid: " + integrator_names() + ")");
      integ = *i;
      if (x.pipeline == "best") {
        entry = &best_pipeline(integ);
      } else {
        entry = pipelines().find(x.pipeline);
        if (!entry) throw BadInput("unknown pipeline '" + x.pipeline + "' (valid: best, " + pipelines().names() + ")");
      }
      if (const auto why = entry->unavailable(); !why.empty())
        throw BadInput("pipeline '" + entry->name + "' is not available: " + why);
      if (const auto why = entry->unsupported(integ); !why.empty())
        throw BadInput("integrator '" + x.integrator + "' is not available on " + entry->name + ": " + why);

      for (const auto& o : a.options) {
        const auto eq = o.find('=');
        if (eq == std::string::npos || eq == 0) throw BadInput("--option '" + o + "': expected NAME=VALUE");
        const std::string name = o.substr(0, eq);
        if (std::find(entry->options.begin(), entry->options.end(), name) == entry->options.end())
          throw BadInput("--option '" + name + "' is not an option of " + entry->name +
                         (entry->options.empty() ? " (it has none)" : ""));
        options[name] = o.substr(eq + 1);
      }

      ModelSpec& ms = x.scene.model;
      if (a.grid) {
        const auto d = parse_size(*a.grid, 2, "--grid");
        ms.topology = Topology::cloth_grid;
        ms.nx = d[0]; ms.ny = d[1]; ms.nz = 1;
      }
      if (a.lattice) {
        const auto d = parse_size(*a.lattice, 3, "--lattice");
        ms.topology = Topology::lattice;
        ms.nx = d[0]; ms.ny = d[1]; ms.nz = d[2];
      }
      Params& p = x.scene.params;
      if (a.dt) p.dt = float(*a.dt);
      if (a.dt && !(std::isfinite(*a.dt) && *a.dt > 0))
        throw BadInput("--dt must be a positive finite number of seconds");
      if (a.threshold) p.threshold = float(*a.threshold);
      if (a.check_every) p.check_every = *a.check_every;
      if (a.steps) p.max_steps = *a.steps;
      if (a.steps && *a.steps < 1) throw BadInput("--steps must be at least 1");
      until_converged = a.until_converged || (x.until_converged && !a.steps);
      if (a.compare && *a.compare != "cpu")
        throw BadInput("--compare '" + *a.compare + "': the only reference is 'cpu' (double precision)");

      // Memory: refuse sizes that cannot fit before allocating them.
      const auto [nodes, springs] = model_size(ms);
      const std::int64_t need = model_bytes(nodes, springs) * (a.compare ? 2 : 1);
      const std::int64_t have = available_memory_bytes();
      if (nodes > (std::int64_t(1) << 30) || (have > 0 && need > have)) {
        std::ostringstream os;
        os << "a model of " << nodes << " nodes and " << springs << " springs needs about "
           << double(need) / double(1 << 30) << " GiB of memory";
        if (have > 0) os << ", " << double(have) / double(1 << 30) << " GiB are available";
        if (nodes > (std::int64_t(1) << 30)) os << " (and exceeds the limit of 2^30 nodes)";
        throw BadInput(os.str());
      }
      model = build_model(x.scene);
      params = resolve_params(x.scene, model);
    }

    // 2. Run, writing into a staging folder that is committed only on success.
    {
      const std::string out = a.out ? *a.out : "runs/" + (x.name.empty() ? std::string("run") : x.name);
      OutputDir dir(out);
      auto pipe = entry->make({model, params, integ, options});
      pipe->set_state(rest_state(model));
      RunOptions opt;
      opt.until_converged = until_converged;
      Profiler profiler;
      opt.profiler = &profiler;
#if DEFORMLAB_GL_RENDER
      std::optional<gl::FrameWriter> frames;
      if (a.frames) {
        frames.emplace(model, dir.staged("frames"), *a.frames);
        opt.after_step = [&](int step) {
          HostSpan span(&profiler, span::render);
          frames->after_step(*pipe, step);
        };
      }
#endif
      const RunResult r = run(*pipe, model, params, opt);
#if DEFORMLAB_GL_RENDER
      if (frames) frames->finish(*pipe, r.steps);
#endif
      const State final_state = pipe->state();

      nlohmann::json compare;
      double compare_err = -1.0;
      if (a.compare) {
        auto ref = make_cpu_pipeline({model, params, integ}, Precision::f64, true);
        ref->set_state(rest_state(model));
        for (int s = 0; s < r.steps; ++s) ref->step();
        compare_err = relative_position_error(final_state, ref->state());
        compare = {{"reference", "double-precision CPU (OpenMP)"},
                   {"steps", r.steps},
                   {"max_position_error_relative_to_extent", compare_err}};
      }

      std::vector<double> ms;
      for (const auto& rec : r.records) ms.push_back(rec.ms);
      const double med = median(ms);
      const double limit = explicit_stability_limit(model, params);

      write_timings_csv(dir.staged("timings.csv"), r);
      profiler.write_csv(dir.staged("spans.csv").string());
      if (a.trace) profiler.write_trace(dir.staged("trace.json").string());
      nlohmann::json stages = nlohmann::json::array();
      for (const auto& g : profiler.summary())
        stages.push_back({{"name", g.name}, {"median_ms_per_step", g.median_ms}, {"steps", g.steps},
                          {"spans", g.spans}, {"total_ms", g.total_ms}, {"clock", g.clock}});
      write_ply(dir.staged("state.ply"), model, final_state);
      nlohmann::json scene = to_json(x.scene);
      nlohmann::json manifest = {
          {"command", a.argv},
          {"experiment", x.name},
          {"pipeline", entry->name},
          {"integrator", std::string(info(integ).name)},
          {"until_converged", until_converged},
          {"options", options},
          {"scene", scene},
          {"model", {{"nodes", model.node_count()}, {"springs", model.spring_count()},
                     {"drag_node", params.drag.node}, {"explicit_stability_limit_s", limit}}},
          {"result", {{"steps", r.steps}, {"converged", r.converged}, {"simulated_time_s", r.steps * double(params.dt)},
                      {"last_max_displacement_m", r.last_displacement}, {"total_ms", r.total_ms},
                      {"median_step_ms_host_clock", med}, {"stage_timing", pipe->timing_method()}}},
          {"stages", stages},
          {"files", {{"timings.csv", "per step: step, t_s, step_ms (wall), max_displacement_m"},
                     {"spans.csv", "per span: name, step, start_ms (host clock), ms, clock (how it was timed)"},
                     {"state.ply", "final state: binary little-endian PLY, vertex x y z (m) vx vy vz (m/s)"}}},
          {"build", build_info()},
          {"machine", machine_info()}};
      if (a.compare) manifest["compare"] = compare;
      if (a.trace) manifest["files"]["trace.json"] = "Chrome trace of the spans (open in Perfetto: ui.perfetto.dev)";
#if DEFORMLAB_GL_RENDER
      if (frames) manifest["frames"] = frames->manifest();
      if (auto g = gl::run_manifest(*pipe); !g.is_null()) manifest["gl"] = g;
#endif
      write_json(dir.staged("manifest.json"), manifest);
      dir.commit();

      std::cout << "deformlab run: " << (x.name.empty() ? "scene" : x.name) << " on " << entry->name << " ("
                << info(integ).name << "), " << (model.topology == Topology::lattice ? "lattice " : "cloth ")
                << model.nx << "x" << model.ny << (model.topology == Topology::lattice ? "x" + std::to_string(model.nz) : "")
                << ": " << model.node_count() << " nodes, " << model.spring_count() << " springs\n";
      std::cout << "  steps: " << r.steps << " (" << r.steps * double(params.dt) << " s simulated); ";
      if (until_converged)
        std::cout << (r.converged ? "converged: no node moved more than " : "not converged within max_steps; threshold ")
                  << params.threshold << " m in the last step\n";
      else
        std::cout << "fixed step count\n";
      // The run loop's clock is the host's: on a GPU pipeline it measures issuing a step,
      // the stage spans below carry the device-measured times.
      std::cout << std::setprecision(4) << "  time: " << r.total_ms / 1000.0 << " s, median " << med
                << " ms/step on the host clock (pipeline stages timed by " << pipe->timing_method() << ")\n";
      if (a.compare)
        std::cout << "  compare: largest position error vs the double reference: " << compare_err
                  << " of the model's extent\n";
      std::cout << "  where a step's time goes (median per step):\n";
      for (const auto& g : profiler.summary())
        std::cout << "    " << std::left << std::setw(12) << g.name << std::right << std::setw(10) << g.median_ms
                  << " ms  (" << g.clock << ")\n";
      std::cout << "  wrote " << dir.dir().string() << "/{timings.csv, spans.csv, state.ply, manifest.json"
                << (a.trace ? ", trace.json" : "") << "}\n";
      return 0;
    }
  });
}

}  // namespace deformlab::app
