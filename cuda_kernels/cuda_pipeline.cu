// The CUDA pipeline: device buffers, the schedule's passes as kernel launches, step graphs
// and the device reduction of the displacement; and its force pass on its own, the CUDA
// stage of the hybrid pipelines. One translation unit: kernels.cuh and temporal.cuh define the
// kernels, force_kernels.cuh the model on the device and the force pass. It is compiled once
// per math mode (core/pipeline.hpp, Math) into namespace DL_CUDA_MATH.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>
#include <stdexcept>

#include "check.cuh"
#include "event_spans.hpp"
#include "cuda_pipeline.hpp"
#include "force_kernels.cuh"
#include "force_pass.hpp"
#include "core/stage.hpp"
#include "core/step_params.hpp"
#include "kernels.cuh"
#include "temporal.cuh"
#include "temporal_plan.cuh"
#include "tma_tile.cuh"
#include "math_builds.hpp"

namespace deformlab::cuda::DL_CUDA_MATH {
namespace {

class Impl final : public CudaPipeline, private ForceKernels, private ForceStage, private UpdateStage {
 public:
  Impl(const PipelineSetup& su, const Options& o)
      : ForceKernels(checked(su, o), su.params, o), p_(su.params), sched_(make_schedule(su.integrator)) {
    const Model& m = model_;
    n_ = m.node_count();
    fused_ = o_.variant == Variant::fused && sched_.single_pass();
    if (o_.variant == Variant::temporal) {
      temporal_ = true;
      plan_ = plan_temporal(m, o_);
    }
    if (dev::kPrefetchAhead && fused_ && m.grid()) plan_prefetch();

    check(cudaStreamCreateWithFlags(&stream_, cudaStreamNonBlocking), "creating the pipeline's stream");

    for (int c = 0; c < kStateSets; ++c) {
      x_[c].allocate(n_, "allocating positions");
      v_[c].allocate(n_, "allocating velocities");
    }
    for (int k = 0; k < sched_.stage_states; ++k) {
      sx_[k].allocate(n_, "allocating stage positions");
      sv_[k].allocate(n_, "allocating stage velocities");
    }
    if (!fused_ && !temporal_)
      for (int k = 0; k < sched_.accel_slots; ++k) acc_[k].allocate(n_, "allocating accelerations");
    if (tma_misfit(o_, m, su.integrator).empty()) {
      tma_ = device_info().cc_major >= 9 && o_.tma.value_or(o_.math == Math::exact);
      if (!o_.tma && o_.math == Math::exact) chosen_["tma"] = tma_ ? "on" : "off";
    }
    for (int c = 0; tma_ && c < kStateSets; ++c) {
      tma_maps_[c][0] = cloth_tensor_map(x_[c].get(), m.nx, m.ny);
      if (damped_) tma_maps_[c][1] = cloth_tensor_map(v_[c].get(), m.nx, m.ny);
    }
    stop_.allocate(kStateSets + 1, "allocating the stop rule's reduction");
    check(cudaMemsetAsync(stop_.get(), 0, (kStateSets + 1) * sizeof(unsigned), stream_),
          "clearing the stop rule's reduction");
    void* h = nullptr;
    check(cudaHostAlloc(&h, sizeof(unsigned long long), cudaHostAllocMapped), "allocating the displacement read-back");
    disp_host_.reset(static_cast<unsigned long long*>(h));
    *disp_host_ = 0;
    check(cudaHostGetDevicePointer(reinterpret_cast<void**>(&disp_device_), h, 0), "mapping the displacement read-back");

    set_state(rest_state(m));
  }

  ~Impl() override {
    drop_graphs();
    if (copied_) cudaEventDestroy(copied_);
    if (stream_) cudaStreamDestroy(stream_);
  }

  void set_state(const State& s) override {
    if (s.x.size() != std::size_t(n_) || s.v.size() != std::size_t(n_))
      throw std::invalid_argument("state size does not match the model");
    cur_ = 0;
    pending_ = 0;
    queued_ = Read::none;
    check(cudaMemsetAsync(stop_.get(), 0, kStateSets * sizeof(unsigned), stream_), "clearing the stop rule's reduction");
    upload_positions(x_[0], s.x);
    upload_vectors(v_[0], s.v);
    half_step_ = s.half_step;
    t_ = s.t;
    stepped_ = false;
    back_ = Back::none;
  }

  State state() override {
    flush();
    State s;
    s.t = t_;
    s.x = download(x_[cur_]);
    s.v = download(v_[cur_]);
    s.half_step = half_step_;
    return s;
  }

