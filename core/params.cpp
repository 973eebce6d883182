#include "params.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace deformlab {

Vec3f DragHandle::target(double t) const {
  if (path.empty()) return {};
  if (t <= path.front().t) return path.front().position;
  for (std::size_t k = 1; k < path.size(); ++k) {
    if (t <= path[k].t) {
      const auto& a = path[k - 1];
      const auto& b = path[k];
      const float s = float((t - a.t) / double(b.t - a.t));
      return a.position + s * (b.position - a.position);
    }
  }
  return path.back().position;
}

namespace {
bool finite(const Vec3f& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
[[noreturn]] void bad(const std::string& what) { throw std::invalid_argument(what); }
}  // namespace

double Params::runaway_distance(float extent) const {
  return double(runaway_factor) * std::max(double(extent), 1e-3);
}

void validate(const Params& p, int node_count) {
  if (!(p.dt > 0.f) || !std::isfinite(p.dt)) bad("dt must be a positive finite number of seconds");
  if (!finite(p.gravity)) bad("gravity must be finite");
  if (!(p.damping >= 0.f) || !std::isfinite(p.damping)) bad("damping must be >= 0");
  if (!finite(p.wind)) bad("wind must be finite");
  if (p.ground && !std::isfinite(*p.ground)) bad("ground height must be finite");
  for (const auto& s : p.spheres)
    if (!finite(s.center) || !(s.radius > 0.f) || !std::isfinite(s.radius))
      bad("a sphere needs a finite centre and a positive radius");
  validate(p.drag, node_count);
  if (!(p.threshold > 0.f) || !std::isfinite(p.threshold)) bad("threshold must be positive");
  if (p.min_steps < 0) bad("min_steps must be >= 0");
  if (p.max_steps < 1) bad("max_steps (--steps) must be at least 1");
  if (p.check_every < 1) bad("check_every must be at least 1");
  if (!(p.runaway_factor > 0.f)) bad("runaway_factor must be positive");
}

void validate(const DragHandle& d, int node_count) {
  if (d.node >= node_count)
    bad("drag node " + std::to_string(d.node) + " is outside the model (0.." + std::to_string(node_count - 1) + ")");
  if (d.node >= 0 && d.path.empty()) bad("the drag handle needs at least one keyframe");
  for (std::size_t k = 0; k < d.path.size(); ++k) {
    if (!finite(d.path[k].position) || !std::isfinite(d.path[k].t))
      bad("drag keyframe " + std::to_string(k) + " is not finite");
    if (k > 0 && !(d.path[k].t > d.path[k - 1].t))
      bad("drag keyframe times must increase (keyframe " + std::to_string(k) + ")");
  }
  if (d.as_spring && !(d.stiffness > 0.f)) bad("drag spring stiffness must be positive");
}

}  // namespace deformlab
