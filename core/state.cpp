#include "state.hpp"

#include "model.hpp"

namespace deformlab {

State rest_state(const Model& m) {
  State s;
  s.x = m.rest_position;
  s.v.assign(m.rest_position.size(), Vec3f{});
  return s;
}

}  // namespace deformlab
