#include "energy.hpp"

namespace deformlab {

Energy energy(const Model& m, const Params& p, const State& s) {
  Energy e;
  const Vec3d g(p.gravity), wind(p.wind);
  for (int i = 0; i < m.node_count(); ++i) {
    if (m.inv_mass[i] == 0.f) continue;
    const double mass = 1.0 / m.inv_mass[i];
    const Vec3d v(s.v[i]), x(s.x[i]);
    e.kinetic += 0.5 * mass * dot(v, v);
    e.field -= dot(g * mass + wind, x);
  }
  for (int k = 0; k < m.spring_count(); ++k) {
    const double stretch = norm(Vec3d(s.x[m.spring_i[k]]) - Vec3d(s.x[m.spring_j[k]])) - m.rest_length[k];
    e.spring += 0.5 * m.stiffness[int(m.kind[k])] * stretch * stretch;
  }
  return e;
}

}  // namespace deformlab