  void copy_positions(float4* dst, cudaStream_t stream) override {
    flush();
    if (!copied_) check(cudaEventCreateWithFlags(&copied_, cudaEventDisableTiming), "creating the copy event");
    check(cudaEventRecord(copied_, stream_), "marking the step before a copy");
    check(cudaStreamWaitEvent(stream, copied_, 0), "ordering a copy after the step");
    check(cudaMemcpyAsync(dst, x_[cur_].get(), std::size_t(n_) * sizeof(float4), cudaMemcpyDeviceToDevice, stream),
          "copying the positions");
  }

  void set_drag(const DragHandle& d) override {
    validate(d, n_);
    flush();  // the steps held back ran with the old handle
    p_.drag = d;
    set_drag_params<float>(sp_, d);
    drop_graphs();  // their launches carry the old handle
  }

  void step() override {
    if (temporal_) return hold_step();
    // Steps the profiler samples run pass by pass (a graph replay has no spans).
    const bool replay = !sampling(prof_) && o_.graphs && time_invariant() &&
                        !(sched_.rule == UpdateRule::verlet && !half_step_);
    if (replay) {
      if (!graph_[cur_]) capture(cur_);
      check(cudaGraphLaunch(graph_[cur_], stream_), "launching the step graph");
    } else {
      enqueue_step();
    }
    end_launch(1, t_);
    t_ += p_.dt;
    stepped_ = true;
  }

  // After a launch of `steps` steps from time t_before: the state it wrote becomes current, and
  // the one before it what step_back returns to.
  void end_launch(int steps, double t_before) {
    back_t_ = t_before;
    back_half_step_ = half_step_;
    back_ = Back::possible;
    if (sched_.rule == UpdateRule::verlet) half_step_ = true;
    cur_ = after(cur_);
    launched_ += steps;
    ++result_launches_;
  }

  // The kernels read state cur_ and write the other set, so the state before the last launch
  // stays until the next.
  bool can_step_back() const override { return true; }
  int steps_per_launch() const override { return temporal_ ? plan_.k : 1; }
  void step_back() override {
    if (back_ != Back::possible) throw std::logic_error("cuda pipeline: no launch to take back");
    cur_ = before(cur_);
    t_ = back_t_;
    half_step_ = back_half_step_;
    back_ = Back::taken;
    // The launch taken back added into the word the next launch from this state adds into.
    check(cudaMemsetAsync(stop_.get() + cur_, 0, sizeof(unsigned), stream_), "clearing the stop rule's reduction");
  }

  // The last step's launch left its largest displacement in a word (dev::StopCheck). The launch
  // after it passes the word to the host; without one, the read copies it.
  void queue_displacement() override {
    flush();
    if (back_ == Back::taken) throw std::logic_error("the displacement before a step taken back is not kept");
    if (queued_ != Read::none) throw std::logic_error("a displacement read is queued and not taken");
    queued_ = stepped_ ? Read::launch : Read::zero;
    read_after_ = result_launches_;
  }
  double take_displacement() override {
    if (queued_ == Read::none) throw std::logic_error("no displacement read queued");
    if (std::exchange(queued_, Read::none) == Read::zero) return 0.0;
    unsigned bits = 0;
    if (result_launches_ > read_after_) {
      bits = passed_on(read_after_ + 1);
    } else {
      unsigned* h = reinterpret_cast<unsigned*>(staging());
      // No launch since: the last one read the set before cur_ and added into its word.
      check(cudaMemcpyAsync(h, stop_.get() + before(cur_), sizeof(unsigned), cudaMemcpyDeviceToHost, stream_),
            "reading the largest displacement");
      check(cudaStreamSynchronize(stream_), "reading the largest displacement");
      bits = *h;
    }
    float d = 0.f;
    std::memcpy(&d, &bits, sizeof d);
    return std::isinf(d) ? std::numeric_limits<double>::quiet_NaN() : double(d);
  }
  double max_displacement() override {
    queue_displacement();
    return take_displacement();
  }
  // Waits for result launch `launch` to pass the maximum of the one before to the host.
  unsigned passed_on(unsigned long long launch) {
    const unsigned want = unsigned(launch);  // the device counts in 32 bits
    auto read = [&] { return *static_cast<volatile unsigned long long*>(disp_host_.get()); };
    for (;;) {
      const unsigned long long word = read();
      if (unsigned(word >> 32) == want) return unsigned(word);
      if (unsigned(word >> 32) > want) throw std::logic_error("a displacement read was taken two launches late");
      const cudaError_t e = cudaStreamQuery(stream_);
      if (e != cudaErrorNotReady) check(e, "reading the largest displacement");
      if (e == cudaSuccess && unsigned(read() >> 32) != want)
        throw std::runtime_error("the launch after a step did not pass its largest displacement on");
    }
  }

