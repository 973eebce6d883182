// Integrators as data: each one's update rule and, for Runge-Kutta schemes, its Butcher
// tableau; a schedule of force and update passes is derived from them. Backends run the
// passes (and may run a one-force-pass schedule as one kernel or shader); adding an explicit
// Runge-Kutta scheme is one entry in integrators(), which every backend then runs.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace deformlab {

enum class Integrator {
  explicit_euler,       // x' = x + dt v,  v' = v + dt a(x, v)   (one-stage Runge-Kutta)
  semi_implicit_euler,  // v' = v + dt a(x, v),  x' = x + dt v'   (paper's "implicit Euler", eq. 7)
  midpoint,             // RK2: a at the half-step state (two force passes)
  rk3,                  // Kutta's third-order Runge-Kutta (three force passes)
  rk4,                  // classical Runge-Kutta 4 (four force passes)
  verlet,               // Verlet as a leapfrog: v' = v + dt a, x' = x + dt v' (v at half steps)
  backward_euler,       // implicit Euler, one linearised solve per step (Baraff & Witkin 1998)
};

// How a step's result is formed; the values are node_physics.h's RULE_*.
enum class UpdateRule { runge_kutta = 0, semi_implicit_euler = 1, verlet = 2, backward_euler = 3 };

inline constexpr int kMaxStages = 4;

// Explicit Runge-Kutta: stage s is evaluated at time t + c_s dt and at the state
// s0 + dt sum_{j<s} a_sj k_j; the result is s0 + dt sum_j b_j k_j, with slopes k_j = (v_j, a_j).
struct Tableau {
  int stages = 1;
  std::array<double, kMaxStages> c{}, b{};
  std::array<std::array<double, kMaxStages>, kMaxStages> a{};
};

struct IntegratorInfo {
  Integrator id;
  std::string_view name;
  std::string_view paper_alias;  // the paper's name, accepted on input ("" if none)
  UpdateRule rule;
  Tableau tableau;               // runge_kutta only
  int order;                     // global order of accuracy in position
  std::string_view summary;
  int force_passes;  // per step (the tableau's stages; backward Euler: 1 evaluation + its Jacobian)
};

const std::vector<IntegratorInfo>& integrators();
const IntegratorInfo& info(Integrator i);
// Accepts names and the paper's aliases; nullopt if unknown.
std::optional<Integrator> parse_integrator(std::string_view name);
std::string integrator_names();  // "explicit-euler, semi-implicit-euler, ..." for messages

// State slots a schedule refers to: 0 = current state (input), 1.. = stage states.
// Acceleration slot j holds the force pass at state j.
struct Pass {
  enum class Op {
    force,    // accel[acc] = a(state[src], t + time_fraction * dt)
    combine,  // state[dst] = state[0] + dt sum_j weights[j] (v of state j, accel j); with
              // dst == kResult, the step's result, then the constraints
    update,   // the step's result by the schedule's one-pass rule from state 0 and accel 0, then constraints
    solve,    // the step's result by backward Euler from state 0, then constraints
  } op = Op::force;
  static constexpr int kResult = -1;
  int src = 0, acc = 0, dst = 0;
  double time_fraction = 0.0;
  std::vector<double> weights;
};

struct Schedule {
  Integrator integrator;
  UpdateRule rule;
  std::vector<Pass> passes;
  int stage_states = 0;  // extra state slots needed besides the current one
  int accel_slots = 1;
  // One force pass, then the result (a one-stage combine or a one-pass update): backends may
  // run it as one kernel or shader, with one_pass_update(rule, weight, ...).
  bool single_pass() const;
  double weight() const;  // b_0 of a one-stage Runge-Kutta scheme (1 otherwise)
};

Schedule make_schedule(Integrator i);

}  // namespace deformlab
