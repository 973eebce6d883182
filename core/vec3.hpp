// A small 3-vector usable from host C++ and CUDA device code alike, so that the per-node
// physics (node_physics.h, through physics.hpp) exists once for every backend.
#pragma once
#include <cmath>

#if defined(__CUDACC__)
#define DL_HD __host__ __device__ __forceinline__
#else
#define DL_HD inline
#endif

namespace deformlab {

template <class T>
struct Vec3 {
  T x{}, y{}, z{};

  template <class U>
  DL_HD explicit operator Vec3<U>() const { return {U(x), U(y), U(z)}; }

  DL_HD Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
  DL_HD Vec3& operator-=(const Vec3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
  DL_HD Vec3& operator*=(T s) { x *= s; y *= s; z *= s; return *this; }
  DL_HD T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  DL_HD const T& operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
};

template <class T> DL_HD Vec3<T> operator+(Vec3<T> a, const Vec3<T>& b) { return a += b; }
template <class T> DL_HD Vec3<T> operator-(Vec3<T> a, const Vec3<T>& b) { return a -= b; }
template <class T> DL_HD Vec3<T> operator-(const Vec3<T>& a) { return {-a.x, -a.y, -a.z}; }
template <class T> DL_HD Vec3<T> operator*(Vec3<T> a, T s) { return a *= s; }
template <class T> DL_HD Vec3<T> operator*(T s, Vec3<T> a) { return a *= s; }
template <class T> DL_HD bool operator==(const Vec3<T>& a, const Vec3<T>& b) {
  return a.x == b.x && a.y == b.y && a.z == b.z;
}
template <class T> DL_HD T dot(const Vec3<T>& a, const Vec3<T>& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <class T> DL_HD Vec3<T> cross(const Vec3<T>& a, const Vec3<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class T> DL_HD T norm(const Vec3<T>& a) { return std::sqrt(dot(a, a)); }
template <class T> DL_HD T length(const Vec3<T>& a) { return norm(a); }  // GLSL's name
// Conversion between precisions (also where a functional cast would be read as aggregate init).
template <class U, class T> DL_HD Vec3<U> vec3_cast(const Vec3<T>& a) { return {U(a.x), U(a.y), U(a.z)}; }

template <class T>
DL_HD bool is_finite(T a) {
#if defined(__CUDA_ARCH__)
  return isfinite(a);
#else
  return std::isfinite(a);
#endif
}

using Vec3f = Vec3<float>;
using Vec3d = Vec3<double>;

}  // namespace deformlab
