#include "run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

#include "interrupt.hpp"
#include "number_text.hpp"
#include "springs.hpp"

namespace deformlab {

double stability_limit(const Model& m, const Params& p, Integrator i) {
  double w2 = 0.0;  // Gershgorin bound on the largest squared angular frequency
  const int nodes = m.node_count();
#pragma omp parallel for schedule(static) reduction(max : w2)
  for (int n = 0; n < nodes; ++n) {
    if (m.inv_mass[n] == 0.f) continue;
    double k = 0.0;
    for_each_link(m, n, [&](int, float, float ks, float) { k += 2.0 * ks; });
    if (p.drag.active() && p.drag.as_spring && n == p.drag.node) k += p.drag.stiffness;
    w2 = std::max(w2, k * m.inv_mass[n]);
  }
  const double w = std::sqrt(w2);
  switch (i) {
    case Integrator::semi_implicit_euler:
    case Integrator::verlet: return 2.0 / w;
    case Integrator::rk3: return std::sqrt(3.0) / w;
    case Integrator::rk4: return 2.0 * std::sqrt(2.0) / w;
    case Integrator::explicit_euler:
    case Integrator::midpoint: return w > 0 ? 0.0 : std::numeric_limits<double>::infinity();
    case Integrator::backward_euler: break;
  }
  return std::numeric_limits<double>::infinity();
}

namespace {

// Pinned, or hard-dragged (the node follows its path, not its velocity).
bool fixed(const Model& m, const Params& p, int n) {
  return m.inv_mass[n] == 0.f || (p.drag.active() && !p.drag.as_spring && n == p.drag.node);
}

}  // namespace

double damping_limit(const Model& m, const Params& p, Integrator i) {
  double gamma = 0.0;  // Gershgorin bound on the largest damping rate of a free node, 1/s
  const int nodes = m.node_count();
#pragma omp parallel for schedule(static) reduction(max : gamma)
  for (int n = 0; n < nodes; ++n) {
    if (fixed(m, p, n)) continue;
    double c = p.damping;  // the global damping, and each spring's on its row and, to a free node, off it
    for_each_link(m, n, [&](int w, float, float, float kd) { c += (fixed(m, p, w) ? 1.0 : 2.0) * kd; });
    gamma = std::max(gamma, c * m.inv_mass[n]);
  }
  // Where each scheme's factor on v' = -gamma v reaches 1 in size along gamma dt: -1 for the
  // Euler schemes, Verlet and RK3, +1 for midpoint and RK4.
  double reach = 2.0;
  if (i == Integrator::rk3) reach = 2.5127453266183286;  // root of z^3 - 3z^2 + 6z - 12
  if (i == Integrator::rk4) reach = 2.785293563405282;   // root of z^3 - 4z^2 + 12z - 24
  if (i == Integrator::backward_euler || gamma == 0.0) return std::numeric_limits<double>::infinity();
  return reach / gamma;
}

std::string damping_bound_passed(const Model& m, const Params& p, Integrator i) {
  const bool springs = std::ranges::any_of(m.damping, [](float kd) { return kd > 0.f; }) ||
                       std::ranges::any_of(m.spring_damping, [](float kd) { return kd > 0.f; });
  std::ostringstream os;
  os << "dt = " << p.dt << " s is above " << info(i).name << "'s bound for the damping (global damping " << p.damping
     << " N s/m" << (springs ? " and the springs' damping" : "") << ": dt < " << damping_limit(m, p, i)
     << " s at the node damped fastest)";
  return os.str();
}

std::string stability_hint(const Model& m, const Params& p, Integrator i) {
  const double limit = stability_limit(m, p, i);
  const std::string name(info(i).name);
  std::ostringstream os;
  if (p.dt >= damping_limit(m, p, i)) {
    os << damping_bound_passed(m, p, i) << ": each step can grow the velocities it damps";
  } else if (limit == 0.0) {
    os << name << " amplifies undamped spring oscillations at any dt (semi-implicit-euler and verlet are stable for dt < "
       << stability_limit(m, p, Integrator::semi_implicit_euler) << " s on this model)";
  } else if (std::isinf(limit)) {
    os << name << " is stable at any dt on the linearised springs: stretching or contact made it diverge";
  } else if (p.dt >= limit) {
    os << "dt = " << p.dt << " s is above " << name << "'s stability bound dt < " << limit
       << " s on this model's linearised springs";
  } else {
    os << "dt = " << p.dt << " s is below " << name << "'s stability bound " << limit
       << " s on the linearised springs: stretching, contact or a stiff drag made it diverge";
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

}  // namespace

namespace {

// How far the constant fields alone move the free node they pull hardest in step `step` of a
// fall from rest: |g + wind / m| dt^2 x step (semi-implicit Euler's; the other schemes' differ
// by at most a step).
double free_fall_step(const Model& m, const Params& p, int step) {
  double a = 0.0;
  for (int n = 0; n < m.node_count(); ++n)
    if (!fixed(m, p, n)) a = std::max(a, norm(Vec3d(p.gravity) + Vec3d(p.wind) * double(m.inv_mass[n])));
  return a * double(p.dt) * double(p.dt) * std::max(step, 1);
}

double runaway_distance(const Params& p, float extent) {
  return double(p.runaway_factor) * std::max(double(extent), 1e-3);
}

}  // namespace

std::string divergence(double disp, float extent, const Model& m, const Params& p, Integrator i, int step, double t) {
  const double runaway = runaway_distance(p, extent);
  if (std::isfinite(disp) && disp <= runaway) return {};
  std::ostringstream os;
  os << "diverged at step " << step << " (t = " << t << " s): ";
  if (!std::isfinite(disp))
    os << "a position or velocity is not finite";
  else
    os << "a node moved " << disp << " m in one step, more than " << runaway
       << " m (runaway_factor x model extent, the extent counted as at least 1 mm)";
  if (const double fall = free_fall_step(m, p, step); fall > runaway)
    os << "; gravity and wind alone move a free node falling from rest " << fall << " m at this step (|g + wind / m| "
       << "dt^2 x step), more than the runaway distance " << runaway << " m: the field, not the step's stability, "
       << "stopped the run (a larger runaway_factor admits motion that stays finite)";
  else
    os << "; " << stability_hint(m, p, i);
  return os.str();
}

std::string loose_stop_rule(const Model& m, const Params& p) {
  std::ostringstream os;
  if (const double runaway = runaway_distance(p, m.extent()); p.threshold >= runaway)
    os << "threshold = " << p.threshold << " m a step is at least the runaway distance " << runaway
       << " m: every step that does not diverge passes the stop rule";
  else if (const double fall = free_fall_step(m, p, p.max_steps); fall > 0.0 && p.threshold > fall)
    os << "threshold = " << p.threshold << " m a step (" << p.threshold / p.dt << " m/s at dt = " << p.dt
       << " s) is more than gravity and wind alone move a node falling from rest at any step up to max_steps ("
       << fall << " m at step " << p.max_steps << "): unless springs or the drag move nodes faster, the stop rule "
       << "holds at its first check";
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
