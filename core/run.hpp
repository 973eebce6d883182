// The run loop: steps a pipeline until the paper's stop rule holds (no node moved more than
// the threshold in a step, once the drag path has ended) or a step budget runs out, and
// catches divergence at the check where it shows.
#pragma once
#include <functional>
#include <stdexcept>
#include <vector>

#include "model.hpp"
#include "integrator.hpp"
#include "params.hpp"
#include "pipeline.hpp"

namespace deformlab {

// The bounds below are Gershgorin's, over the rows of the free nodes (not pinned, not
// hard-dragged) of the model linearised at rest: a spring's stiffness or damping counts on its
// node's row, and again off it where its other end is free. They are exact on a free node alone,
// one on a spring to a fixed node and two free nodes of one mass on a spring, conservative
// elsewhere (on a grid a step some way over one may still be stable).
//
// The largest time step for which `i` keeps the undamped springs from growing: c / w_max, with
// c = 2 for the symplectic schemes (semi-implicit Euler, Verlet), sqrt(3) for RK3 and 2 sqrt(2)
// for RK4 (where their stability regions cross the imaginary axis), and w_max^2 the largest
// (stiffness terms + drag spring) / mass. Infinite for backward Euler and where no free node has
// a spring; 0 for explicit Euler and midpoint, which amplify an undamped oscillation at any step.
double stability_limit(const Model& m, const Params& p, Integrator i);
// The largest time step for which `i` keeps the damping from growing the velocities it damps:
// r / gamma_max, r = 2 for the Euler schemes, midpoint and Verlet, 2.51 for RK3 and 2.79 for
// RK4 (their stability intervals on the negative real axis), gamma_max the largest (c + the
// springs' damping terms) / mass, c the global damping (f = -c v). Infinite without damping and
// for backward Euler.
double damping_limit(const Model& m, const Params& p, Integrator i);
// Semi-implicit Euler's and Verlet's bound with the springs and the damping together, where
// w_max^2 dt^2 + 2 gamma_max dt = 4: under both of the above, and equal to one where the other
// rate is 0. Infinite for the other schemes, for which none is derived here (RK4's region has
// points under both of its bounds where a mode grows: w dt near 2.7 with gamma dt near 2.5).
double damped_stability_limit(const Model& m, const Params& p, Integrator i);
// Empty, or "dt = ... s is above <i>'s bound ..." naming the first of the three bounds that dt
// reaches (the damping's, the springs', both together) and its value.
std::string step_bound_passed(const Model& m, const Params& p, Integrator i);
// What a divergence message says about the step: the bound and where dt lies against it.
std::string stability_hint(const Model& m, const Params& p, Integrator i);

// Empty when a step's largest displacement `disp` (Pipeline::max_displacement) is finite and
// below the runaway limit (runaway_factor x `extent`, the model's Model::extent(), which walks
// every node: callers take it once; `extent` counts as at least 1 mm, so that a model of almost no
// extent does not take every move for a runaway), else the message naming the step, what was seen
// and the bound.
std::string divergence(double disp, float extent, const Model& m, const Params& p, Integrator i, int step, double t);

// Empty, or why the stop rule passes whatever a run does: a threshold at or over the runaway
// distance, or one that gravity and wind do not reach in any step of a fall from rest between
// the rule's first check and max_steps (a dt too small for the threshold).
std::string loose_stop_rule(const Model& m, const Params& p);

class DivergenceError : public std::runtime_error {
 public:
  DivergenceError(int step, const std::string& what) : std::runtime_error(what), step(step) {}
  int step;
};

struct StepRecord {
  int step;
  double t;                 // simulated time after the step, s
  double ms;                // time of the step on the pipeline's step clock (RunResult::clock), ms
  double queue_ms;          // host clock around step(), ms: on a GPU pipeline the time to queue it
  double max_displacement;  // m; NaN where the step was not checked
};

struct RunResult {
  int steps = 0;
  bool converged = false;
  double last_displacement = 0.0;
  double total_ms = 0.0;  // of the steps, on the step clock
  // Host clock from the first step to the device's end of the last, with the checks and the
  // after_step calls in between: what the run took.
  double wall_ms = 0.0;
  std::string clock;      // the step clock (Pipeline::step_timer)
  std::vector<StepRecord> records;
};

// The simulated time after `steps` steps of `dt`, in the decimals the scene gave dt in (0.002 s
// a step, not the float's 0.0020000000949949026) to the nanosecond.
double simulated_time_s(int steps, float dt);

// The first step at which the stop rule may end a convergence run: from min_steps on, once
// the drag path has ended.
int first_stop_step(const Params& p);

struct RunOptions {
  bool until_converged = false;  // else run exactly params.max_steps steps
  // Called after every step (e.g. to write frames); may be empty. When set, each check waits
  // for its step; else a pipeline that can step back has it read while the next step runs.
  std::function<void(int step)> after_step;
  // Called after every step with the largest displacement last checked (m; 0 before the
  // first check), without waiting for the device: for a progress line. May be empty.
  std::function<void(int step, double displacement)> progress;
  // When set: the pipeline's own stage spans, "step" on the step clock and "reductions" on
  // the host clock.
  Profiler* profiler = nullptr;
  Integrator integrator = Integrator::semi_implicit_euler;  // the pipeline's, for the divergence message
};

// Throws DivergenceError naming the step, what was seen and the stability limit, and
// Interrupted after the step where an InterruptCatcher caught a signal.
RunResult run(Pipeline& pipe, const Model& m, const Params& p, const RunOptions& opt);

}  // namespace deformlab
