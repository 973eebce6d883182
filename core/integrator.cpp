#include "integrator.hpp"

#include <stdexcept>

namespace deformlab {

const std::vector<IntegratorInfo>& integrators() {
  static const std::vector<IntegratorInfo> all = {
      {Integrator::explicit_euler, "explicit-euler", "", 1, 1, "forward Euler; unstable without damping"},
      {Integrator::semi_implicit_euler, "semi-implicit-euler", "implicit-euler", 1, 1,
       "symplectic Euler (the paper's \"implicit Euler\", eq. 7)"},
      {Integrator::midpoint, "midpoint", "", 2, 2, "RK2, forces re-evaluated at the half step"},
      {Integrator::rk4, "rk4", "", 4, 4, "classical Runge-Kutta, four force evaluations (not the paper's eqs. 10-11)"},
      {Integrator::verlet, "verlet", "midpoint-verlet", 1, 2, "position Verlet (the paper's eq. 6; its eq. 9 is not a known scheme)"},
      {Integrator::backward_euler, "backward-euler", "", 1, 1,
       "implicit Euler, linearised, sparse conjugate gradient (Baraff & Witkin)"},
  };
  return all;
}

const IntegratorInfo& info(Integrator i) {
  for (const auto& e : integrators())
    if (e.id == i) return e;
  throw std::logic_error("unknown integrator");
}

std::optional<Integrator> parse_integrator(std::string_view name) {
  for (const auto& e : integrators())
    if (name == e.name || (!e.paper_alias.empty() && name == e.paper_alias)) return e.id;
  return std::nullopt;
}

std::string integrator_names() {
  std::string s;
  for (const auto& e : integrators()) {
    if (!s.empty()) s += ", ";
    s += e.name;
  }
  return s;
}

bool Schedule::single_pass() const {
  return passes.size() == 2 && passes[0].op == Pass::Op::force && passes[1].op == Pass::Op::fused;
}

namespace {
Pass force_pass(int src, int acc, double time_fraction) {
  Pass p;
  p.op = Pass::Op::force;
  p.src = src; p.acc = acc; p.time_fraction = time_fraction;
  return p;
}
Pass stage_pass(int src, int dst, double coef) {  // reads accel slot `src`
  Pass p;
  p.op = Pass::Op::stage;
  p.src = src; p.dst = dst; p.acc = src; p.coef = coef;
  return p;
}
Pass update_pass(Pass::Op op) {
  Pass p;
  p.op = op;
  return p;
}
Pass combine_pass(std::vector<double> weights) {
  Pass p;
  p.op = Pass::Op::combine;
  p.weights = std::move(weights);
  return p;
}
}  // namespace

Schedule make_schedule(Integrator i) {
  Schedule s{.integrator = i, .passes = {}, .stage_states = 0, .accel_slots = 1};
  switch (i) {
    case Integrator::explicit_euler:
    case Integrator::semi_implicit_euler:
    case Integrator::verlet:
      s.passes = {force_pass(0, 0, 0.0), update_pass(Pass::Op::fused)};
      break;
    case Integrator::midpoint:
      s.stage_states = 1;
      s.accel_slots = 2;
      s.passes = {force_pass(0, 0, 0.0), stage_pass(0, 1, 0.5), force_pass(1, 1, 0.5), combine_pass({0.0, 1.0})};
      break;
    case Integrator::rk4:
      s.stage_states = 3;
      s.accel_slots = 4;
      s.passes = {force_pass(0, 0, 0.0), stage_pass(0, 1, 0.5), force_pass(1, 1, 0.5),
                  stage_pass(1, 2, 0.5), force_pass(2, 2, 0.5), stage_pass(2, 3, 1.0),
                  force_pass(3, 3, 1.0), combine_pass({1.0 / 6, 2.0 / 6, 2.0 / 6, 1.0 / 6})};
      break;
    case Integrator::backward_euler:
      s.passes = {update_pass(Pass::Op::solve)};  // its force evaluation (f0) uses accel slot 0
      break;
  }
  return s;
}

}  // namespace deformlab
