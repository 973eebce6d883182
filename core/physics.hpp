// The per-node physics of core/node_physics.h for C++ and CUDA: Physics<float> for the float
// pipelines and kernels, Physics<double> for the reference and the energies.
#pragma once
#include <cmath>
#include <limits>

#include "vec3.hpp"

namespace deformlab {

template <class Real>
struct Physics {
  using real = Real;
  using vec3 = Vec3<Real>;
#define DL_FN static DL_HD
#define CREF(T) const T&
#define OUT(T) T&
#define INOUT(T) T&
#define VEC3(a, b, c) vec3{a, b, c}
#define DL_FINITE(a) is_finite(a)
#define DL_INFINITY std::numeric_limits<Real>::infinity()
#define DL_RECIP(a) (real(1) / (a))
#define DL_RSQRT(a) (real(1) / std::sqrt(a))
#define DL_DOT(a, b) dot(a, b)
#define DL_LENGTH(a) length(a)
#define DL_PRECISE
#include "node_physics.h"
#undef DL_FN
#undef CREF
#undef OUT
#undef INOUT
#undef VEC3
#undef DL_FINITE
#undef DL_INFINITY
#undef DL_RECIP
#undef DL_RSQRT
#undef DL_DOT
#undef DL_LENGTH
#undef DL_PRECISE
};

}  // namespace deformlab
