// Integrators as schedules of force and update passes. A schedule is plain data: which
// state slot to evaluate forces at, which update to apply. Backends run the passes (and
// may fuse a one-force-pass schedule into one kernel or shader); the integrator never
// knows which backend runs it.
#pragma once
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace deformlab {

enum class Integrator {
  explicit_euler,       // x' = x + dt v,  v' = v + dt a(x, v)
  semi_implicit_euler,  // v' = v + dt a(x, v),  x' = x + dt v'   (paper's "implicit Euler", eq. 7)
  midpoint,             // RK2: a at the half-step state (two force passes)
  rk4,                  // classical Runge-Kutta 4 (four force passes)
  verlet,               // position Verlet: x' = 2x - x_prev + dt^2 a,  v' = (x' - x) / dt
  backward_euler,       // implicit Euler, one linearised solve per step (Baraff & Witkin 1998)
};

struct IntegratorInfo {
  Integrator id;
  std::string_view name;
  std::string_view paper_alias;  // the paper's name, accepted on input ("" if none)
  int force_passes;              // per step (backward Euler: 1 evaluation + its Jacobian)
  int order;                     // global order of accuracy in position
  std::string_view summary;
};

const std::vector<IntegratorInfo>& integrators();
const IntegratorInfo& info(Integrator i);
// Accepts names and the paper's aliases; nullopt if unknown.
std::optional<Integrator> parse_integrator(std::string_view name);
std::string integrator_names();  // "explicit-euler, semi-implicit-euler, ..." for messages

// State slots a schedule refers to: 0 = current state (input), 1.. = stage states.
// Acceleration slots hold a force pass's result, 0..3.
struct Pass {
  enum class Op {
    force,    // accel[acc] = a(state[src], t + time_fraction * dt)
    stage,    // state[dst] = state[0] + coef * dt * (v of state[src], accel[acc])
    combine,  // next = state[0] + dt * sum_k weights[k] * (v of state[k], accel[k]); then constraints
    fused,    // next = one-pass update from state[0] and accel[0] (the `update` rule); then constraints
    solve,    // next = backward Euler solve from state[0]; then constraints
  } op = Op::force;
  int src = 0, dst = 0, acc = 0;
  double coef = 0.0, time_fraction = 0.0;
  std::vector<double> weights;  // combine only: one per stage (state k, accel k)
};

struct Schedule {
  Integrator integrator;
  std::vector<Pass> passes;
  int stage_states = 0;  // extra state slots needed besides the current one
  int accel_slots = 0;
  // True when the schedule is one force pass followed by a fused update, so that
  // backends may run it as one kernel / shader.
  bool single_pass() const;
};

Schedule make_schedule(Integrator i);

}  // namespace deformlab
