#include "cpu_backend.hpp"

#include <omp.h>

#include <algorithm>

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "springs.hpp"
#include "stage.hpp"
#include "step_params.hpp"

namespace deformlab {
namespace {

template <class Real>
class CpuPipeline final : public Pipeline, private ForceStage, private UpdateStage {
  using P = Physics<Real>;
  using V = Vec3<Real>;
  struct Slot {
    std::vector<V> x, v;
  };

 public:
  CpuPipeline(const PipelineSetup& s, bool parallel)
      : m_(s.model),
        p_(s.params),
        sp_(step_params<Real>(s.model, s.params)),
        stencil_(stencil_entries<Real>(s.model)),
        sched_(make_schedule(s.integrator)),
        threads_(parallel ? std::clamp(m_.node_count() / kNodesPerThread, 1, omp_get_max_threads()) : 1) {
    const std::size_t n = m_.rest_position.size();
    slots_.resize(1 + sched_.stage_states);
    for (auto& sl : slots_) { sl.x.resize(n); sl.v.resize(n); }
    acc_.resize(sched_.accel_slots, std::vector<V>(n));
    next_.x.resize(n); next_.v.resize(n);
    set_state(rest_state(m_));
  }

  void set_state(const State& s) override {
    const std::size_t n = m_.rest_position.size();
    if (s.x.size() != n || s.v.size() != n) throw std::invalid_argument("state size does not match the model");
    half_step_ = s.half_step;
    for_nodes([&](int i) {
      slots_[0].x[i] = V(s.x[i]);
      slots_[0].v[i] = V(s.v[i]);
    });
    t_ = s.t;
    last_disp_ = 0.0;
  }

  State state() override {
    State s;
    s.t = t_;
    const std::size_t n = slots_[0].x.size();
    s.half_step = half_step_;
    s.x.resize(n); s.v.resize(n);
    for_nodes([&](int i) {
      s.x[i] = Vec3f(slots_[0].x[i]);
      s.v[i] = Vec3f(slots_[0].v[i]);
    });
    return s;
  }

  void set_drag(const DragHandle& d) override {
    validate(d, m_.node_count());
    p_.drag = d;
    set_drag_params<Real>(sp_, d);
  }

  void step() override {
    run_passes(sched_, t_, p_.dt, *this, *this);
    HostSpan span(sampling(prof_), span::constraints);
    constrain_and_commit();
  }

  std::vector<Vec3f> accelerations(const State& s, double t) {
    set_state(s);
    force(slots_[0], acc_[0], t);
    return std::vector<Vec3f>(acc_[0].begin(), acc_[0].end());
  }

  // The passes are timed by the host clock in the profiler's sampled steps.
  void set_profiler(Profiler* p) override { prof_ = p; }

  double max_displacement() override { return last_disp_; }

 private:
  template <class F>
  void for_nodes(F&& f) {
    const int n = m_.node_count();
#pragma omp parallel for schedule(static) num_threads(threads_) if (threads_ > 1)
    for (int i = 0; i < n; ++i) f(i);
  }

  // Sum of the spring forces on node i: grids by their stencil, other models by adjacency.
  V springs(const Slot& s, int i) const {
    V f{};
    if (m_.grid()) {
      const int ci = P::grid_axis(i, 1, sp_.nx), cj = P::grid_axis(i, sp_.nx, sp_.ny),
                ck = P::grid_axis(i, sp_.nx * sp_.ny, sp_.nz);
      for (const auto& e : stencil_) {
        const int j = P::grid_neighbour(sp_, ci, cj, ck, e.di, e.dj, e.dk);
        if (j >= 0) f += P::spring_force(s.x[i], s.x[j], s.v[i], s.v[j], e.k, e.kd, e.rest);
      }
      return f;
    }
    for (int e = m_.adj_offset[i]; e < m_.adj_offset[i + 1]; ++e) {
      const int sp = m_.adj_spring[e], j = m_.adj_node[e];
      f += P::spring_force(s.x[i], s.x[j], s.v[i], s.v[j], Real(m_.spring_k(sp)), Real(m_.spring_kd(sp)),
                           Real(m_.rest_length[sp]));
    }
    return f;
  }

  void forces(int src, int acc, double t) override {
    HostSpan span(sampling(prof_), span::force);
    force(slots_[src], acc_[acc], t);
  }

  void update(const Pass& pass) override {
    HostSpan span(sampling(prof_), span::update);
    switch (pass.op) {
      case Pass::Op::combine: return combine(pass);
      case Pass::Op::update: return one_pass();
      case Pass::Op::solve: return solve();
      case Pass::Op::force: throw std::logic_error("a force pass is not an update");
    }
  }

  void force(const Slot& s, std::vector<V>& a, double t) {
    const V target = sp_.drag_mode == DRAG_SPRING ? V(p_.drag.target(t)) : V{};
    for_nodes([&](int i) {
      const Real w = m_.inv_mass[i];
      a[i] = P::node_fixed(sp_, i, w) ? V{} : P::node_acceleration(sp_, i, w, s.x[i], s.v[i], springs(s, i), target);
    });
  }

