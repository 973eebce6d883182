// `deformlab-bench hybrid`: ms per step of the hybrid pipelines under each interop mode,
// split by stage, against glsl-tf and cuda-fused, with host time per step beside GPU time.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>

#include "app/command_line.hpp"
#include "bench.hpp"
#include "core/profiler.hpp"
#include "cuda_kernels/cuda_pipeline.hpp"
#include "experiments/pipelines.hpp"
#include "gl/context.hpp"
#include "interop/calibrate.hpp"
#include "interop/hybrid.hpp"

namespace deformlab::bench {
namespace {

struct HybridOptions : BenchOptions {
  std::vector<std::string> modes{"map", "external", "external-gpusync", "staged"};
  std::vector<std::string> updates{"tf", "compute"};
  int steps = 20;  // timed steps at the least
  double floor_us = NAN;  // the calibrated floor; measured here when unset and external-gpusync is swept
  bool baselines = true;  // also time cuda-fused and glsl-tf
};

struct Row {
  int n = 0;
  std::string pipeline, mode;
  double wall_ms = NAN;      // per step: host clock over all steps, drained at the end
  double host_ms = NAN;      // per step: host clock inside step() (issuing, and any CPU wait)
  double gpu_ms = NAN;       // per step: the pipeline's step clock (CUDA events, GL timer queries)
  double force_ms = NAN;     // per step: CUDA events
  double update_ms = NAN;    // per step: GL timer queries
  double hand_off_host_us = NAN;  // per step: host clock inside hand-off calls
  double hand_off_us = NAN;  // per hand-off: (wall - force - update) / hand-offs
  int hand_offs = 0;         // per step
  ClockSummary clock;        // over the steps timed on the step clock
};

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Runs `steps` steps; returns {wall ms per step after a drain, host ms per step in step()}.
std::pair<double, double> timed(Pipeline& p, int steps, Profiler* prof) {
  p.max_displacement();  // drains the queued work
  const auto t0 = std::chrono::steady_clock::now();
  double host = 0.0;
  for (int s = 1; s <= steps; ++s) {
    if (prof) prof->set_step(s);
    const auto h = std::chrono::steady_clock::now();
    p.step();
    host += ms_since(h);
  }
  p.max_displacement();
  return {ms_since(t0) / steps, host / steps};
}

double stage_ms(const Profiler& prof, const char* name) {
  for (const auto& g : prof.summary())
    if (g.name == name) return g.median_ms;
  return NAN;
}

void run_hybrid(const HybridOptions& o) {
  std::vector<std::string> names = {"hybrid", "hybrid-compute"};
  if (o.baselines) names.insert(names.end(), {"cuda-fused", "glsl-tf"});
  const Integrator integ = o.checked(names);
  const gl::ContextInfo& ctx = gl::context();
  const int dev = interop::cuda_device_of_gl();
  const bool gpusync = std::find(o.modes.begin(), o.modes.end(), "external-gpusync") != o.modes.end();
  CsvFile csv = open_csv(o.csv,
                               "n,pipeline,mode,wall_ms,host_ms,gpu_ms,force_ms,update_ms,hand_off_us,"
                               "hand_off_host_us_per_step,floor_us,sm_mhz_median,slowed_fraction",
                               kRunColumns);
  // The floor's ping-pong does no work: copies for o.warmup_ms raise the device's clock first, as
  // the cases' warm-ups do (their times are not used).
  const bool measure_floor = std::isnan(o.floor_us) && gpusync;
  if (measure_floor) cuda::time_copy(std::int64_t(256) << 20, 1, o.warmup_ms);
  const double floor_us = measure_floor ? interop::hand_off_floor_us(2000) : o.floor_us;
  const int passes = info(integ).force_passes;
  const SceneKind kind = o.scene_kind();
  std::cout << title("hybrid") << " CUDA device " << dev << ", GL " << ctx.renderer << "\n"
            << "cloth n x n, " << describe(kind) << "; " << o.integrator << ", " << warm_up_words(o)
            << counted(o.warmup, "warm-up step") << ".\n"
            << "gpu: the pipeline's step clock, median per step of steps back to back for about "
            << fixed(kGpuTimedMs, 0) << " ms (at least\n"
            << o.steps << "; CUDA events for cuda-fused, GL timer queries for glsl-tf and the hybrids, whose GL\n"
            << "update waits for the CUDA forces), as `deformlab run` times its steps. Then as many steps again:\n"
            << "wall: host clock over them, drained at the end, per step. host: host clock inside step().\n"
            << "force: CUDA events;\n"
            << "update: GL timer queries (median per step). hand-off: (wall - force - update) / hand-offs per step\n"
            << "(" << 2 * passes << "); ho-host: host clock inside the hand-off calls per step. floor: GL<->CUDA\n"
            << "semaphore ping-pong with no work, " << fixed(floor_us, 1) << " us per hand-off. bound: wall <= 1.05 x\n"
            << "(update + force + " << 2 * passes << " floors).\n\n";
  std::cout << std::setw(6) << "n" << std::setw(16) << "pipeline" << std::setw(18) << "mode" << std::setw(10) << "wall ms"
            << std::setw(10) << "host ms" << std::setw(10) << "gpu ms" << std::setw(10) << "force ms" << std::setw(11)
            << "update ms" << std::setw(13) << "hand-off us" << std::setw(10) << "x floor" << std::setw(13)
            << "ho-host us" << std::setw(7) << "bound" << "\n";
  auto print = [&](const Row& r) {
    const double bound = 1.05 * (r.update_ms + r.force_ms + 2 * passes * floor_us * 1e-3);
    std::cout << std::setw(6) << r.n << std::setw(16) << r.pipeline << std::setw(18) << r.mode << std::setw(10)
              << fixed(r.wall_ms, 3) << std::setw(10) << fixed(r.host_ms, 3) << std::setw(10) << fixed(r.gpu_ms, 3)
              << std::setw(10) << fixed(r.force_ms, 3) << std::setw(11) << fixed(r.update_ms, 3) << std::setw(13)
              << fixed(r.hand_off_us, 1) << std::setw(10) << fixed(r.hand_off_us / floor_us, 2) << std::setw(13)
              << fixed(r.hand_off_host_us, 1) << std::setw(7)
              << (std::isnan(r.force_ms) ? "" : r.wall_ms <= bound ? "ok" : "over") << std::endl;
    if (csv)
      csv << r.n << "," << r.pipeline << "," << r.mode << "," << r.wall_ms << "," << r.host_ms << "," << r.gpu_ms << ","
          << r.force_ms << "," << r.update_ms << "," << r.hand_off_us << "," << r.hand_off_host_us << "," << floor_us
          << "," << clock_columns(r.clock) << run_columns(o) << "\n";
  };

  const std::string bus = cuda::device_info(dev).pci_bus_id;
  ClockTally clocks;
  // Times `p` into `r`: the step clock, then as many steps on the host clock, with `prof` where
  // given (the stage split).
  auto measure = [&](Pipeline& p, const Model& m, Row& r, Profiler* prof) {
    const TimedWork g = time_steps(p, m, o.warmup_ms, o.warmup, o.steps, bus);
    r.gpu_ms = g.median_ms();
    r.clock = g.clock;
    clocks.add(std::to_string(r.n) + "^2 " + r.pipeline + (r.mode == "-" ? "" : " " + r.mode), g.clock);
    p.set_profiler(prof);
    std::tie(r.wall_ms, r.host_ms) = timed(p, int(g.ms.size()), prof);
    p.set_profiler(nullptr);
  };
  for (int n : o.sizes) {
    const BenchScene scene(n, kind);
    const Model& m = scene.model;
    const PipelineSetup setup = scene.setup(integ);
    if (o.baselines) {
      Row fused{n, "cuda-fused", "-"};
      measure(*cuda::make_pipeline(setup, {cuda::Variant::fused, {}, true}), m, fused, nullptr);
      print(fused);
      Row tf{n, "glsl-tf", "-"};
      Profiler prof;  // profiled as the hybrids are, so that the wall times compare
      measure(*pipelines().find("glsl-tf")->make(setup), m, tf, &prof);
      print(tf);
    }
    for (const auto& u : o.updates)
      for (const auto& mode_name : o.modes) {
        const auto mode = interop::parse_mode(mode_name);  // checked as the flag was read
        Row r{n, u == "compute" ? "hybrid-compute" : "hybrid", mode_name};
        if (const std::string why = interop::unavailable(*mode); !why.empty()) {
          std::cout << std::setw(6) << n << std::setw(16) << r.pipeline << std::setw(18) << mode_name
                    << "  unavailable: " << why << "\n";
          continue;
        }
        auto p = interop::make_hybrid_pipeline(
            setup, {u == "compute" ? interop::Update::compute : interop::Update::transform_feedback, *mode,
                    cuda::Variant::naive});
        Profiler prof;
        measure(*p, m, r, &prof);
        r.force_ms = stage_ms(prof, span::force);
        r.update_ms = stage_ms(prof, span::update);
        r.hand_off_host_us = stage_ms(prof, span::hand_off) * 1e3;
        r.hand_offs = 2 * passes;
        r.hand_off_us = (r.wall_ms - r.force_ms - r.update_ms) * 1e3 / r.hand_offs;
        print(r);
      }
  }
  print_clocks(std::cout, clocks, "steps timed on the step clock");
}

}  // namespace

void add_hybrid_bench(CLI::App& app) {
  auto o = std::make_shared<HybridOptions>();
  o->sizes = {64, 128, 256, 512, 1024, 2048};
  auto* c = app.add_subcommand("hybrid", "Hybrid pipelines per interop mode, split by stage, against glsl-tf and "
                                         "cuda-fused");
  add_bench_options(*c, *o);
  add_warmup_ms(*c, *o);
  c->add_option("--modes", o->modes, "Interop modes: " + interop::mode_names())
      ->check(CLI::Validator(
          [](std::string& v) {
            return interop::parse_mode(v) ? std::string() : "'" + v + "' is not one of " + interop::mode_names();
          },
          ""));
  c->add_option("--updates", o->updates, "Update passes: tf, compute")->check(CLI::IsMember({"tf", "compute"}));
  c->add_option("--steps", o->steps, "Timed steps at the least (more where they take under 200 ms)")
      ->check(deformlab::app::whole_in(1, std::numeric_limits<int>::max()));
  c->add_flag("!--no-baselines", o->baselines, "Skip the cuda-fused and glsl-tf rows");
  c->add_option("--floor-us", o->floor_us, "The hand-off floor, us (default: measured when external-gpusync is swept)")
      ->check(deformlab::app::real_in(0, 1e6));
  c->callback([o] { run_hybrid(*o); });
}

}  // namespace deformlab::bench
