#include "energy.hpp"

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
  for (int k = 0; k < m.spring_count(); ++k)
    e.spring += P::spring_energy(Vec3d(s.x[m.spring_i[k]]), Vec3d(s.x[m.spring_j[k]]), m.spring_k(k), m.rest_length[k]);
  return e;
}

}  // namespace deformlab
