// A simulation as the viewer runs it: one model and scene, a pipeline that can be replaced
// while the state carries over (another pipeline, integrator, option or dt), the drag handle
// that picking moves, pins toggled on nodes, and divergence caught where it shows.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "core/model.hpp"
#include "core/params.hpp"
#include "core/pipeline.hpp"

namespace deformlab::viewer {

struct SessionSetup {
  Model model;
  Params params;
  const PipelineEntry* entry = nullptr;
  Integrator integrator = Integrator::semi_implicit_euler;
  PipelineOptions options;
};

class Session {
 public:
  explicit Session(SessionSetup s);

  Pipeline& pipeline() { return *pipe_; }
  const Model& model() const { return s_.model; }
  const Params& params() const { return s_.params; }
  const PipelineEntry& entry() const { return *s_.entry; }
  Integrator integrator() const { return s_.integrator; }
  const PipelineOptions& options() const { return s_.options; }
  int steps() const { return steps_; }
  double time() const { return time_; }

  // Makes a pipeline of `e` with `i`, `o` and `dt` the current one, from the current state.
  // Empty on success; else why not, and the current pipeline stays.
  std::string replace(const PipelineEntry& e, Integrator i, const PipelineOptions& o, float dt);
  // Whether the last replacement's state, read back from the new pipeline, equalled the one
  // handed over bit for bit (checked at every replacement).
  bool carried_exactly() const { return carried_exactly_; }

  // Runs n steps, each timed by `timer` (one of the pipeline's, or null) and numbered in
  // `prof` (the pipeline's profiler, or null), then checks the largest displacement of the
  // last one: returns it, or throws DivergenceError with the run loop's message (the session
  // then holds the diverged state).
  double step(int n, StepTimer* timer = nullptr, Profiler* prof = nullptr);
  // The rest state, the scene's drag handle and pins.
  void reset();

  // The drag handle of picking: `node` pulled towards `target` (the scene's mode: hard, or a
  // spring of its stiffness); release() removes it.
  void drag(int node, Vec3f target);
  void release();
  int dragged() const { return dragged_; }
  // Pins a free node where it is, or frees a node pinned here or by the scene.
  void toggle_pin(int node);

 private:
  std::unique_ptr<Pipeline> make(const PipelineEntry& e, Integrator i, const PipelineOptions& o, const Params& p);

  SessionSetup s_;
  std::vector<float> scene_inv_mass_;  // the scene's, for freeing and reset
  float extent_;                       // the model's (divergence's bound)
  std::unique_ptr<Pipeline> pipe_;
  DragHandle handle_;  // the pipeline's: the scene's until picking replaces it
  int steps_ = 0, dragged_ = -1;
  double time_ = 0.0;
  bool carried_exactly_ = true;
};

// The node nearest the point `at` (the surface under the cursor: the nearest node of the
// triangle there); -1 for no nodes.
int nearest_node(const std::vector<Vec3f>& x, Vec3f at);

// Where no surface is under the cursor: the node whose image lies nearest pixel (px, py),
// within `radius_px`; -1 when none. `pixel` maps a position to its pixel (NaN off screen).
template <class ToPixel>
int pick_node(const std::vector<Vec3f>& x, double px, double py, double radius_px, ToPixel pixel) {
  int best = -1;
  double best_d2 = radius_px * radius_px;
  for (int i = 0; i < int(x.size()); ++i) {
    const auto p = pixel(x[i]);
    const double d2 = (p[0] - px) * (p[0] - px) + (p[1] - py) * (p[1] - py);
    if (d2 <= best_d2) best = i, best_d2 = d2;
  }
  return best;
}

// Where the ray (origin o, direction d) meets the plane through `point` with normal `n`;
// `point` itself where the ray runs along the plane.
Vec3f on_plane(Vec3f o, Vec3f d, Vec3f point, Vec3f n);

}  // namespace deformlab::viewer