  std::map<std::string, std::string> chosen_options() const override { return chosen_; }

  void set_profiler(Profiler* p) override {
    spans_.collect(prof_);
    prof_ = p;
  }

  std::unique_ptr<StepTimer> step_timer() override {
    return std::make_unique<EventStepTimer>(stream_, &launched_, [this] { flush(); });
  }

 private:
  // State transfers go through the pipeline's stream (ordered after the steps already queued)
  // a chunk at a time through one pinned staging buffer: no second host copy of a state.
  static constexpr int kChunk = kTransferChunkNodes;
  float4* staging() {
    if (!staging_) {
      void* p = nullptr;
      check(cudaMallocHost(&p, kChunk * sizeof(float4)), "allocating the transfer buffer");
      staging_.reset(static_cast<float4*>(p));
    }
    return staging_.get();
  }
  // b[i] = make(i) for every node.
  template <class Make>
  void upload(Buffer<float4>& b, Make make, const char* what) {
    float4* h = staging();
    for (int base = 0; base < n_; base += kChunk) {
      const int count = std::min(kChunk, n_ - base);
      check(cudaStreamSynchronize(stream_), what);  // the previous chunk has left the staging buffer
      for (int i = 0; i < count; ++i) h[i] = make(base + i);
      check(cudaMemcpyAsync(b.get() + base, h, count * sizeof(float4), cudaMemcpyHostToDevice, stream_), what);
    }
    check(cudaStreamSynchronize(stream_), what);
  }
  void upload_positions(Buffer<float4>& b, const std::vector<Vec3f>& x) {
    upload(b, [&](int i) { return make_float4(x[i].x, x[i].y, x[i].z, model_.inv_mass[i]); }, "uploading positions");
  }
  void upload_vectors(Buffer<float4>& b, const std::vector<Vec3f>& v) {
    upload(b, [&](int i) { return make_float4(v[i].x, v[i].y, v[i].z, 0.f); }, "uploading velocities");
  }
  std::vector<Vec3f> download(const Buffer<float4>& b) {
    float4* h = staging();
    std::vector<Vec3f> out(n_);
    for (int base = 0; base < n_; base += kChunk) {
      const int count = std::min(kChunk, n_ - base);
      check(cudaMemcpyAsync(h, b.get() + base, count * sizeof(float4), cudaMemcpyDeviceToHost, stream_),
            "reading the state back");
      check(cudaStreamSynchronize(stream_), "reading the state back");
      for (int i = 0; i < count; ++i) out[base + i] = {h[i].x, h[i].y, h[i].z};
    }
    return out;
  }

  // The drag handle's targets do not change from step to step (none, or past its path).
  bool time_invariant() const { return !p_.drag.active() || t_ > p_.drag.end_time(); }

  // The drag targets of a one-pass step: at its start (the forces) and at its end (the constraints).
  Targets targets() const {
    if (!p_.drag.active()) return {};
    return {p_.drag.target(t_), p_.drag.target(t_ + p_.dt)};
  }

  void drop_graphs() {
    for (auto& g : graph_) {
      if (g) cudaGraphExecDestroy(g);
      g = nullptr;
    }
  }

  void capture(int set) {
    cudaGraph_t g = nullptr;
    check(cudaStreamBeginCapture(stream_, cudaStreamCaptureModeThreadLocal), "starting the step capture");
    try {
      enqueue_step();
    } catch (...) {
      cudaStreamEndCapture(stream_, &g);
      if (g) cudaGraphDestroy(g);
      throw;
    }
    check(cudaStreamEndCapture(stream_, &g), "capturing the step graph");
    const cudaError_t e = cudaGraphInstantiate(&graph_[set], g, 0);
    cudaGraphDestroy(g);
    check(e, "instantiating the step graph");
  }

  // Slot 0 is the current state, 1.. the stage states.
  const float4* slot_x(int k) const { return k == 0 ? x_[cur_].get() : sx_[k - 1].get(); }
  const float4* slot_v(int k) const { return k == 0 ? v_[cur_].get() : sv_[k - 1].get(); }

