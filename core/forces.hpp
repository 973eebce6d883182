// The force and constraint formulas, written once for every C++ and CUDA backend
// (the GLSL shaders carry their own copy of the same arithmetic).
#pragma once
#include "vec3.hpp"

namespace deformlab {

// Force on node i from a spring to node j (Hooke + damping along the spring axis):
//   f_i = -(k (|d| - l) + kd (v_i - v_j).u) u,  d = x_i - x_j,  u = d / |d|.
// (The paper's eq. (2) drops the minus sign.) Coincident nodes exert no force.
template <class T>
DL_HD Vec3<T> spring_force(const Vec3<T>& xi, const Vec3<T>& xj, const Vec3<T>& vi,
                           const Vec3<T>& vj, T k, T kd, T rest) {
  const Vec3<T> d = xi - xj;
  const T len = norm(d);
  if (len == T(0)) return {};
  const Vec3<T> u = d * (T(1) / len);
  T s = k * (len - rest);
  if (kd != T(0)) s += kd * dot(vi - vj, u);  // skipped when undamped: same result, fewer instructions
  return u * (-s);
}

// External and damping forces on a free node: wind - c v (+ drag spring pull, if any).
// Acceleration = inv_mass * (springs + external) + gravity.
template <class T>
DL_HD Vec3<T> acceleration(const Vec3<T>& spring_sum, const Vec3<T>& v, T inv_mass, T c,
                           const Vec3<T>& wind, const Vec3<T>& gravity) {
  return (spring_sum + wind - v * c) * inv_mass + gravity;
}

// Ground plane y >= h: clamp the position, remove the velocity into the ground.
template <class T>
DL_HD void ground_constraint(Vec3<T>& x, Vec3<T>& v, T h) {
  if (x.y < h) {
    x.y = h;
    if (v.y < T(0)) v.y = T(0);
  }
}

// Sphere collider: a node inside is projected onto the surface (paper eq. 13, corrected)
// and its inward normal velocity removed. A node at the exact centre goes out along +y.
template <class T>
DL_HD void sphere_constraint(Vec3<T>& x, Vec3<T>& v, const Vec3<T>& c, T r) {
  const Vec3<T> d = x - c;
  const T len = norm(d);
  if (len >= r) return;
  const Vec3<T> n = len > T(0) ? d * (T(1) / len) : Vec3<T>{T(0), T(1), T(0)};
  x = c + n * r;
  const T vn = dot(v, n);
  if (vn < T(0)) v -= n * vn;
}

}  // namespace deformlab
