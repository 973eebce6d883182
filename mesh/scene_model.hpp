// The model a scene names: a cloth grid or lattice from the core builders, or a mesh file
// read, repaired, filled and reordered as the scene says; pins applied.
#pragma once
#include "core/scene.hpp"

namespace deformlab {

// Throws std::invalid_argument for sizes, files or settings that cannot be built, and for a
// mesh whose model does not fit in host memory.
Model build_model(const Scene& s);

}  // namespace deformlab