  void enqueue_step() {
    if (fused_) return timed(span::force_update, [&] { one_pass(true); });
    run_passes(sched_, t_, p_.dt, *this, *this);
  }

  void forces(int src, int acc, double t) override {
    const Vec3f target = p_.drag.active() ? p_.drag.target(t) : Vec3f{};
    timed(span::force, [&] { launch_forces(slot_x(src), slot_v(src), acc_[acc].get(), target, stream_); });
  }

  void update(const Pass& pass) override {
    switch (pass.op) {
      case Pass::Op::combine:
        if (sched_.single_pass()) return timed(span::update, [&] { one_pass(false); });
        return timed(span::update, [&] { combine_pass(pass); });
      case Pass::Op::update: return timed(span::update, [&] { one_pass(false); });
      case Pass::Op::solve: throw std::logic_error("solve pass on a CUDA pipeline");
      case Pass::Op::force: throw std::logic_error("a force pass is not an update");
    }
  }

  // Runs `launch`, timed as a span named `name` when a profiler is attached (of `steps` steps:
  // EventSpans::begin).
  template <class F>
  void timed(const char* name, F&& launch, int steps = 1) {
    Profiler* p = sampling(prof_);
    if (!p) return launch();
    spans_.begin(*p, name, stream_, steps);
    launch();
    spans_.end(stream_);
    if (spans_.pending() > 1024) spans_.collect(prof_);
  }

  // The checks in the order their errors are reported, before anything is allocated.
  static const Model& checked(const PipelineSetup& su, const Options& o) {
    if (const std::string why = unsupported(su.integrator, o.variant); !why.empty()) throw std::invalid_argument(why);
    if (const std::string why = unavailable(); !why.empty()) throw std::invalid_argument(why);
    validate(su.params, su.model.node_count());
    if (o.variant == Variant::temporal && !su.model.grid())
      throw std::invalid_argument("cuda-temporal runs grid models (cloths and lattices), not meshes (use cuda-fused)");
    if (o.variant == Variant::tiled || su.model.topology != Topology::general) check_tile(su.model, o.tile);
    if (o.tma.value_or(false)) {
      std::string why = tma_misfit(o, su.model, su.integrator);
      if (why.empty() && device_info().cc_major < 9) why = "the device's compute capability is below 9.0";
      if (!why.empty())
        throw std::invalid_argument("option tma=on: the tensor memory accelerator's kernel cannot run: " + why);
    }
    require_device_memory(bytes_needed(su.model.size(), su.integrator, o),
                          std::string("the cuda-") + to_string(o.variant) + " pipeline for " +
                              std::to_string(su.model.node_count()) + " nodes (" +
                              std::string(info(su.integrator).name) + ")");
    return su.model;
  }

  // The result of a one-force-pass schedule: the update kernel after a force pass, or with
  // `fused` forces, update and constraints in one kernel.
  void one_pass(bool fused) {
    with_rule([&](auto rule) { one_pass_as<rule()>(fused); });
  }
  // Calls f(Rule) with the one-pass update rule (RULE_*) of the schedule as a compile-time flag
  // (the one-step and cuda-temporal launches, the prefetch plan).
  template <class F>
  void with_rule(F&& f) const {
    using std::integral_constant;
    switch (sched_.rule) {
      case UpdateRule::runge_kutta: return f(integral_constant<int, RULE_RUNGE_KUTTA>{});
      case UpdateRule::semi_implicit_euler: return f(integral_constant<int, RULE_SEMI_IMPLICIT_EULER>{});
      case UpdateRule::verlet: return f(integral_constant<int, RULE_VERLET>{});
      case UpdateRule::backward_euler: throw std::logic_error("a one-pass launch for backward Euler");
    }
  }
  template <int Rule>
  void one_pass_as(bool fused) {
    const int nxt = after(cur_);
    const float w = float(sched_.weight());
    const float4 *x = x_[cur_].get(), *v = v_[cur_].get();
    float4 *xo = x_[nxt].get(), *vo = v_[nxt].get();
    const Targets tg = targets();
    if (!fused) {
      dev::update<Rule><<<blocks_for(n_), kBlock, 0, stream_>>>(sp_, w, x, v, acc_[0].get(), half_step_, xo, vo,
                                                                tg.end, stop_check());
      check_launch("launching the update kernel");
    } else if (!model_.grid()) {
      const auto kernel = damped_ ? dev::fused_csr<Rule, true> : dev::fused_csr<Rule, false>;
      kernel<<<blocks_for(n_), kBlock, 0, stream_>>>(sp_, w, offset_.get(), links_.get(), x, v, half_step_, xo, vo,
                                                     tg, stop_check());
      check_launch("launching the fused CSR step kernel");
    } else if (tma_) {
      const auto kernel = damped_ ? dev::fused_cloth_tma<true, Rule> : dev::fused_cloth_tma<false, Rule>;
      kernel<<<grid_blocks(), grid_threads(), 0, stream_>>>(sp_, stencil_, w, tma_maps_[cur_][0], tma_maps_[cur_][1], v,
                                                            half_step_, xo, vo, tg, stop_check());
      check_launch("launching the fused cloth step kernel");
    } else {
      with_grid_flags([&](auto n, auto damped) {
        dev::fused_grid<n(), damped(), Rule>
            <<<grid_blocks(), grid_threads(), 0, stream_>>>(sp_, stencil_, w, x, v, half_step_, xo, vo, tg,
                                                            stop_check(), prefetch_);
      });
      check_launch("launching the fused step kernel");
    }
  }

