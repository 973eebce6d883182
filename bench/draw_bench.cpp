// `deformlab-bench draw`: what a frame of the viewer costs beside its steps: the state handed to
// the renderer and drawn, per pipeline and route (a GL pipeline's own buffer, a CUDA pipeline's
// positions copied on the device through interop in map mode, a read-back uploaded), on a
// drained device, with the draw alone on GL's clock.
#include <chrono>
#include <iomanip>
#include <iostream>
#include <optional>

#include "bench.hpp"
#include "experiments/pipelines.hpp"
#include "gl/context.hpp"
#include "gl/render.hpp"
#include "interop/gl_positions.hpp"

namespace deformlab::bench {
namespace {

enum class Route { own_buffer, interop, read_back };
const char* to_string(Route r) {
  return r == Route::own_buffer ? "own GL buffer" : r == Route::interop ? "CUDA-GL map copy" : "read-back + upload";
}

void run_draw(const StepOptions& o) {
  const gl::ContextInfo& ctx = gl::context();  // first: on a software renderer the buffers count as host memory
  const Integrator integ = o.checked({"glsl-compute", "hybrid-compute", "cuda-fused"});
  CsvFile csv =
      open_csv(o.csv, "n,pipeline,route,frame_ms,draw_ms,sm_mhz_median,slowed_fraction", kRunColumns);
  std::cout << title("draw") << " GL " << ctx.renderer << "; cloth n x n, " << describe(o.scene_kind())
            << ", drawn 1280 x 800 as a surface.\n"
            << "frame: host clock from a drained device (the pipeline's last step done) to glFinish after the draw,\n"
            << "the state's hand-over included; draw: the draw alone on " << gl::Timer().method() << ".\n"
            << "Medians of " << o.reps << " frames after " << warm_up_words(o)
            << counted(o.warmup, "warm-up frame") << ", ms.\n\n"
            << std::setw(6) << "n" << std::setw(16) << "pipeline" << std::setw(22) << "route" << std::setw(11)
            << "frame ms" << std::setw(10) << "draw ms" << "\n";
  ClockTally clocks;
  const std::pair<const char*, Route> cases[] = {{"glsl-compute", Route::own_buffer},
                                                 {"hybrid-compute", Route::own_buffer},
                                                 {"cuda-fused", Route::interop},
                                                 {"cuda-fused", Route::read_back}};
  for (int n : o.sizes) {
    const BenchScene scene(n, o.scene_kind());
    gl::Renderer r(scene.model, {.width = 1280, .height = 800});
    for (const auto& [name, route] : cases) {
      const PipelineEntry& e = *pipelines().find(name);
      if (const std::string why = e.unavailable(); !why.empty()) {
        std::cout << std::setw(6) << n << std::setw(16) << name << std::setw(22) << to_string(route)
                  << "  unavailable: " << why << "\n";
        continue;
      }
      auto p = e.make(scene.setup(integ));
      warm_up_from_rest(*p, scene.model, o.warmup_ms);
      p->step();
      std::unique_ptr<interop::GlPositions> bridge;
      if (route == Route::interop) bridge = std::make_unique<interop::GlPositions>(scene.model.node_count());
      std::vector<double> frame_ms;
      std::optional<ClockWatch> watch;
      for (int k = 0; k < o.warmup + o.reps; ++k) {
        if (k == o.warmup) watch.emplace(gpu_bus_id(e));
        p->max_displacement();  // drains the pipeline's work
        glFinish();
        const auto t0 = std::chrono::steady_clock::now();
        if (route == Route::own_buffer) r.draw_positions(p->gl_position_buffer());
        else if (route == Route::interop && bridge->update(*p)) r.draw_positions(bridge->buffer());
        else r.draw(p->state());
        glFinish();
        if (k >= o.warmup)
          frame_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      }
      const std::vector<double> draws = r.take_draw_ms();
      const double draw = stats(std::vector<double>(draws.end() - o.reps, draws.end())).median;
      const double frame = stats(frame_ms).median;
      const ClockSummary clock = watch->stop();
      clocks.add(std::to_string(n) + "^2 " + name + " " + to_string(route), clock);
      std::cout << std::setw(6) << n << std::setw(16) << name << std::setw(22) << to_string(route) << std::setw(11)
                << fixed(frame, 3) << std::setw(10) << fixed(draw, 3) << std::endl;
      if (csv)
        csv << n << "," << name << "," << to_string(route) << "," << frame << "," << draw << "," << clock_columns(clock)
            << run_columns(o) << "\n";
    }
  }
  print_clocks(std::cout, clocks, "timed frames");
}

}  // namespace

void add_draw_bench(CLI::App& app) {
  add_step_bench(app, "draw", "The viewer's frame: the state handed to the renderer and drawn, per route",
                 {256, 1024, 2048}, 5, 30, "Timed frames", run_draw, Device::gpu);
}

}  // namespace deformlab::bench
