#include <cuda_runtime.h>

#include <stdexcept>

#include "cuda_kernels/event_spans.hpp"
#include "core/stage.hpp"
#include "cuda_kernels/force_pass.hpp"
#include "gl/gl_pipeline.hpp"
#include "gl/pipelines_internal.hpp"
#include "hybrid.hpp"

namespace deformlab::interop {

HybridOptions hybrid_options(const PipelineOptions& o, Update u) {
  HybridOptions h;
  h.update = u;
  if (auto it = o.find("interop"); it != o.end()) {
    const auto m = parse_mode(it->second);
    if (!m) throw std::invalid_argument("interop mode '" + it->second + "' is not one of " + mode_names());
    h.mode = *m;
  }
  if (auto it = o.find("force"); it != o.end()) {
    const std::string& f = it->second;
    if (f == "naive") h.force = cuda::Variant::naive;
    else if (f == "tiled") h.force = cuda::Variant::tiled;
    else if (f == "scatter") h.force = cuda::Variant::scatter;
    else throw std::invalid_argument("force '" + f + "' is not a CUDA force pass of the hybrid pipelines (naive, tiled, scatter)");
  }
  h.tile = cuda::tile_option(o);
  h.math = math_option(o);
  return h;
}

Mode default_mode() { return unavailable(Mode::external_gpusync).empty() ? Mode::external_gpusync : Mode::map; }

std::string hybrid_unsupported(Integrator i) {
  if (i == Integrator::backward_euler)
    return "backward-euler needs a linear solve per step; the hybrid pipelines have force and update passes only "
           "(use cpu, omp or reference)";
  return {};
}

std::string hybrid_idle_option(const PipelineOptions& o, Topology t) {
  if (!o.count("tile")) return {};
  const cuda::Variant force = hybrid_options(o, Update::compute).force;
  if (force == cuda::Variant::scatter)
    return "option tile: the scatter force pass (force=scatter) runs one thread per spring in blocks of its own";
  if (force != cuda::Variant::tiled && t == Topology::general)
    return "option tile: on a mesh only the tiled force pass (force=tiled) takes a tile, its nodes per tile";
  return {};
}

namespace {

// The CUDA force stage and the GL update stage run by the schedule: each force pass hands the
// state to CUDA, runs the force kernels and hands the accelerations back to GL; each update
// pass is a GL pass. With a profiler attached, each stage is timed with its own clock.
class HybridPipeline final : public Pipeline, private ForceStage, private UpdateStage {
 public:
  HybridPipeline(const PipelineSetup& s, const HybridOptions& o) : p_(s.params), sched_(make_schedule(s.integrator)) {
    if (const std::string why = hybrid_unsupported(s.integrator); !why.empty()) throw std::invalid_argument(why);
    const Mode mode = o.mode.value_or(default_mode());
    if (!o.mode) chosen_["interop"] = to_string(mode);
    sb_ = make_shared_buffers(mode);  // selects the CUDA device behind the GL context
    fp_ = cuda::make_force_pass(s.model, p_, o.force, o.tile, o.math);
    auto shared = [this](std::size_t bytes, gl::NodeRole role) {
      return sb_->add(bytes, role == gl::NodeRole::accelerations ? CudaAccess::write : CudaAccess::read);
    };
    const gl::CudaMemory own = cuda_memory();  // the update's own buffers
    gl_ = o.update == Update::compute ? gl::make_compute_update(s, shared, own) : gl::make_tf_update(s, shared, own);
  }

  ~HybridPipeline() override {
    glFinish();
    cudaStreamSynchronize(sb_->stream());
  }

  void set_state(const State& s) override { gl_->set_state(s); }
  State state() override { return gl_->state(); }
  void set_drag(const DragHandle& d) override {
    gl_->set_drag(d);  // checks it
    fp_->set_drag(d);
    p_.drag = d;
  }
  void step() override {
    run_passes(sched_, gl_->time(), p_.dt, *this, *this);
    gl_->finish_step();
    if (prof_ && force_spans_.pending() > 512) collect();
  }
  double max_displacement() override { return gl_->max_displacement(); }
  bool can_step_back() const override { return gl_->can_step_back(); }
  void step_back() override { gl_->step_back(); }
  void queue_displacement() override { gl_->queue_displacement(); }
  double take_displacement() override { return gl_->take_displacement(); }
  unsigned gl_position_buffer() override { return gl_->gl_position_buffer(); }
  std::string timing_method() const override {
    return "CUDA events (force), " + gl::Timer().method() + " (update), host clock (hand-off)";
  }
  // GL's clock: its update pass waits for the CUDA forces, so a step's two GL ends span both.
  std::unique_ptr<StepTimer> step_timer() override { return gl_->step_timer(); }
  std::map<std::string, std::string> chosen_options() const override { return chosen_; }
  // Spans still pending go to the profiler they were taken for.
  void set_profiler(Profiler* p) override {
    collect();
    prof_ = p;
  }

 private:
  void forces(int src, int acc, double t) override {
    (void)acc;  // one acceleration buffer: each update pass keeps what later passes need
    const auto [x, v] = gl_->slot_buffers(src);
    const GLuint a = gl_->force_buffer();
    const Vec3f target = p_.drag.active() ? p_.drag.target(t) : Vec3f{};
    Profiler* p = sampling(prof_);
    {
      HostSpan h(p, span::hand_off);
      sb_->to_cuda({x, v, a});
    }
    if (p) force_spans_.begin(*p, span::force, sb_->stream());
    fp_->run(static_cast<const float4*>(sb_->cuda_ptr(x)), static_cast<const float4*>(sb_->cuda_ptr(v)),
             static_cast<float4*>(sb_->cuda_ptr(a)), target, sb_->stream());
    if (p) force_spans_.end(sb_->stream());
    HostSpan h(p, span::hand_off);
    sb_->to_gl();
  }

  void update(const Pass& pass) override {
    Profiler* p = sampling(prof_);
    if (p) update_spans_.begin(*p, span::update);
    gl_->update(pass);
    if (p) update_spans_.end();
  }

  void collect() {
    force_spans_.collect(prof_);
    update_spans_.collect(prof_);
  }

  Params p_;
  Schedule sched_;
  std::map<std::string, std::string> chosen_;
  Profiler* prof_ = nullptr;
  cuda::EventSpans force_spans_;
  gl::TimerSpans update_spans_;
  // Destroyed in reverse: the GL pipeline first, the shared buffers (and their stream) last.
  std::unique_ptr<SharedBuffers> sb_;
  std::unique_ptr<cuda::ForcePass> fp_;
  std::unique_ptr<gl::GlPipeline> gl_;
};

}  // namespace

std::unique_ptr<Pipeline> make_hybrid_pipeline(const PipelineSetup& s, const HybridOptions& o) {
  gl::context();  // a clear error first when there is no GL
  return std::make_unique<HybridPipeline>(s, o);
}

}  // namespace deformlab::interop