  // How many nodes ahead a fused grid launch asks L2 for (dev::fused_grid, fast math): a third
  // of the nodes the device runs at once.
  void plan_prefetch() {
    with_rule([&](auto rule) {
      with_grid_flags([&](auto n, auto damped) {
        const dim3 t = grid_threads();
        int per_sm = 0;
        check(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&per_sm, dev::fused_grid<n(), damped(), rule()>,
                                                            int(t.x * t.y), 0),
              "querying the fused kernel's occupancy");
        prefetch_ = int(std::int64_t(per_sm) * device_info().sm_count * t.x * t.y / 3);
      });
    });
  }

  // The state sets after and before set c.
  int after(int c) const { return (c + 1) % kStateSets; }
  int before(int c) const { return (c + kStateSets - 1) % kStateSets; }

  // cuda-temporal's step: held until steps_per_launch steps can go in one launch.
  void hold_step() {
    held_t_[pending_++] = t_;
    t_ += p_.dt;
    stepped_ = true;
    back_ = Back::none;  // until these steps are launched
    if (pending_ == plan_.k) flush();
  }
  // Launches the held steps, if any (before anything reads the state or its step times).
  void flush() {
    if (pending_ == 0) return;
    timed(span::force_update, [&] { with_rule([&](auto rule) { launch_temporal<rule()>(); }); }, pending_);
    end_launch(pending_, held_t_[0]);
    pending_ = 0;
  }
  template <int Rule>
  void launch_temporal() {
    dev::StepTargets tg{};
    for (int q = 0; q < pending_ && p_.drag.active(); ++q)
      tg.step[q] = {p_.drag.target(held_t_[q]), p_.drag.target(held_t_[q] + p_.dt)};
    const int nxt = after(cur_);
    const dim3 blocks = plan_.blocks(sp_.nx, sp_.ny, sp_.nz), threads(dev::kTemporalThreads);
    with_grid_flags([&](auto n, auto damped) {
      const auto kernel = dev::temporal_grid<n(), damped(), Rule>;
      // The limit is the kernel's, for every pipeline that launches it: raised to the device's
      // (the same for all), once for the one kernel this pipeline launches.
      if (!temporal_limit_raised_)
        check(cudaFuncSetAttribute(kernel, cudaFuncAttributeMaxDynamicSharedMemorySize, plan_.shared_limit),
              "raising the temporal kernel's shared-memory limit");
      temporal_limit_raised_ = true;
      kernel<<<blocks, threads, plan_.shared, stream_>>>(
          sp_, stencil_, float(sched_.weight()), pending_, plan_.tile, x_[cur_].get(), v_[cur_].get(), half_step_,
          x_[nxt].get(), v_[nxt].get(), tg, stop_check());
    });
    check_launch("launching the temporal step kernel");
  }

  // The stop rule's reduction in the launch that writes the step's result: a launch from set c
  // adds into word c and passes on the word of the launch before it (the step graphs hold one
  // set each); the word after the sets' counts the launches.
  dev::StopCheck stop_check() {
    return {stop_.get() + cur_, stop_.get() + before(cur_), stop_.get() + kStateSets, disp_device_};
  }

