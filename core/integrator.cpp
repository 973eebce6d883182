#include "integrator.hpp"

#include <stdexcept>

#include "physics.hpp"

namespace deformlab {

static_assert(int(UpdateRule::runge_kutta) == RULE_RUNGE_KUTTA &&
              int(UpdateRule::semi_implicit_euler) == RULE_SEMI_IMPLICIT_EULER &&
              int(UpdateRule::verlet) == RULE_VERLET);

namespace {

Tableau euler() {
  Tableau t;
  t.b[0] = 1.0;
  return t;
}
Tableau midpoint() {
  Tableau t;
  t.stages = 2;
  t.c = {0.0, 0.5};
  t.a[1][0] = 0.5;
  t.b = {0.0, 1.0};
  return t;
}
Tableau kutta3() {
  Tableau t;
  t.stages = 3;
  t.c = {0.0, 0.5, 1.0};
  t.a[1][0] = 0.5;
  t.a[2][0] = -1.0;
  t.a[2][1] = 2.0;
  t.b = {1.0 / 6, 4.0 / 6, 1.0 / 6};
  return t;
}
Tableau classic4() {
  Tableau t;
  t.stages = 4;
  t.c = {0.0, 0.5, 0.5, 1.0};
  t.a[1][0] = 0.5;
  t.a[2][1] = 0.5;
  t.a[3][2] = 1.0;
  t.b = {1.0 / 6, 2.0 / 6, 2.0 / 6, 1.0 / 6};
  return t;
}

IntegratorInfo entry(Integrator id, std::string_view name, std::string_view alias, UpdateRule rule, Tableau t, int order,
                     std::string_view summary) {
  return {id, name, alias, rule, t, order, summary, rule == UpdateRule::runge_kutta ? t.stages : 1};
}

}  // namespace

const std::vector<IntegratorInfo>& integrators() {
  using R = UpdateRule;
  static const std::vector<IntegratorInfo> all = {
      entry(Integrator::explicit_euler, "explicit-euler", "", R::runge_kutta, euler(), 1,
       "forward Euler; unstable without damping"),
      entry(Integrator::semi_implicit_euler, "semi-implicit-euler", "implicit-euler", R::semi_implicit_euler, Tableau{}, 1,
       "symplectic Euler (the paper's \"implicit Euler\", eq. 7)"),
      entry(Integrator::midpoint, "midpoint", "", R::runge_kutta, midpoint(), 2, "RK2, forces re-evaluated at the half step"),
      entry(Integrator::rk3, "rk3", "", R::runge_kutta, kutta3(), 3,
       "Kutta's third-order Runge-Kutta, three force evaluations (its third stage combines the first two)"),
      entry(Integrator::rk4, "rk4", "", R::runge_kutta, classic4(), 4,
       "classical Runge-Kutta, four force evaluations (not the paper's eqs. 10-11)"),
      entry(Integrator::verlet, "verlet", "midpoint-verlet", R::verlet, Tableau{}, 2,
       "Verlet (the paper's eq. 6; its eq. 9 is not a known scheme) as a leapfrog; first order with damping"),
      entry(Integrator::backward_euler, "backward-euler", "", R::backward_euler, Tableau{}, 1,
       "implicit Euler, linearised, sparse conjugate gradient (Baraff & Witkin)"),
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
  return passes.size() == 2 && passes[0].op == Pass::Op::force &&
         (passes[1].op == Pass::Op::update || (passes[1].op == Pass::Op::combine && passes[1].dst == Pass::kResult));
}

double Schedule::weight() const {
  return single_pass() && passes[1].op == Pass::Op::combine ? passes[1].weights[0] : 1.0;
}

Schedule make_schedule(Integrator i) {
  const IntegratorInfo& in = info(i);
  Schedule s{.integrator = i, .rule = in.rule, .passes = {}, .stage_states = 0, .accel_slots = 1};
  Pass p;
  switch (in.rule) {
    case UpdateRule::runge_kutta: {
      const Tableau& t = in.tableau;
      s.stage_states = t.stages - 1;
      s.accel_slots = t.stages;
      for (int st = 0; st < t.stages; ++st) {
        Pass f;
        f.op = Pass::Op::force;
        f.src = f.acc = st;
        f.time_fraction = t.c[st];
        s.passes.push_back(f);
        Pass c;
        c.op = Pass::Op::combine;
        const bool last = st + 1 == t.stages;
        c.dst = last ? Pass::kResult : st + 1;
        for (int j = 0; j <= st; ++j) c.weights.push_back(last ? t.b[j] : t.a[st + 1][j]);
        s.passes.push_back(c);
      }
      break;
    }
    case UpdateRule::semi_implicit_euler:
    case UpdateRule::verlet:
      p.op = Pass::Op::force;
      s.passes.push_back(p);
      p.op = Pass::Op::update;
      s.passes.push_back(p);
      break;
    case UpdateRule::backward_euler:
      p.op = Pass::Op::solve;  // its force evaluation (f0) uses accel slot 0
      s.passes.push_back(p);
      break;
  }
  return s;
}

}  // namespace deformlab
