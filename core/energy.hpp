// Energies of a state, for physics checks and runs' energy.csv (deformlab run --energy K):
// kinetic, spring potential, and the potential of gravity and wind (constant force fields).
// Pinned nodes carry no kinetic energy; the drag handle's spring and the constraints' contacts
// are not counted.
#pragma once
#include "model.hpp"
#include "params.hpp"
#include "state.hpp"

namespace deformlab {

struct Energy {
  double kinetic = 0;  // sum m |v|^2 / 2 over free nodes, J
  double spring = 0;   // sum k (|d| - l)^2 / 2 over springs, J
  double field = 0;    // -sum (m g + wind) . x over free nodes, J
  double total() const { return kinetic + spring + field; }
};

Energy energy(const Model& m, const Params& p, const State& s);

// A run's energies after one of its steps (0: the state it starts from).
struct EnergySample {
  int step = 0;
  double t = 0;  // s
  Energy e;
};

}  // namespace deformlab