  // A stage state or the step's result from the slopes with a non-zero weight.
  void combine_pass(const Pass& pass) {
    dev::Terms terms{};
    for (int k = 0; k < int(pass.weights.size()); ++k) {
      if (pass.weights[k] == 0.0) continue;
      terms.v[terms.count] = slot_v(k);
      terms.a[terms.count] = acc_[k].get();
      terms.weight[terms.count] = float(pass.weights[k]);
      ++terms.count;
    }
    const bool result = pass.dst == Pass::kResult;
    const int nxt = after(cur_);
    float4* xo = result ? x_[nxt].get() : sx_[pass.dst - 1].get();
    float4* vo = result ? v_[nxt].get() : sv_[pass.dst - 1].get();
    dev::combine<<<blocks_for(n_), kBlock, 0, stream_>>>(sp_, x_[cur_].get(), v_[cur_].get(), terms, xo, vo,
                                                         targets().end,
                                                         result ? stop_check() : dev::StopCheck{});
    check_launch("launching the combine kernel");
  }

  Params p_;
  Profiler* prof_ = nullptr;
  EventSpans spans_;  // force / update / force+update spans while profiled
  Schedule sched_;
  int n_ = 0;
  bool fused_ = false;

  // State sets in turn: cur_ is the current state, the other the previous step's until the
  // next step.
  Buffer<float4> x_[kStateSets], v_[kStateSets];
  Buffer<float4> sx_[3], sv_[3], acc_[4];
  Buffer<unsigned> stop_;  // the maximum of a launch from each state, the result launches (stop_check)
  struct FreeHost {
    void operator()(void* p) const { cudaFreeHost(p); }
  };
  std::unique_ptr<float4, FreeHost> staging_;
  std::unique_ptr<unsigned long long, FreeHost> disp_host_;  // dev::StopCheck::host
  unsigned long long* disp_device_ = nullptr;                 // the same word for the device
  unsigned long long result_launches_ = 0;                    // as the device counts them
  enum class Read { none, launch, zero } queued_ = Read::none;  // zero: no step since set_state
  unsigned long long read_after_ = 0;                         // result launches when the read was queued

  cudaStream_t stream_ = nullptr;
  cudaEvent_t copied_ = nullptr;  // copy_positions: the steps before a copy
  cudaGraphExec_t graph_[kStateSets] = {};  // one step from each state set
  int cur_ = 0;
  int prefetch_ = 0;  // fused grid launches with dev::kPrefetchAhead: plan_prefetch
  // Fused cloth launches by dev::fused_cloth_tma, each set's x (and v if damped) through its tensor maps.
  bool tma_ = false;
  std::array<CUtensorMap, 2> tma_maps_[kStateSets] = {};
  std::map<std::string, std::string> chosen_;  // chosen_options
  bool half_step_ = false, stepped_ = false;
  double t_ = 0.0;
  enum class Back { none, possible, taken } back_ = Back::none;  // step_back
  double back_t_ = 0.0;         // t_ before the last launch
  bool back_half_step_ = false;  // half_step_ before it
  std::int64_t launched_ = 0;  // steps queued on the device

  // cuda-temporal: steps are held back until a launch can take steps_per_launch of them (or
  // something reads the state); t_ then counts the held steps too.
  bool temporal_ = false;
  TemporalPlan plan_;
  int pending_ = 0;  // steps held
  double held_t_[dev::kMaxStepsPerLaunch] = {};  // the held steps' start times
  bool temporal_limit_raised_ = false;
};

// The force pass alone, on the current device (the hybrid pipelines' CUDA stage).
class DeviceForcePass final : public ForcePass, private ForceKernels {
 public:
  DeviceForcePass(const Model& m, const Params& p, const Options& o) : ForceKernels(m, p, o) {}
  void run(const float4* x, const float4* v, float4* acc, Vec3f drag_target, CUstream_st* stream) override {
    launch_forces(x, v, acc, drag_target, stream);
  }
  void set_drag(const DragHandle& d) override { set_drag_params<float>(sp_, d); }
};

}  // namespace

std::unique_ptr<CudaPipeline> make_pipeline(const PipelineSetup& s, const Options& o) {
  return std::make_unique<Impl>(s, o);
}

std::unique_ptr<ForcePass> make_force_pass(const Model& m, const Params& p, const Options& o) {
  if (o.variant == Variant::fused) throw std::invalid_argument("cuda-fused is a whole step, not a force pass");
  if (const std::string why = unavailable(); !why.empty()) throw std::invalid_argument(why);
  validate(p, m.node_count());
  if (o.variant == Variant::tiled || m.topology != Topology::general) check_tile(m, o.tile);
  return std::make_unique<DeviceForcePass>(m, p, o);
}

}  // namespace deformlab::cuda::DL_CUDA_MATH