  void combine(const Pass& pass) {
    const Slot& s0 = slots_[0];
    Slot& dst = pass.dst == Pass::kResult ? next_ : slots_[pass.dst];
    const int terms = int(pass.weights.size());
    for_nodes([&](int i) {
      V dx{}, dv{};
      for (int j = 0; j < terms; ++j)
        if (pass.weights[j] != 0.0) P::add_slope(dx, dv, Real(pass.weights[j]), slots_[j].v[i], acc_[j][i]);
      P::rk_state(s0.x[i], s0.v[i], dx, dv, sp_.dt, dst.x[i], dst.v[i]);
    });
  }

  void one_pass() {
    const Slot& s = slots_[0];
    const auto& a = acc_[0];
    for_nodes([&](int i) {
      P::one_pass_update(int(sched_.rule), Real(1), s.x[i], s.v[i], a[i], half_step_, sp_.dt,
                         next_.x[i], next_.v[i]);
    });
  }

  // Backward Euler, linearised once per step (Baraff & Witkin 1998):
  //   (M - dt D - dt^2 K) dv = dt (f0 + dt K v0),  v' = v0 + dv,  x' = x0 + dt v'
  // with K = df/dx (the (1 - l/|d|) term clamped at 0 so K stays negative semi-definite)
  // and D = df/dv. Pinned and hard-dragged nodes keep dv = 0 (identity rows).
  void solve() {
    using SpMat = Eigen::SparseMatrix<Real>;
    using Vec = Eigen::Matrix<Real, Eigen::Dynamic, 1>;
    using M3 = Eigen::Matrix<Real, 3, 3>;
    using E3 = Eigen::Matrix<Real, 3, 1>;
    const int n = m_.node_count();
    const Real dt = p_.dt, c = p_.damping;
    const Slot& s = slots_[0];
    force(s, acc_[0], t_);
    auto fixed = [&](int i) { return P::node_fixed(sp_, i, Real(m_.inv_mass[i])); };
    auto e3 = [](const V& v) { return E3(v.x, v.y, v.z); };

    std::vector<Eigen::Triplet<Real>> trip;
    trip.reserve(9 * (std::size_t(n) + 2 * m_.spring_count()));
    Vec rhs(3 * n);
    std::vector<M3> diag(n, M3::Zero());
    std::vector<E3> kv(n, E3::Zero());  // K v0
    auto add_block = [&](int r, int col, const M3& b) {
      for (int a = 0; a < 3; ++a)
        for (int q = 0; q < 3; ++q) trip.emplace_back(3 * r + a, 3 * col + q, b(a, q));
    };
    for_each_spring(m_, [&](const SpringRef& sp) {
      const int i = sp.i, j = sp.j;
      const E3 d = e3(s.x[i] - s.x[j]);
      const Real len = d.norm();
      if (len == Real(0)) return;
      const E3 u = d / len;
      const M3 uu = u * u.transpose();
      const Real ks = sp.k, kd = sp.kd, rest = sp.rest;
      const Real geo = std::max(Real(0), Real(1) - rest / len);
      const M3 K = -ks * (geo * (M3::Identity() - uu) + uu);  // df_i/dx_i
      const M3 D = -kd * uu;                                  // df_i/dv_i
      const M3 A = -dt * D - dt * dt * K;                      // contribution to A_ii (and -A_ij)
      const E3 vi = e3(s.v[i]), vj = e3(s.v[j]);
      kv[i] += K * (vi - vj);
      kv[j] += K * (vj - vi);
      diag[i] += A;
      diag[j] += A;
      if (!fixed(i) && !fixed(j)) {
        add_block(i, j, -A);
        add_block(j, i, -A);
      }
    });
    const bool spring_drag = p_.drag.active() && p_.drag.as_spring;
    for (int i = 0; i < n; ++i) {
      if (fixed(i)) {
        add_block(i, i, M3::Identity());
        rhs.template segment<3>(3 * i).setZero();
        continue;
      }
      const Real mass = Real(1) / Real(m_.inv_mass[i]);
      M3 b = diag[i] + (mass + dt * c) * M3::Identity();
      E3 k_v = kv[i];
      if (spring_drag && i == p_.drag.node) {
        b += dt * dt * Real(p_.drag.stiffness) * M3::Identity();
        k_v -= Real(p_.drag.stiffness) * e3(s.v[i]);
      }
      add_block(i, i, b);
      const E3 f0 = mass * e3(acc_[0][i]);  // the force pass already holds f0 / m
      rhs.template segment<3>(3 * i) = dt * (f0 + dt * k_v);
    }
    SpMat A(3 * n, 3 * n);
    A.setFromTriplets(trip.begin(), trip.end());
    Eigen::ConjugateGradient<SpMat, Eigen::Lower | Eigen::Upper> cg;
    cg.setTolerance(std::is_same_v<Real, double> ? Real(1e-10) : Real(1e-6));
    cg.setMaxIterations(std::max(100, 3 * n));
    // Eigen's sparse products take its own thread count (all of OpenMP's unless set): this
    // pipeline's, so that cpu solves on one thread. Each row is one thread's, so any count gives
    // the same bits. The count is process-wide: pipelines step one at a time.
    Eigen::setNbThreads(threads_);
    cg.compute(A);
    const Vec dv = cg.solve(rhs);
    if (cg.info() != Eigen::Success && !(cg.error() < 1e-3))
      throw std::runtime_error("backward Euler: conjugate gradient did not converge (error " +
                               std::to_string(double(cg.error())) + ")");
    for (int i = 0; i < n; ++i) {
      next_.v[i] = s.v[i] + V{dv(3 * i), dv(3 * i + 1), dv(3 * i + 2)};
      next_.x[i] = s.x[i] + next_.v[i] * dt;
    }
  }

