// The run loop: steps a pipeline until the paper's stop rule holds (no node moved more than
// the threshold in a step, once the drag path has ended) or a step budget runs out, and
// catches divergence at the check where it shows.
#pragma once
#include <functional>
#include <stdexcept>
#include <vector>

#include "model.hpp"
#include "params.hpp"
#include "pipeline.hpp"

namespace deformlab {

// Largest explicit time step for which a symplectic scheme stays stable on this model:
// dt < 2 sqrt(m / k_eff), with k_eff = 2 * (sum of incident spring stiffness) per node,
// a Gershgorin bound on the stiffness matrix (so the limit is conservative). Infinite when
// no free node has springs.
double explicit_stability_limit(const Model& m, const Params& p);

class DivergenceError : public std::runtime_error {
 public:
  DivergenceError(int step, const std::string& what) : std::runtime_error(what), step(step) {}
  int step;
};

struct StepRecord {
  int step;
  double t;                 // simulated time after the step, s
  double ms;                // wall time of the step, ms (host clock)
  double max_displacement;  // m; NaN where the step was not checked
};

struct RunResult {
  int steps = 0;
  bool converged = false;
  double last_displacement = 0.0;
  double total_ms = 0.0;
  std::vector<StepRecord> records;
};

struct RunOptions {
  bool until_converged = false;  // else run exactly params.max_steps steps
  // Called after every step (e.g. to write frames); may be empty.
  std::function<void(int step)> after_step;
  // When set: the pipeline's own stage spans, plus "step" and "reductions" on the host clock.
  Profiler* profiler = nullptr;
};

// Throws DivergenceError naming the step, what was seen and the stability limit.
RunResult run(Pipeline& pipe, const Model& m, const Params& p, const RunOptions& opt);

}  // namespace deformlab
