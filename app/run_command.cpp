#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <iomanip>
#include <iostream>
#include <limits>
#include <optional>

#include "commands.hpp"
#include "core/clock_watch.hpp"
#include "core/cpu_backend.hpp"
#include "core/interrupt.hpp"
#include "core/number_text.hpp"
#include "core/run.hpp"
#include "experiments/output.hpp"
#include "experiments/pipelines.hpp"
#include "progress.hpp"
#include "run_input.hpp"
#if DEFORMLAB_GL_RENDER
#include "gl/render.hpp"
#endif

namespace deformlab::app {
namespace {

// Windows of Profiler::kSampleWindow steps: one in kRunSampling has its passes timed.
constexpr int kRunSampling = 8;

using nlohmann::json;

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

struct Ran {
  RunResult result;
  json frames;  // the frames' manifest with --frames, else null
  WarmUp warm_up;
  ClockSummary clock;  // the GPU's clock over the run, on pipelines with a GPU pass
  std::vector<EnergySample> energy;  // with --energy
};

// Runs the pipeline from rest, after its warm-up, with the profiler attached; with --frames,
// renders into the staged frames/ folder.
Ran run_pipeline(const RunArgs& a, const RunInput& in, Pipeline& pipe, Profiler& profiler, const OutputDir& dir) {
  // Untimed steps from rest for --warmup-ms (by default kGpuWarmUpMs where a pass runs on a GPU).
  const double warm_ms = a.warmup_ms.value_or(on_gpu(*in.entry) ? kGpuWarmUpMs : 0.0);
  WarmUp warm;
  if (warm_ms > 0.0) warm = warm_up_from_rest(pipe, in.model, warm_ms);
  else pipe.set_state(rest_state(in.model));
  std::optional<ClockWatch> watch;
  if (on_gpu(*in.entry)) watch.emplace(gpu_bus_id(*in.entry));
  const auto clock = [&] { return watch ? watch->stop() : ClockSummary{}; };
  RunOptions opt;
  opt.until_converged = in.until_converged;
  opt.integrator = in.integ;
  opt.profiler = &profiler;
  ProgressLine progress(in.params.max_steps, in.params.dt, in.until_converged ? in.params.threshold : 0.0);
  if (progress.shown()) opt.progress = std::ref(progress);
  // --energy: the state read back at the start, every N steps and after the last.
  std::vector<EnergySample> energies;
  const auto sample_energy = [&](int step) {
    const State s = pipe.state();
    energies.push_back({step, simulated_time_s(step, in.params.dt), energy(in.model, in.params, s)});
  };
  if (a.energy) sample_energy(0);
#if DEFORMLAB_GL_RENDER
  std::optional<gl::FrameWriter> frames;
  if (a.frames) frames.emplace(in.model, dir.staged("frames"), *a.frames, gl::with_obstacles({}, in.params));
#else
  (void)dir;
#endif
  if (a.frames || a.energy)
    opt.after_step = [&](int step) {
#if DEFORMLAB_GL_RENDER
      if (frames && frames->due(step)) {  // a frame span per frame, not per step
        HostSpan span(&profiler, span::frame);
        frames->after_step(pipe, step);
      }
#endif
      if (a.energy && step % *a.energy == 0) sample_energy(step);
    };
  Ran ran{run(pipe, in.model, in.params, opt), nullptr, warm, clock(), {}};
  if (a.energy && energies.back().step != ran.result.steps) sample_energy(ran.result.steps);
  ran.energy = std::move(energies);
#if DEFORMLAB_GL_RENDER
  if (frames) {
    if (!frames->due(ran.result.steps)) {  // else written after that step
      HostSpan span(&profiler, span::frame);
      frames->write_last(pipe, ran.result.steps);
    }
    frames->finish(pipe, ran.result.steps);
    ran.frames = frames->manifest();
  }
#endif
  return ran;
}

// The double-precision CPU run of as many steps from rest, and how far `final_state` is from it.
json compare_with_reference(const RunInput& in, const State& final_state, int steps) {
  auto ref = make_cpu_pipeline({in.model, in.params, in.integ}, Precision::f64, true);
  ref->set_state(rest_state(in.model));
  for (int s = 0; s < steps; ++s) {
    ref->step();
    if (const int sig = InterruptCatcher::caught())
      throw Interrupted(sig, signal_name(sig) + " in --compare's reference run");
  }
  return {{"reference", "double-precision CPU (OpenMP)"},
          {"steps", steps},
          {"max_position_error_relative_to_extent", relative_position_error(final_state, ref->state())}};
}

json stages_of(const Profiler& profiler) {
  json stages = json::array();
  for (const auto& g : profiler.summary())
    stages.push_back({{"name", g.name}, {"median_ms_per_step", g.median_ms}, {"steps", g.steps},
                      {"spans", g.spans}, {"total_ms", g.total_ms}, {"clock", g.clock}});
  return stages;
}

// What the run's memory check counted and the process's measured peak.
json memory_of(const RunInput& in) {
  const Footprint f = in.entry->footprint(in.model.size(), in.integ, in.options);
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return {{"model_host_bytes", in.model.host_bytes()},
          {"pipeline_host_bytes", f.host},
          {"pipeline_device_bytes", f.device},
          {"state_host_bytes", state_host_bytes(in.model.node_count())},
          {"peak_resident_bytes", std::int64_t(u.ru_maxrss) * 1024}};
}

// Medians of the steps' times: on the step clock, and the host's time to queue them.
struct StepMedians {
  double step_ms, queue_ms;
};
// Over the steps whose passes the profiler did not time (its events or queries are device work
// in the steps it samples), or over every step where it sampled them all (--trace, short runs).
StepMedians medians_of(const RunResult& r, const Profiler& profiler) {
  std::vector<double> ms, queue;
  for (bool all : {false, true}) {
    for (const auto& rec : r.records)
      if (all || !profiler.sampled(rec.step)) {
        ms.push_back(rec.ms);
        queue.push_back(rec.queue_ms);
      }
    if (!ms.empty()) break;
  }
  return {median(ms), median(queue)};
}

json manifest_of(const RunArgs& a, const RunInput& in, const Pipeline& pipe, const Ran& ran, const Profiler& profiler,
                 const StepMedians& med, double setup_s) {
  const RunResult& r = ran.result;
  json manifest = {
      {"command", a.argv},
      {"experiment", in.x.name},
      {"pipeline", in.entry->name},
      {"integrator", std::string(info(in.integ).name)},
      {"until_converged", in.until_converged},
      {"options", in.options},
      {"chosen_options", pipe.chosen_options()},
      {"scene", to_json(in.x.scene)},
      {"model", {{"nodes", in.model.node_count()}, {"springs", in.model.spring_count()},
                 {"drag_node", in.params.drag.active() ? in.model.file_index(in.params.drag.node) : -1},
                 {"repairs", in.model.repairs}, {"bandwidth", bandwidth(in.model)},
                 {"stability_limit_s", stability_limit(in.model, in.params, in.integ)},
                 {"host_bytes", in.model.host_bytes()}}},
      {"memory", memory_of(in)},
      {"setup", {{"model_build_s", in.build_s}, {"pipeline_setup_s", setup_s}, {"clock", "host steady_clock"}}},
      {"warm_up", {{"steps", ran.warm_up.steps}, {"ms", ran.warm_up.ms}, {"clock", "host steady_clock"},
                   {"what", "untimed steps from rest before the run, which then starts from rest"}}},
      {"result", {{"steps", r.steps}, {"converged", r.converged}, {"simulated_time_s", simulated_time_s(r.steps, in.params.dt)},
                  {"last_max_displacement_m", r.last_displacement}, {"total_ms", r.total_ms},
                  {"wall_ms", r.wall_ms}, {"wall_clock", "host steady_clock from the first step to the device's end "
                                                         "of the last, checks and frames included"},
                  {"median_step_ms", med.step_ms}, {"step_clock", r.clock},
                  {"median_queue_ms_host_clock", med.queue_ms}, {"stage_timing", pipe.timing_method()},
                  {"sm_clock", to_json(ran.clock)}}},
      {"stages", stages_of(profiler)},
      {"stages_timed_in", profiler.sampled_steps()},
      {"files", {{"timings.csv", "per step: step, t_s, step_ms (on the step clock), queue_ms (host clock around "
                                 "the call that queues the step), max_displacement_m"},
                 {"spans.csv", "per span: name, step, start_ms (host clock), ms, clock (how it was timed); the "
                               "passes' spans in the steps of stages_timed_in"},
                 {"state.ply", "final state: binary little-endian PLY, vertex x y z (m) vx vy vz (m/s)"}}},
      {"build", build_info()},
      {"machine", machine_info()}};
  if (a.trace) manifest["files"]["trace.json"] = "Chrome trace of the spans (open in Perfetto: ui.perfetto.dev)";
  if (a.no_state) manifest["files"].erase("state.ply");
  if (!ran.energy.empty()) {
    const Energy &first = ran.energy.front().e, &last = ran.energy.back().e;
    manifest["energy"] = {{"every_steps", *a.energy}, {"samples", ran.energy.size()},
                          {"first_total_J", first.total()}, {"last_total_J", last.total()}};
    manifest["files"]["energy.csv"] = "the state's energies at step 0, every_steps and the last: step, t_s, "
                                      "kinetic_J, spring_J, field_J (gravity and wind), total_J";
  }
  if (!ran.frames.is_null()) {
    manifest["frames"] = ran.frames;
    manifest["files"]["frames/"] = "PNG frames (and frames.mp4 where ffmpeg is installed); see frames";
  }
  return manifest;
}

void print_summary(const RunArgs& a, const RunInput& in, const Pipeline& pipe, const Ran& ran, const Profiler& profiler,
                   const StepMedians& med, const json& compare, const OutputDir& dir, double setup_s) {
  const Model& m = in.model;
  const RunResult& r = ran.result;
  const WarmUp& warm = ran.warm_up;
  const std::string experiment = in.x.name.empty() ? "the experiment's" : in.x.name + "'s";
  std::cout << "deformlab run: "
            << (a.scene ? "scene " + *a.scene + " (in place of " + experiment + ")" : in.x.name.empty() ? "scene" : in.x.name)
            << " on " << in.entry->name << " ("
            << info(in.integ).name << "), " << describe(in.x.scene.model) << ": " << counted(m.node_count(), "node")
            << ", " << counted(m.spring_count(), "spring") << "\n";
  for (const auto& [name, value] : pipe.chosen_options())
    std::cout << "  option " << name << "=" << value << ": chosen for this machine (none given)\n";
  for (const auto& line : m.repairs) std::cout << "  mesh: " << line << "\n";
  std::cout << "  steps: " << r.steps << " (" << significant_trimmed(simulated_time_s(r.steps, in.params.dt), 6)
            << " s simulated); ";
  if (r.converged)
    std::cout << "converged: no node moved more than " << significant_trimmed(in.params.threshold, 3)
              << " m in the last step\n";
  else if (in.until_converged && r.steps < first_stop_step(in.params))
    std::cout << "not converged: " << stop_rule_start(in.params) << ", after max_steps\n";
  else if (in.until_converged)
    std::cout << "not converged by max_steps: the last check found a node moving "
              << significant_trimmed(r.last_displacement, 3) << " m in a step, over the threshold "
              << significant_trimmed(in.params.threshold, 3) << " m\n";
  else
    std::cout << "fixed step count\n";
  std::cout << "  time: median " << significant(med.step_ms, 4) << " ms/step (" << r.clock << "), "
            << duration_text(r.total_ms / 1000.0) << " in steps";
  if (r.clock != HostStepTimer().clock())
    std::cout << "; queueing a step took " << significant(med.queue_ms, 4) << " ms on the host clock";
  std::cout << "; the run took " << duration_text(r.wall_ms / 1000.0) << " on the host clock (checks"
            << (a.frames ? ", frames" : "") << " included)\n";
  if (on_gpu(*in.entry)) std::cout << "  clock: " << describe(ran.clock) << "\n";
  if (a.compare)
    std::cout << "  compare: largest position error vs the double reference: "
              << compare["max_position_error_relative_to_extent"].get<double>() << " of the model's extent\n";
  std::cout << "  where a step's time goes (median per step; passes timed in " << profiler.sampled_steps() << "):\n";
  // A stage seen in fewer steps than those sampled (the checks of a run that checks rarely, whose
  // last one waits for the queued steps; cuda-temporal's launches) says in how many.
  const int sampled = profiler.sampled_count(r.steps);
  auto stages = profiler.summary();  // the whole step last, below its parts
  std::stable_partition(stages.begin(), stages.end(), [](const auto& g) { return g.name != span::step; });
  for (const auto& g : stages) {
    // A GPU pipeline's check is the host waiting for the device's work, then reading its result.
    const bool waits = on_gpu(*in.entry) && g.name == span::reductions;
    const std::string time = duration_text(g.median_ms / 1000.0);  // "µs" takes 3 bytes for 2 places
    const auto places = std::count_if(time.begin(), time.end(), [](char c) { return (c & 0xC0) != 0x80; });
    std::cout << "    " << std::left << std::setw(13) << g.name << std::string(std::max(0L, 9 - long(places)), ' ')
              << time << "  (" << g.clock << (waits ? ", waiting for the device" : "");
    if (g.steps < sampled) std::cout << "; in " << counted(g.steps, "step");
    std::cout << ")\n";
  }
  const json mem = memory_of(in);
  const double nodes = double(m.node_count());
  std::cout << "  setup: model built in " << duration_text(in.build_s) << ", pipeline in " << duration_text(setup_s);
  if (warm.steps > 0)
    std::cout << "; warm-up: " << counted(warm.steps, "untimed step") << " from rest in "
              << duration_text(warm.ms / 1000.0) << ", then back to rest";
  std::cout << " (host clock)\n";
  const auto per_node = [&](const char* key) { return significant(mem[key].get<double>() / nodes, 3) + " B"; };
  std::cout << "  memory: host " << gib(mem["peak_resident_bytes"]) << " resident at peak; counted per node: model "
            << per_node("model_host_bytes") << ", pipeline " << per_node("pipeline_host_bytes") << ", state "
            << per_node("state_host_bytes");
  if (mem["pipeline_device_bytes"].get<std::int64_t>() > 0)
    std::cout << "; device " << per_node("pipeline_device_bytes") << " ("
              << gib(mem["pipeline_device_bytes"]) << ")";
  if (!ran.energy.empty()) {
    const EnergySample &first = ran.energy.front(), &last = ran.energy.back();
    std::cout << "\n  energy: total " << significant(first.e.total(), 6) << " J at step " << first.step << ", "
              << significant(last.e.total(), 6) << " J at step " << last.step << " (kinetic "
              << significant(last.e.kinetic, 4) << ", springs " << significant(last.e.spring, 4) << ", gravity and wind "
              << significant(last.e.field, 4) << ")"
              << (on_gpu(*in.entry) ? "; with --energy each check and each read back waits for the device: time a "
                                      "run without it"
                                    : "");
  }
  std::cout << "\n  wrote " << dir.dir().string() << "/{timings.csv, spans.csv, " << (a.no_state ? "" : "state.ply, ")
            << "manifest.json" << (a.trace ? ", trace.json" : "") << (a.frames ? ", frames/" : "")
            << (a.energy ? ", energy.csv" : "") << "}\n";
}

// f(), a signal that stops it said to leave the output folder as it was.
template <class F>
auto unless_interrupted(F&& f) {
  try {
    return f();
  } catch (const Interrupted& e) {
    throw Interrupted(e.signal, std::string(e.what()) + ": the run stopped and wrote nothing");
  }
}

}  // namespace

int run_command(const RunArgs& a) {
  return report_errors([&] {
    // 1. Everything is read and checked before anything is written (bad input: exit 2).
    const RunInput in = read_run_input(a);
    // 2. Run, writing into a staging folder that is committed only on success (a signal stops
    // the run and leaves the folder as it was).
    const InterruptCatcher signals;
    std::vector<std::string> writes = {"timings.csv", "spans.csv"};
    if (!a.no_state) writes.push_back("state.ply");
    if (a.trace) writes.push_back("trace.json");
    if (a.frames) writes.push_back("frames/");
    if (a.energy) writes.push_back("energy.csv");
    OutputDir dir(in.out, {"timings.csv", "spans.csv", "state.ply", "trace.json", "frames/", "energy.csv"}, writes);
    const auto t0 = std::chrono::steady_clock::now();
    auto pipe = in.entry->make({in.model, in.params, in.integ, in.options});
    const double setup_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (const int k = pipe->steps_per_launch(); k > 1 && in.params.check_every % k != 0)
      std::cerr << "deformlab: note: " << in.entry->name << " runs " << k << " steps a launch; checking the stop rule "
                << "every " << in.params.check_every << " step(s) launches the steps held at each check, fewer at a "
                << "time, and waits for them (--check-every " << k << " or a multiple of it keeps every launch whole "
                << "and reads each check while the next launch runs)\n";
    if (const std::string passed = step_bound_passed(in.model, in.params, in.integ); !passed.empty())
      std::cerr << "deformlab: note: " << passed << ": the run may diverge\n";
    if (in.until_converged)
      if (const std::string loose = loose_stop_rule(in.model, in.params); !loose.empty())
        std::cerr << "deformlab: note: " << loose << "\n";
    if (in.until_converged && first_stop_step(in.params) > in.params.max_steps)
      std::cerr << "deformlab: note: " << stop_rule_start(in.params) << ", after max_steps ("
                << in.params.max_steps << "): this run takes " << in.params.max_steps << " steps and cannot converge\n";
    if (in.entry->name == "cuda-temporal" && in.model.volume())
      std::cerr << "deformlab: note: on lattices cuda-temporal took longer a step than cuda-fused at every "
                << "steps_per_launch and tile measured (H100, 256^3: a node's 32 springs bind the step to arithmetic, "
                << "which the halo only adds to; docs/speed.md); cuda-fused is the faster choice there\n";
    Profiler profiler;
    profiler.stream_csv(dir.staged("spans.csv").string(), a.trace);  // the trace needs them all
    // The passes' timers are device work in the steps they time, so a run times them in one
    // window of steps in kRunSampling (the step clock's median then comes from steps without
    // them, as in an experiment cell or the bench); a trace times every step.
    profiler.sample_every(a.trace ? 1 : kRunSampling);
    const Ran ran = unless_interrupted([&] { return run_pipeline(a, in, *pipe, profiler, dir); });
    profiler.end_stream();
    const RunResult& r = ran.result;
    const State final_state = pipe->state();
    const json compare =
        a.compare ? unless_interrupted([&] { return compare_with_reference(in, final_state, r.steps); }) : json();
    const StepMedians med = medians_of(r, profiler);

    // A signal while the outputs are written (state.ply can take minutes) stops before the next
    // one, and the folder is left as it was.
    auto unless_signalled = [](const char* next) {
      unless_interrupted([&] {
        if (const int sig = InterruptCatcher::caught())
          throw Interrupted(sig, signal_name(sig) + " before writing " + next);
      });
    };
    write_timings_csv(dir.staged("timings.csv"), r);
    if (a.energy) write_energy_csv(dir.staged("energy.csv"), ran.energy);
    if (a.trace) profiler.write_trace(dir.staged("trace.json").string());
    unless_signalled(a.no_state ? "manifest.json" : "state.ply");
    if (!a.no_state) write_ply(dir.staged("state.ply"), in.model, final_state);
    unless_signalled("manifest.json");
    json manifest = manifest_of(a, in, *pipe, ran, profiler, med, setup_s);
    if (a.compare) manifest["compare"] = compare;
#if DEFORMLAB_GL_RENDER
    if (auto g = gl::run_manifest(*pipe); !g.is_null()) manifest["gl"] = g;
#endif
    write_json(dir.staged("manifest.json"), manifest);
    dir.commit();
    print_summary(a, in, *pipe, ran, profiler, med, compare, dir, setup_s);
    return 0;
  });
}

}  // namespace deformlab::app
