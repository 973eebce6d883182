#include "energy.hpp"

#include "springs.hpp"
#include "step_params.hpp"

namespace deformlab {

Energy energy(const Model& m, const Params& p, const State& s) {
  using P = Physics<double>;
  const P::StepParams sp = step_params<double>(m, p);
  Energy e;
  for (int i = 0; i < m.node_count(); ++i) {
    e.kinetic += P::kinetic_energy(m.inv_mass[i], Vec3d(s.v[i]));
    e.field += P::field_energy(sp, m.inv_mass[i], Vec3d(s.x[i]));
  }
  for_each_spring(m, [&](const SpringRef& r) {
    e.spring += P::spring_energy(Vec3d(s.x[r.i]), Vec3d(s.x[r.j]), r.k, r.rest);
  });
  return e;
}

}  // namespace deformlab
