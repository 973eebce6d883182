#include <cuda_runtime.h>

#include <deque>
#include <optional>
#include <stdexcept>

#include "cuda_kernels/check.cuh"
#include "cuda_kernels/force_stage.hpp"
#include "glsl_tf/gl_pipeline.hpp"
#include "glsl_tf/pipelines_internal.hpp"
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
  return h;
}

std::string hybrid_unsupported(Integrator i) {
  if (i == Integrator::backward_euler)
    return "backward-euler needs a linear solve per step; the hybrid pipelines have force and update passes only "
           "(use cpu, omp or reference)";
  return {};
}

namespace {

// The CUDA side of a hybrid step: hand-off to CUDA, the force pass, hand-off back to GL;
// and the timing of each stage with its own clock when a profiler is attached.
class HybridForces final : public gl::ExternalForces {
 public:
  HybridForces(const Params& p, SharedBuffers& sb, cuda::ForceStage& fs) : p_(p), sb_(sb), fs_(fs) {}

  ~HybridForces() override {
    for (auto& e : events_) {
      cudaEventDestroy(e.begin);
      cudaEventDestroy(e.end);
    }
  }

  GLuint node_buffer(std::size_t bytes, gl::NodeRole role) override {
    return sb_.add(bytes, role == gl::NodeRole::accelerations ? CudaAccess::write : CudaAccess::read);
  }

  void forces(GLuint x, GLuint v, GLuint acc, double t) override {
    const Vec3f target = p_.drag.active() ? p_.drag.target(t) : Vec3f{};
    {
      HostSpan h(prof_, span::hand_off);
      sb_.to_cuda({x, v, acc});
    }
    {
      NvtxRange range(span::force);
      Pending f{span::force, prof_ ? prof_->step() : 0, prof_ ? prof_->now_ms() : 0.0, -1};
      if (prof_) {
        f.events = take_events();
        cuda::check(cudaEventRecord(events_[f.events].begin, sb_.stream()), "recording the force pass start");
      }
      fs_.run(static_cast<const float4*>(sb_.cuda_ptr(x)), static_cast<const float4*>(sb_.cuda_ptr(v)),
              static_cast<float4*>(sb_.cuda_ptr(acc)), target, sb_.stream());
      if (prof_) {
        cuda::check(cudaEventRecord(events_[f.events].end, sb_.stream()), "recording the force pass end");
        pending_.push_back(f);
      }
    }
    {
      HostSpan h(prof_, span::hand_off);
      sb_.to_gl();
    }
    if (prof_) {
      update_range_.emplace(span::update);
      pending_.push_back({span::update, prof_->step(), prof_->now_ms(), -1});
      gl_timer().begin();
    }
  }

  void update_issued() override {
    if (!prof_) return;
    gl_timer().end();
    update_range_.reset();
    if (pending_.size() > 512) collect();
  }

  // Spans still pending go to the profiler they were taken for.
  void set_profiler(Profiler* p) {
    collect();
    prof_ = p;
  }

 private:
  struct Pending {
    const char* name;
    int step;
    double start_ms;
    int events;  // CUDA event pair (force), -1: a GL timer span (update)
  };
  struct EventPair {
    cudaEvent_t begin = nullptr, end = nullptr;
  };

  gl::Timer& gl_timer() {
    if (!timer_) timer_ = std::make_unique<gl::Timer>();
    return *timer_;
  }

  int take_events() {
    if (!free_events_.empty()) {
      const int k = free_events_.back();
      free_events_.pop_back();
      return k;
    }
    EventPair e;
    cuda::check(cudaEventCreate(&e.begin), "creating a timing event");
    cuda::check(cudaEventCreate(&e.end), "creating a timing event");
    events_.push_back(e);
    return int(events_.size()) - 1;
  }

  // Resolves every pending span (waits for its GPU work) and hands it to the profiler.
  void collect() {
    if (pending_.empty()) return;
    std::vector<double> gl_ms = timer_ ? timer_->take() : std::vector<double>{};
    std::size_t next_gl = 0;
    for (const Pending& s : pending_) {
      Span out{s.name, s.step, s.start_ms, 0.0, ""};
      if (s.events >= 0) {
        const EventPair& e = events_[s.events];
        cuda::check(cudaEventSynchronize(e.end), "waiting for a timed force pass");
        float ms = 0.f;
        cuda::check(cudaEventElapsedTime(&ms, e.begin, e.end), "reading a force pass timer");
        out.ms = ms;
        out.clock = "CUDA events";
        free_events_.push_back(s.events);
      } else {
        out.ms = next_gl < gl_ms.size() ? gl_ms[next_gl++] : 0.0;
        out.clock = timer_ ? timer_->method() : "GL timer queries";
      }
      if (prof_) prof_->add(std::move(out));
    }
    pending_.clear();
  }

  const Params& p_;
  SharedBuffers& sb_;
  cuda::ForceStage& fs_;
  Profiler* prof_ = nullptr;
  std::unique_ptr<gl::Timer> timer_;
  std::optional<NvtxRange> update_range_;
  std::vector<EventPair> events_;
  std::vector<int> free_events_;
  std::vector<Pending> pending_;
};

class HybridPipeline final : public Pipeline {
 public:
  HybridPipeline(const PipelineSetup& s, const HybridOptions& o) : p_(s.params) {
    if (const std::string why = hybrid_unsupported(s.integrator); !why.empty()) throw std::invalid_argument(why);
    if (o.force == cuda::Variant::fused)
      throw std::invalid_argument("the hybrid pipelines run a CUDA force pass: naive, tiled or scatter, not fused");
    validate(p_, s.model.node_count());
    sb_ = make_shared_buffers(o.mode);  // selects the CUDA device behind the GL context
    fs_ = cuda::make_force_stage(s.model, p_, o.force, o.tile);
    forces_ = std::make_unique<HybridForces>(p_, *sb_, *fs_);
    gl_ = o.update == Update::compute ? gl::make_compute_update(s, forces_.get()) : gl::make_tf_update(s, forces_.get());
  }

  ~HybridPipeline() override {
    glFinish();
    cudaStreamSynchronize(sb_->stream());
  }

  void set_state(const State& s) override { gl_->set_state(s); }
  State state() override { return gl_->state(); }
  void step() override { gl_->step(); }
  double max_displacement() override { return gl_->max_displacement(); }
  std::string timing_method() const override {
    return "host clock per step; stages: CUDA events (force), " + gl::Timer().method() +
           " (update), host clock (hand-off)";
  }
  void set_profiler(Profiler* p) override { forces_->set_profiler(p); }

 private:
  Params p_;
  // Destroyed in reverse: the GL pipeline first, the shared buffers (and their stream) last.
  std::unique_ptr<SharedBuffers> sb_;
  std::unique_ptr<cuda::ForceStage> fs_;
  std::unique_ptr<HybridForces> forces_;
  std::unique_ptr<gl::GlPipeline> gl_;
};

}  // namespace

std::unique_ptr<Pipeline> make_hybrid_pipeline(const PipelineSetup& s, const HybridOptions& o) {
  gl::context();  // a clear error first when there is no GL
  return std::make_unique<HybridPipeline>(s, o);
}

}  // namespace deformlab::interop
