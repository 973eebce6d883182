#include "run.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

namespace deformlab {

double explicit_stability_limit(const Model& m, const Params& p) {
  double limit = std::numeric_limits<double>::infinity();
  for (int i = 0; i < m.node_count(); ++i) {
    if (m.inv_mass[i] == 0.f) continue;
    double ksum = 0.0;
    for (int e = m.adj_offset[i]; e < m.adj_offset[i + 1]; ++e) ksum += m.stiffness[int(m.kind[m.adj_spring[e]])];
    if (p.drag.active() && p.drag.as_spring && i == p.drag.node) ksum += p.drag.stiffness;
    if (ksum <= 0.0) continue;
    limit = std::min(limit, 2.0 * std::sqrt((1.0 / m.inv_mass[i]) / (2.0 * ksum)));
  }
  return limit;
}

RunResult run(Pipeline& pipe, const Model& m, const Params& p, const RunOptions& opt) {
  using clock = std::chrono::steady_clock;
  RunResult r;
  r.records.reserve(std::size_t(std::min(p.max_steps, 1 << 20)));
  const double runaway = double(p.runaway_factor) * std::max(double(m.extent()), 1e-3);
  const double drag_end = p.drag.active() ? p.drag.end_time() : 0.0;
  pipe.set_profiler(opt.profiler);
  for (int step = 1; step <= p.max_steps; ++step) {
    if (opt.profiler) opt.profiler->set_step(step);
    const auto t0 = clock::now();
    {
      HostSpan span(opt.profiler, span::step);
      pipe.step();
    }
    const double ms = std::chrono::duration<double, std::milli>(clock::now() - t0).count();
    const double t = step * double(p.dt);
    r.total_ms += ms;
    r.steps = step;
    double disp = std::numeric_limits<double>::quiet_NaN();
    const bool check = step % p.check_every == 0 || step == p.max_steps;
    if (check) {
      HostSpan span(opt.profiler, span::reductions);
      disp = pipe.max_displacement();
      r.last_displacement = disp;
      if (!std::isfinite(disp) || disp > runaway) {
        std::ostringstream os;
        os << "diverged at step " << step << " (t = " << t << " s): ";
        if (!std::isfinite(disp))
          os << "a position or velocity is not finite";
        else
          os << "a node moved " << disp << " m in one step, more than " << runaway
             << " m (runaway_factor x model extent)";
        os << "; explicit stability limit dt < 2 sqrt(m / k_eff) = " << explicit_stability_limit(m, p)
           << " s for this model, dt = " << p.dt << " s";
        throw DivergenceError(step, os.str());
      }
    }
    r.records.push_back({step, t, ms, disp});
    if (opt.after_step) opt.after_step(step);
    if (opt.until_converged && check && step >= p.min_steps && t >= drag_end && disp < p.threshold) {
      r.converged = true;
      break;
    }
  }
  pipe.set_profiler(nullptr);  // collects the spans still pending
  return r;
}

}  // namespace deformlab
