#include "run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <utility>

#include "interrupt.hpp"
#include "number_text.hpp"
#include "springs.hpp"

namespace deformlab {

namespace {

bool fixed(const Model& m, const Params& p, int n) { return m.pinned(n) || p.hard_dragged(n); }

// Gershgorin bounds over the free nodes' rows of the linearised model: w2 on the largest squared
// angular frequency of the springs (and a drag spring), gamma on the largest damping rate (the
// global damping's and the springs'). A spring counts on its node's row, and again off it where
// its other end is free.
struct Rates {
  double w2 = 0.0, gamma = 0.0;
};
Rates rates(const Model& m, const Params& p) {
  double w2 = 0.0, gamma = 0.0;
  const int nodes = m.node_count();
#pragma omp parallel for schedule(static) reduction(max : w2, gamma)
  for (int n = 0; n < nodes; ++n) {
    if (fixed(m, p, n)) continue;
    double k = 0.0, c = p.damping;
    for_each_link(m, n, [&](int w, float, float ks, float kd) {
      const double terms = fixed(m, p, w) ? 1.0 : 2.0;
      k += terms * ks;
      c += terms * kd;
    });
    if (p.drag.active() && p.drag.as_spring && n == p.drag.node) k += p.drag.stiffness;
    w2 = std::max(w2, k * m.inv_mass[n]);
    gamma = std::max(gamma, c * m.inv_mass[n]);
  }
  return {w2, gamma};
}

constexpr double kInfinity = std::numeric_limits<double>::infinity();

double springs_bound(const Rates& r, Integrator i) {
  const double w = std::sqrt(r.w2);
  switch (i) {
    case Integrator::semi_implicit_euler:
    case Integrator::verlet: return 2.0 / w;
    case Integrator::rk3: return std::sqrt(3.0) / w;
    case Integrator::rk4: return 2.0 * std::sqrt(2.0) / w;
    case Integrator::explicit_euler:
    case Integrator::midpoint: return w > 0 ? 0.0 : kInfinity;
    case Integrator::backward_euler: break;
  }
  return kInfinity;
}

double damping_bound(const Rates& r, Integrator i) {
  // Where each scheme's factor on v' = -gamma v reaches 1 in size along gamma dt: -1 for the
  // Euler schemes, Verlet and RK3, +1 for midpoint and RK4.
  double reach = 2.0;
  if (i == Integrator::rk3) reach = 2.5127453266183286;  // root of z^3 - 3z^2 + 6z - 12
  if (i == Integrator::rk4) reach = 2.785293563405282;   // root of z^3 - 4z^2 + 12z - 24
  if (i == Integrator::backward_euler || r.gamma == 0.0) return kInfinity;
  return reach / r.gamma;
}

// Semi-implicit Euler and Verlet on x'' = -w^2 x - gamma x' stay bounded while
// w^2 dt^2 + 2 gamma dt < 4 (Jury's conditions on the step's matrix), the root in dt here
// (written 4 / (sqrt(gamma^2 + 4 w^2) + gamma), which does not cancel).
double together_bound(const Rates& r, Integrator i) {
  if (i != Integrator::semi_implicit_euler && i != Integrator::verlet) return kInfinity;
  const double root = std::sqrt(r.gamma * r.gamma + 4.0 * r.w2) + r.gamma;
  return root > 0.0 ? 4.0 / root : kInfinity;
}

// "dt = ... s is above <i>'s bound ..." for the tightest bound of `r`, where dt reaches it, or "".
std::string bound_passed(const Rates& r, const Model& m, const Params& p, Integrator i) {
  const auto bound = [](double v) {
    std::ostringstream os;
    os << std::setprecision(3) << v;
    return os.str();
  };
  // The tightest of the bounds, where dt passes it (a springs' bound of 0, unstable at any dt, is
  // the scheme's own note); on a tie (within rounding: without springs the joint bound is the
  // damping's) the one that names a single cause.
  const double springs = springs_bound(r, i), k = springs > 0.0 ? springs : kInfinity, d = damping_bound(r, i),
               t = together_bound(r, i), least = std::min({d, k, t});
  if (!(p.dt >= least)) return "";
  const auto tight = [least](double b) { return b <= least * (1.0 + 1e-9); };
  std::ostringstream os;
  os << "dt = " << p.dt << " s is above " << info(i).name;
  if (tight(k))
    os << "'s stability bound dt < " << bound(k) << " s on this model's linearised springs";
  else if (tight(d))
    os << "'s bound for the damping (global damping " << p.damping << " N s/m"
       << (m.damped() ? " and the springs' damping" : "") << ": dt < " << bound(d)
       << " s at the node damped fastest): each step can grow the velocities it damps";
  else
    os << "'s bound for the springs and the damping together (dt < " << bound(t)
       << " s, where w^2 dt^2 + 2 gamma dt = 4 on the linearised model; each alone allows a longer step)";
  return os.str();
}

}  // namespace

double stability_limit(const Model& m, const Params& p, Integrator i) { return springs_bound(rates(m, p), i); }
double damping_limit(const Model& m, const Params& p, Integrator i) { return damping_bound(rates(m, p), i); }
double damped_stability_limit(const Model& m, const Params& p, Integrator i) {
  return together_bound(rates(m, p), i);
}

std::string step_bound_passed(const Model& m, const Params& p, Integrator i) {
  return bound_passed(rates(m, p), m, p, i);
}

std::string stability_hint(const Model& m, const Params& p, Integrator i) {
  const Rates r = rates(m, p);
  if (std::string passed = bound_passed(r, m, p, i); !passed.empty()) return passed;
  const double limit = springs_bound(r, i);
  const std::string name(info(i).name);
  std::ostringstream os;
  if (limit == 0.0) {
    os << name << " amplifies undamped spring oscillations at any dt (semi-implicit-euler and verlet are stable "
       << "for dt < " << together_bound(r, Integrator::semi_implicit_euler) << " s on this model)";
  } else if (std::isinf(limit)) {
    os << name << " is stable at any dt on the linearised springs: stretching or contact made it diverge";
  } else {
    const double least = std::min({limit, damping_bound(r, i), together_bound(r, i)});
    os << "dt = " << p.dt << " s is below " << name << "'s bounds on the linearised springs and damping (" << least
       << " s): stretching, contact or a stiff drag made it diverge";
  }
  return os.str();
}

namespace {

std::size_t whole_launches(int steps, int per_launch) { return std::size_t((steps + per_launch - 1) / per_launch * per_launch); }

// Each step's time on the pipeline's step clock, filled into the records a batch of about 1024
// steps at a time (reading them waits for the device) and at the end. Reading the times
// launches the steps a pipeline holds back, so a batch is whole launches.
class StepTimes {
 public:
  StepTimes(Pipeline& pipe, RunResult& r, Profiler* prof)
      : timer_(pipe.step_timer()), r_(r), prof_(prof), batch_(whole_launches(1024, pipe.steps_per_launch())) {
    r.clock = timer_->clock();
  }
  void begin() {
    start_ms_.push_back(prof_ ? prof_->now_ms() : 0.0);
    timer_->begin();
  }
  void end() { timer_->end(); }
  // After the step's record is added.
  void after_step() {
    if (r_.records.size() - filled_ >= batch_) fill();
  }
  void fill() {
    const std::vector<double> ms = timer_->take();
    for (std::size_t k = 0; k < ms.size() && filled_ < r_.records.size(); ++k, ++filled_) {
      StepRecord& rec = r_.records[filled_];
      rec.ms = ms[k];
      r_.total_ms += ms[k];
      if (prof_) prof_->add({span::step, rec.step, start_ms_[k], ms[k], r_.clock});
    }
    start_ms_.clear();
  }
  // Removes the last steps' records before their times are read: the run took them back
  // (fill() leaves the timer's times of them unread).
  void drop_last(int steps) { r_.records.resize(r_.records.size() - std::size_t(steps)); }

