#include "session.hpp"

#include <cmath>
#include <stdexcept>

#include "core/run.hpp"

namespace deformlab::viewer {

Session::Session(SessionSetup s)
    : s_(std::move(s)), scene_inv_mass_(s_.model.inv_mass), extent_(s_.model.extent()), handle_(s_.params.drag) {
  pipe_ = make(*s_.entry, s_.integrator, s_.options, s_.params);
}

std::unique_ptr<Pipeline> Session::make(const PipelineEntry& e, Integrator i, const PipelineOptions& o,
                                        const Params& p) {
  if (const std::string why = e.unavailable(); !why.empty()) throw std::invalid_argument(e.name + ": " + why);
  if (const std::string why = e.unsupported(i); !why.empty()) throw std::invalid_argument(e.name + ": " + why);
  check_options(e, o);  // names and values, as `run` checks them
  validate(p, s_.model.node_count());
  auto pipe = e.make({s_.model, p, i, o});
  pipe->set_drag(handle_);
  return pipe;
}

std::string Session::replace(const PipelineEntry& e, Integrator i, const PipelineOptions& o, float dt) {
  Params p = s_.params;
  p.dt = dt;
  State st = pipe_->state();
  // Verlet's half-step velocity belongs to its own dt: another rule or step starts from (x, v).
  if (i != s_.integrator || dt != s_.params.dt) st.half_step = false;
  try {
    std::unique_ptr<Pipeline> next = make(e, i, o, p);
    next->set_state(st);
    const State back = next->state();
    carried_exactly_ = back.t == st.t && back.x == st.x && back.v == st.v && back.half_step == st.half_step;
    pipe_ = std::move(next);
  } catch (const std::exception& ex) {
    return ex.what();
  }
  s_.entry = &e;
  s_.integrator = i;
  s_.options = o;
  s_.params = p;
  return {};
}

double Session::step(int n, StepTimer* timer, Profiler* prof) {
  for (int k = 0; k < n; ++k) {
    if (prof) prof->set_step(steps_ + k + 1);
    if (timer) timer->begin();
    pipe_->step();
    if (timer) timer->end();
  }
  steps_ += n;
  time_ += n * double(s_.params.dt);
  const double disp = pipe_->max_displacement();
  if (const std::string why = divergence(disp, extent_, s_.model, s_.params, s_.integrator, steps_, time_); !why.empty())
    throw DivergenceError(steps_, why);
  return disp;
}

void Session::reset() {
  if (s_.model.inv_mass != scene_inv_mass_) {
    s_.model.inv_mass = scene_inv_mass_;
    pipe_.reset();  // it reads the model's masses when made
  }
  handle_ = s_.params.drag;
  dragged_ = -1;
  if (!pipe_) pipe_ = make(*s_.entry, s_.integrator, s_.options, s_.params);
  pipe_->set_drag(handle_);
  pipe_->set_state(rest_state(s_.model));
  steps_ = 0;
  time_ = 0.0;
}

void Session::drag(int node, Vec3f target) {
  DragHandle h{node, {{0.f, target}}, s_.params.drag.as_spring, s_.params.drag.stiffness};
  pipe_->set_drag(h);
  handle_ = h;
  dragged_ = node;
}

void Session::release() {
  handle_ = DragHandle{};
  pipe_->set_drag(handle_);
  dragged_ = -1;
}

void Session::toggle_pin(int node) {
  if (node < 0 || node >= s_.model.node_count()) throw std::invalid_argument("no node " + std::to_string(node));
  const State st = pipe_->state();
  pipe_.reset();
  float& w = s_.model.inv_mass[node];
  // A node the scene pins gets the mean inverse mass of the free nodes when freed.
  if (w != 0.f) {
    w = 0.f;
  } else if (scene_inv_mass_[node] != 0.f) {
    w = scene_inv_mass_[node];
  } else {
    double sum = 0.0;
    int count = 0;
    for (float f : scene_inv_mass_)
      if (f != 0.f) sum += f, ++count;
    w = count ? float(sum / count) : 1.f;
  }
  pipe_ = make(*s_.entry, s_.integrator, s_.options, s_.params);
  pipe_->set_state(st);
}

int nearest_node(const std::vector<Vec3f>& x, Vec3f at) {
  int best = -1;
  float best_d = 0.f;
  for (int i = 0; i < int(x.size()); ++i)
    if (const float d = norm(x[i] - at); best < 0 || d < best_d) best = i, best_d = d;
  return best;
}

Vec3f on_plane(Vec3f o, Vec3f d, Vec3f point, Vec3f n) {
  const float den = dot(d, n);
  if (std::abs(den) < 1e-6f) return point;
  return o + d * (dot(point - o, n) / den);
}

}  // namespace deformlab::viewer
