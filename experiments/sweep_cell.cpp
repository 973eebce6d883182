// One cell of a sweep (sweep.hpp's run_cell): sized, bounded in time, timed, profiled.
#include <algorithm>
#include <chrono>
#include <numeric>
#include <optional>
#include <sstream>

#include "core/clock_watch.hpp"
#include "core/scene.hpp"
#include "core/state.hpp"
#include "core/node_order.hpp"
#include "output.hpp"
#include "pipelines.hpp"
#include "sweep.hpp"
#include "sweep_models.hpp"
#if DEFORMLAB_HAVE_GL
#include "gl/context.hpp"
#include "gl/render.hpp"
#endif

namespace deformlab {

using nlohmann::json;

namespace {

using clock = std::chrono::steady_clock;

json not_applicable(json r, const std::string& why) {
  r["status"] = "n/a";
  r["reason"] = why;
  return r;
}

// Sizes the scene's grid to the cell and records its nodes and springs in `r`; returns why it
// does not fit here, else "".
std::string size_grid(Scene& scene, const Cell& c, const PipelineEntry& e, Integrator i, json& r) {
  size_model(scene.model, c.size);
  const ModelSize size = model_size(scene.model);
  r["nodes"] = size.nodes;
  r["springs"] = size.springs;
  const std::string why = host_memory_shortfall(size, e, i, c.options);
  return why.empty() ? why : "does not fit: " + why;
}

// "volume" for a mesh with nodes inside its surface (Model::triangle, a volume's boundary),
// else "surface" (every node of a surface is on a triangle).
std::string mesh_kind(const Model& m) {
  std::vector<bool> on_surface(m.node_count(), false);
  for (auto v : m.triangle) on_surface[v] = true;
  return std::find(on_surface.begin(), on_surface.end(), false) != on_surface.end() ? "volume" : "surface";
}

// A mesh model's facts in `r` once it is built; returns why the cell does not fit here, else
// "" (the model counted again beside what it already holds, as `deformlab run` counts it).
std::string record_mesh(const Model& m, const Scene& scene, const Cell& c, const PipelineEntry& e, Integrator i,
                        json& r) {
  r["nodes"] = m.node_count();
  r["springs"] = m.spring_count();
  r["mesh"] = mesh_kind(m);
  r["order"] = to_string(scene.model.mesh.order);
  r["bandwidth"] = bandwidth(m);
  const std::string why = host_memory_shortfall(m.size(), e, i, c.options);
  return why.empty() ? why : "does not fit: " + why;
}

// A cell's steps. With "frame" timing every step is followed by a draw of the state at
// 1024 x 1024 (the paper's frame); pipelines outside GL hand their state over through a
// read-back. Frame timing without OpenGL throws std::invalid_argument (the cell is n/a).
class CellSteps {
 public:
  CellSteps(Pipeline& pipe, const Model& m, const std::string& time) : pipe_(pipe) {
#if DEFORMLAB_HAVE_GL
    if (time != "frame") return;
    if (auto why = gl::unavailable_reason(); !why.empty())
      throw std::invalid_argument("frame timing needs OpenGL: " + why);
    renderer_ = std::make_unique<gl::Renderer>(m);
#else
    (void)m;
    if (time == "frame") throw std::invalid_argument("frame timing needs a build with OpenGL");
#endif
  }
  void step() {
    pipe_.step();
#if DEFORMLAB_HAVE_GL
    if (renderer_) renderer_->draw(pipe_);
#endif
  }
  // Waits for the device's last step (and draw).
  void finish() {
    pipe_.max_displacement();
#if DEFORMLAB_HAVE_GL
    if (renderer_) renderer_->take_draw_ms();
#endif
  }