 private:
  std::unique_ptr<StepTimer> timer_;
  RunResult& r_;
  Profiler* prof_;
  std::size_t batch_;  // steps read at a time
  std::size_t filled_ = 0;
  std::vector<double> start_ms_;  // host clock at each pending step's start
};

// How far gravity and wind alone move a free node in step `step` of a fall from rest, the
// farthest over the free nodes: semi-implicit Euler's v_k = (1 - gamma dt) v_(k-1) + a dt moves
// it a dt^2 (1 - q^k) / (1 - q), q = 1 - gamma dt, in step k (k a dt^2 undamped), with
// a = |g + wind / m| and gamma = c / m of the global damping (a uniform fall stretches no
// spring); the other schemes differ by at most a step. 0 where the global damping grows a
// velocity (q <= -1): that, not the fall, is what a run meets.
double free_fall_step(const Model& m, const Params& p, int step) {
  const double dt = p.dt, k = std::max(step, 1);
  double far = 0.0;
  for (int n = 0; n < m.node_count(); ++n) {
    if (fixed(m, p, n)) continue;
    const double a = norm(Vec3d(p.gravity) + Vec3d(p.wind) * double(m.inv_mass[n]));
    const double gdt = double(p.damping) * m.inv_mass[n] * dt;  // 1 - q
    if (gdt >= 2.0) return 0.0;
    const double sum = gdt == 0.0 ? k : gdt < 1.0 ? -std::expm1(k * std::log1p(-gdt)) / gdt
                                                  : (1.0 - std::pow(1.0 - gdt, k)) / gdt;
    far = std::max(far, a * dt * dt * sum);
  }
  return far;
}

}  // namespace

std::string divergence(double disp, float extent, const Model& m, const Params& p, Integrator i, int step, double t) {
  const double runaway = p.runaway_distance(extent);
  if (std::isfinite(disp) && disp <= runaway) return {};
  std::ostringstream os;
  os << "diverged at step " << step << " (t = " << t << " s): ";
  if (!std::isfinite(disp))
    os << "a position, a velocity or a node's move in the step is not finite in float";
  else
    os << "a node moved " << disp << " m in one step, more than " << runaway
       << " m (runaway_factor x model extent, the extent counted as at least 1 mm)";
  // A fall alone makes a state non-finite only where a step's move overflows float's |d|^2.
  const double fall = free_fall_step(m, p, step);
  const double beyond = std::isfinite(disp) ? runaway : std::sqrt(double(std::numeric_limits<float>::max()));
  if (fall <= beyond) {
    os << "; " << stability_hint(m, p, i);
    return os.str();
  }
  os << "; gravity and wind alone move a free node falling from rest " << fall << " m at this step, more than "
     << (std::isfinite(disp) ? "the runaway distance " : "float holds for a move, ") << beyond
     << " m: the field stopped the run";
  if (std::isfinite(disp)) os << " (a larger runaway_factor admits the fall)";
  if (const std::string passed = step_bound_passed(m, p, i); !passed.empty()) os << "; also, " << passed;
  return os.str();
}

std::string loose_stop_rule(const Model& m, const Params& p) {
  std::ostringstream os;
  if (const double runaway = p.runaway_distance(m.extent()); p.threshold >= runaway)
    os << "threshold = " << p.threshold << " m a step is at least the runaway distance " << runaway
       << " m: every step that does not diverge passes the stop rule";
  else if (const int first = first_stop_step(p); first <= p.max_steps) {
    // The fall's step grows to max_steps, or, where the damping overshoots (q < 0), swings
    // about its terminal step, widest at the first step of the range or the one after.
    double fall = 0.0;
    for (const int k : {first, std::min(first + 1, p.max_steps), p.max_steps})
      fall = std::max(fall, free_fall_step(m, p, k));
    if (fall > 0.0 && p.threshold > fall)
      os << "threshold = " << p.threshold << " m a step (" << p.threshold / p.dt << " m/s at dt = " << p.dt
         << " s) is more than gravity and wind alone move a node falling from rest in any step from the stop "
         << "rule's first check to max_steps (" << fall << " m at most): unless springs or the drag move nodes "
         << "faster, the rule holds at its first check";
  }
  return os.str();
}

double simulated_time_s(int steps, float dt) { return std::round(steps * shortest_decimal(dt) * 1e9) / 1e9; }

int first_stop_step(const Params& p) {
  const double drag_end = p.drag.active() ? p.drag.end_time() : 0.0;
  int step = std::max(p.min_steps, 1);
  if (step * double(p.dt) >= drag_end) return step;
  // A path that ends past the last step an int can count: never.
  const double q = std::ceil(drag_end / double(p.dt));
  if (q >= double(std::numeric_limits<int>::max())) return std::numeric_limits<int>::max();
  step = int(q);
  while (step < std::numeric_limits<int>::max() && step * double(p.dt) < drag_end) ++step;  // q rounded down
  return step;
}

RunResult run(Pipeline& pipe, const Model& m, const Params& p, const RunOptions& opt) {
  using clock = std::chrono::steady_clock;
  RunResult r;
  r.records.reserve(std::size_t(std::min(p.max_steps, 1 << 20)));
  const int first_stop = first_stop_step(p);
  const float extent = m.extent();
  // A check waits for its step where the pipeline cannot step back, each step is looked at
  // (after_step) or checks fall between launches; else it is read while the next launch runs
  // (Pipeline::step_back), that is `launch` steps later.
  const int launch = pipe.steps_per_launch();
  const bool lagged = pipe.can_step_back() && !opt.after_step && p.check_every % launch == 0;
  int queued = 0;  // the step whose check is queued (lagged), else 0
  // Records a checked step's displacement; true when the run stops there.
  auto stops_at = [&](int step, double disp) {
    const double t = step * double(p.dt);
    r.records[std::size_t(step - 1)].max_displacement = disp;
    r.last_displacement = disp;
    if (const std::string why = divergence(disp, extent, m, p, opt.integrator, step, t); !why.empty())
      throw DivergenceError(step, why);
    return opt.until_converged && step >= first_stop && disp < p.threshold;
  };
  pipe.set_profiler(opt.profiler);
  StepTimes times(pipe, r, opt.profiler);
  const auto start = clock::now();
  for (int step = 1; step <= p.max_steps; ++step) {
    if (opt.profiler) opt.profiler->set_step(step);
    const auto t0 = clock::now();
    times.begin();
    {
      NvtxRange range(span::step);
      pipe.step();
    }
    times.end();
    const double queue_ms = std::chrono::duration<double, std::milli>(clock::now() - t0).count();
    r.steps = step;
    r.records.push_back({step, simulated_time_s(step, p.dt), std::numeric_limits<double>::quiet_NaN(), queue_ms,
                         std::numeric_limits<double>::quiet_NaN()});
    if (queued && step == queued + launch) {  // the check before this launch, read while it runs
      const int checked = std::exchange(queued, 0);
      bool met = false;
      try {
        HostSpan span(opt.profiler, span::reductions);
        met = stops_at(checked, pipe.take_displacement());
      } catch (const DivergenceError&) {
        pipe.step_back();
        throw;
      }
      if (met) {
        pipe.step_back();
        times.drop_last(launch);
        r.steps = checked;
        r.converged = true;
        break;
      }
    }
    const bool check = step % p.check_every == 0 || step == p.max_steps;
    bool stop = false;
    if (check && lagged && step + launch <= p.max_steps) {
      pipe.queue_displacement();
      queued = step;
    } else if (check) {
      HostSpan span(opt.profiler, span::reductions);
      stop = stops_at(step, pipe.max_displacement());
    }
    times.after_step();
    if (opt.after_step) opt.after_step(step);
    if (opt.progress) opt.progress(step, r.last_displacement);
    if (const int sig = InterruptCatcher::caught())
      throw Interrupted(sig, signal_name(sig) + " at step " + std::to_string(step) + " of " + std::to_string(p.max_steps));
    if (stop) {
      r.converged = true;
      break;
    }
  }
  times.fill();  // waits for the last step
  r.wall_ms = std::chrono::duration<double, std::milli>(clock::now() - start).count();
  pipe.set_profiler(nullptr);  // collects the spans still pending
  return r;
}

}  // namespace deformlab
