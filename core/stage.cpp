#include "stage.hpp"

namespace deformlab {

void run_passes(const Schedule& s, double t, double dt, ForceStage& f, UpdateStage& u) {
  for (const Pass& pass : s.passes) {
    if (pass.op == Pass::Op::force) f.forces(pass.src, pass.acc, t + pass.time_fraction * dt);
    else u.update(pass);
  }
}

}  // namespace deformlab