  // Constraints on next_, then next_ becomes the current state; records the largest
  // displacement of the step (NaN if any value is not finite).
  void constrain_and_commit() {
    const double t1 = t_ + p_.dt;
    const V drag_target = p_.drag.active() ? V(p_.drag.target(t1)) : V{};
    Slot& s = slots_[0];
    Real disp = 0;
    const int n = m_.node_count();
#pragma omp parallel for schedule(static) num_threads(threads_) if (threads_ > 1) reduction(max : disp)
    for (int i = 0; i < n; ++i) {
      P::constrain_node(sp_, i, Real(m_.inv_mass[i]), s.x[i], drag_target, next_.x[i], next_.v[i]);
      disp = std::max(disp, P::displacement(next_.x[i], s.x[i], next_.v[i]));
    }
    if (sched_.rule == UpdateRule::verlet) half_step_ = true;
    std::swap(s.x, next_.x);
    std::swap(s.v, next_.v);
    t_ = t1;
    last_disp_ = std::isinf(disp) ? std::numeric_limits<double>::quiet_NaN() : double(disp);
  }

  const Model& m_;
  Params p_;
  typename P::StepParams sp_;
  std::vector<typename P::StencilEntry> stencil_;
  Schedule sched_;
  int threads_;
  std::vector<Slot> slots_;  // 0: current state, 1..: stage states
  std::vector<std::vector<V>> acc_;
  Slot next_;
  Profiler* prof_ = nullptr;
  bool half_step_ = false;
  double t_ = 0.0;
  double last_disp_ = 0.0;
};

}  // namespace

std::unique_ptr<Pipeline> make_cpu_pipeline(const PipelineSetup& s, Precision p, bool parallel) {
  if (p == Precision::f64) return std::make_unique<CpuPipeline<double>>(s, parallel);
  return std::make_unique<CpuPipeline<float>>(s, parallel);
}

std::vector<Vec3f> cpu_accelerations(const PipelineSetup& setup, const State& s, double t) {
  return CpuPipeline<float>(setup, false).accelerations(s, t);
}

static Footprint cpu_footprint(const ModelSize& m, Integrator i, Precision p) {
  const Schedule s = make_schedule(i);
  const std::int64_t real = p == Precision::f64 ? 8 : 4, vec = 3 * real;
  // slots (x, v), accelerations and the next state
  Footprint f{m.nodes * vec * (2 * (1 + s.stage_states) + s.accel_slots + 2), 0};
  if (s.rule == UpdateRule::backward_euler) {
    // 3x3 blocks: triplets (two indices and a value), the matrix and its transposed copy while
    // assembled; per node the diagonal blocks, K v0, and the solver's vectors (about 8 x 3n).
    const std::int64_t nnz = 9 * (m.nodes + 2 * m.springs);
    f.host += nnz * (8 + real) + 2 * nnz * (4 + real) + m.nodes * real * (9 + 3 + 24);
  }
  return f;
}

void add_cpu_pipelines(PipelineRegistry& r) {
  auto always = [] { return std::string(); };
  auto every = [](Integrator) { return std::string(); };
  auto in = [](Precision p) {
    return [p](const ModelSize& m, Integrator i, const PipelineOptions&) { return cpu_footprint(m, i, p); };
  };
  r.add(described("cpu", always, every, [](const PipelineSetup& s) { return make_cpu_pipeline(s, Precision::f32, false); },
                  in(Precision::f32)));
  r.add(described("omp", always, every, [](const PipelineSetup& s) { return make_cpu_pipeline(s, Precision::f32, true); },
                  in(Precision::f32)));
  r.add(described("reference", always, every,
                  [](const PipelineSetup& s) { return make_cpu_pipeline(s, Precision::f64, true); }, in(Precision::f64)));
}

}  // namespace deformlab