 private:
  Pipeline& pipe_;
#if DEFORMLAB_HAVE_GL
  std::unique_ptr<gl::Renderer> renderer_;
#endif
};

// The kBoundingSteps: returns why the cell is cut, else "".
std::string cut_after_second_step(CellSteps& steps, const Sweep& s, int per_batch) {
  steps.step();
  steps.finish();
  const auto t0 = clock::now();
  steps.step();
  steps.finish();
  const double step_s = std::chrono::duration<double>(clock::now() - t0).count();
  const double expect_s = step_s * (s.warmup + double(per_batch) * s.repetitions);
  if (expect_s <= s.cell_limit_s) return {};
  std::ostringstream os;
  os << "cut: the second step took " << step_s << " s, the cell would need about " << expect_s
     << " s, over its limit of " << s.cell_limit_s << " s";
  return os.str();
}

// The rest of the warm-up, then ms per step of each of s.repetitions timed batches of
// `per_batch` steps: steps by `timer`, one of the pipeline's step timers, all back to back (the
// batches cut from one timed run); frames (null timer: a step and its draw each) on the host
// clock, from a drained device to a drained device.
std::vector<double> timed_batches(Pipeline& pipe, StepTimer* timer, CellSteps& steps, const Sweep& s, int per_batch) {
  for (int w = kBoundingSteps; w < s.warmup; ++w) steps.step();
  steps.finish();
  std::vector<double> ms_per_step;
  if (timer) {
    const std::vector<double> ms = timed_steps(pipe, *timer, s.repetitions * per_batch);
    for (auto b = ms.begin(); b != ms.end(); b += per_batch)
      ms_per_step.push_back(std::accumulate(b, b + per_batch, 0.0) / double(per_batch));
    return ms_per_step;
  }
  for (int rep = 0; rep < s.repetitions; ++rep) {
    const auto b0 = clock::now();
    for (int st = 0; st < per_batch; ++st) steps.step();
    steps.finish();
    ms_per_step.push_back(std::chrono::duration<double, std::milli>(clock::now() - b0).count() / per_batch);
  }
  return ms_per_step;
}

// One more batch with a profiler attached, for each stage's time per step; it is kept out
// of the timed batches (a profiled CUDA pipeline runs pass by pass, not as a graph).
json stage_times(Pipeline& pipe, CellSteps& steps, const Sweep& s) {
  Profiler prof;
  pipe.set_profiler(&prof);
  for (int st = 1; st <= s.steps; ++st) {
    prof.set_step(st);
    steps.step();
  }
  steps.finish();
  pipe.set_profiler(nullptr);
  json stages = json::array();
  for (const auto& g : prof.summary())
    stages.push_back(
        {{"name", g.name}, {"median_ms", g.median_ms}, {"clock", g.clock}, {"per_step", double(g.spans) / g.steps}});
  return stages;
}

std::string method_of(const Sweep& s) {
  const std::string after = " after " + std::to_string(s.warmup) + " warm-up steps (pipelines with a GPU pass: after " +
                            std::to_string(int(kGpuWarmUpMs)) + " ms of untimed steps from rest first)";
  const std::string reps = std::to_string(s.repetitions), steps = std::to_string(s.steps);
  if (s.time == "frame")
    return "host steady_clock around each batch of frames (a step and a 1024 x 1024 draw each), from a drained "
           "device to a drained device, ms per frame, median of " + reps + " batches of " + steps + after;
  return "each step on its pipeline's step clock, ms per step (the batch's mean), median of " + reps +
         " batches of at least " + steps + " steps, all timed back to back (pipelines with a GPU pass: about " +
         std::to_string(int(kGpuTimedMs)) + " ms of steps in all; a cell's steps_per_batch)" + after;
}

// Times the cell on `pipe` from the rest state into `r`, or says why it was cut. On a GPU
// pipeline untimed steps from rest for kGpuWarmUpMs come first, as in `deformlab run`, so that
// the steps that bound the cell and the timed ones run at the device's working clock, and the
// GPU's clock is watched over the timed batches.
json measure(json r, Pipeline& pipe, const Model& m, const Sweep& s, const PipelineEntry& e) {
  const bool gpu = on_gpu(e);
  CellSteps steps(pipe, m, s.time);
  int per_batch = s.steps;
  if (gpu) {
    pipe.set_state(rest_state(m));
    const WarmUp w = warm_up([&] { steps.step(); }, [&] { steps.finish(); }, kGpuWarmUpMs);
    r["warm_up"] = {{"steps", w.steps}, {"ms", w.ms}, {"clock", "host steady_clock"}};
    if (s.time != "frame")
      per_batch = steps_spanning(kGpuTimedMs / s.repetitions, w.ms / std::max(w.steps, 1), s.steps);
  }
  pipe.set_state(rest_state(m));
  if (auto why = cut_after_second_step(steps, s, per_batch); !why.empty()) return not_applicable(r, why);
  const std::unique_ptr<StepTimer> timer = s.time == "frame" ? nullptr : pipe.step_timer();
  std::optional<ClockWatch> watch;
  if (gpu) watch.emplace(gpu_bus_id(e));
  const std::vector<double> ms = timed_batches(pipe, timer.get(), steps, s, per_batch);
  const ClockSummary clock = watch ? watch->stop() : ClockSummary{};
  const double d = pipe.max_displacement();
  // A report's stage tables show where a GPU pipeline's step goes; the CPU's passes are plain loops.
  if (json stages = gpu ? stage_times(pipe, steps, s) : json::array(); !stages.empty()) r["stages"] = stages;
  r["status"] = "ok";
  r["median_ms"] = median(ms);
  r["min_ms"] = *std::min_element(ms.begin(), ms.end());
  r["samples_ms"] = ms;
  r["stable"] = d == d;
  r["pipeline_timing"] = pipe.timing_method();
  if (const auto chosen = pipe.chosen_options(); !chosen.empty()) r["chosen_options"] = chosen;
  r["time"] = s.time;
  r["method"] = method_of(s);
  r["steps_per_batch"] = per_batch;
  if (timer) r["step_clock"] = timer->clock();
  if (gpu) r["sm_clock"] = to_json(clock);
  return r;
}

}  // namespace

json run_cell(const Experiment& x, const Sweep& s, const Cell& c, ModelCache& cache) {
  json r = {{"id", c.id()}, {"size", c.size}, {"pipeline", c.pipeline}, {"integrator", c.integrator},
            {"options", c.options}, {"build", build_info()["git"]}};
  if (!c.model.empty()) r["model"] = c.model;
  if (!c.order.empty()) r["order"] = c.order;
  const PipelineEntry& e = *pipelines().find(c.pipeline);
  const Integrator integ = *parse_integrator(c.integrator);
  if (auto why = e.unavailable(); !why.empty()) return not_applicable(r, why);
  if (auto why = e.unsupported(integ); !why.empty()) return not_applicable(r, why);
  Scene scene = c.model.empty() ? x.scene : model_cell_scene(x, s, c);
  if (c.model.empty())
    if (auto why = size_grid(scene, c, e, integ, r); !why.empty()) return not_applicable(r, why);
  const Model* m = nullptr;
  Params p;
  try {
    const int built = cache.models_built();
    const auto t0 = clock::now();
    m = &cache.model(scene, c);
    r["model_build_s"] = cache.models_built() == built ? 0.0 : std::chrono::duration<double>(clock::now() - t0).count();
    p = resolve_params(scene, *m);
  } catch (const DoesNotFit& ex) {
    return not_applicable(r, std::string("does not fit: ") + ex.what());
  } catch (const std::invalid_argument& ex) {  // the scene is bad input on this model: the sweep stops
    const std::string key = c.model.empty() ? size_key(s, c.size) : model_key(s, c.model), what = ex.what();
    throw std::invalid_argument(what.starts_with(key) ? what : key + ": " + what);
  } catch (const std::bad_alloc&) {
    return not_applicable(r, "does not fit: out of host memory");
  } catch (const std::exception& ex) {
    return not_applicable(r, std::string("failed: ") + ex.what());
  }
  if (!c.model.empty())
    if (auto why = record_mesh(*m, scene, c, e, integ, r); !why.empty()) return not_applicable(r, why);
  try {
    auto pipe = e.make({*m, p, integ, c.options});
    return measure(r, *pipe, *m, s, e);
  } catch (const std::invalid_argument& ex) {
    return not_applicable(r, ex.what());
  } catch (const std::bad_alloc&) {
    return not_applicable(r, "does not fit: out of host memory");
  } catch (const std::exception& ex) {  // a pipeline failed (a driver error, a divergence)
    return not_applicable(r, std::string("failed: ") + ex.what());
  }
}

}  // namespace deformlab
