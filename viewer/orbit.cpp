#include "orbit.hpp"

#include <algorithm>
#include <cmath>

namespace deformlab::viewer {
namespace {

// `v` turned by `angle` about the unit axis `k` (Rodrigues).
Vec3f rotate(Vec3f v, Vec3f k, float angle) {
  const float c = std::cos(angle), s = std::sin(angle);
  return v * c + cross(k, v) * s + k * (dot(k, v) * (1.f - c));
}

Vec3f unit(Vec3f v) { return v * (1.f / norm(v)); }

}  // namespace

void orbit(gl::Camera& c, float yaw, float pitch) {
  const Vec3f up = unit(c.up);
  Vec3f d = rotate(c.eye - c.target, up, -yaw);
  const float now = std::acos(std::clamp(dot(unit(d), up), -1.f, 1.f));  // from the up axis
  const float limit = 0.05f;
  pitch = std::clamp(pitch, now - (3.14159265f - limit), now - limit);
  const Vec3f right = unit(cross(up, d));
  d = rotate(d, right, -pitch);
  c.eye = c.target + d;
}

void pan(gl::Camera& c, float dx, float dy, int h) {
  const auto [f, s, u] = c.axes();
  const float per_px = 2.f * norm(c.target - c.eye) * std::tan(c.fovy / 2) / float(h);
  const Vec3f move = s * (-dx * per_px) + u * (dy * per_px);
  c.eye = c.eye + move;
  c.target = c.target + move;
}

void zoom(gl::Camera& c, float factor) { c.eye = c.target + (c.eye - c.target) * factor; }

}  // namespace deformlab::viewer
