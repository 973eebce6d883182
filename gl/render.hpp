// Drawing a state into an offscreen framebuffer (points, or a lit surface: a cloth grid's with
// normals from its neighbours, a mesh's triangles with flat normals, all computed on the GPU)
// with the scene's ground and spheres, PNG frames and an MP4 through ffmpeg when it is installed.
// Works for every pipeline: GL pipelines are drawn from their own buffers, others uploaded.
#pragma once
#include <cstdint>
#include <array>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/model.hpp"
#include "core/params.hpp"
#include "core/pipeline.hpp"
#include "core/state.hpp"

namespace deformlab::gl {

struct RenderOptions {
  int width = 1024, height = 1024;  // the paper's output size
  // automatic: a surface for cloth grids and for meshes (their triangles, a volume's boundary)
  enum class Mode { automatic, points, surface } mode = Mode::automatic;
  // Texels of position data one draw call reads (0: the driver's texture buffer limit); a
  // larger model is drawn in bands. A cloth wider than twice the frame is drawn every
  // stride-th row and column.
  std::int64_t band_texels = 0;
  // The scene's ground height: the camera frames down to it and half the model's width to each
  // side (a model dropped onto it stays in view). The ground and the spheres are drawn where
  // the model does not hide them, and left out of surface_at's picking.
  std::optional<float> ground;
  std::vector<Sphere> spheres;
};

// `o` with the scene's obstacles (its ground and spheres).
RenderOptions with_obstacles(RenderOptions o, const Params& p);

// A perspective camera: where it is, what it looks at, its up direction and vertical field of
// view (radians).
struct Camera {
  Vec3f eye, target, up{0.f, 1.f, 0.f};
  float fovy = 0.8f;

  // Unit axes: where it looks, its right and its up (those of the view matrix).
  struct Axes {
    Vec3f forward, right, up;
  };
  Axes axes() const;
  // The ray through pixel (px, py) (from the top left; pixel centres at .5) of a w x h view:
  // the eye and a unit direction.
  std::pair<Vec3f, Vec3f> ray(double px, double py, int w, int h) const;
  // The pixel (from the top left) where `x` appears in a w x h view; NaN behind the eye.
  std::array<double, 2> pixel(Vec3f x, int w, int h) const;
};

// In front of and above the model's rest shape and the space below it where a pinned model
// hangs, looking at the centre of both; with a ground, down to it and half the model's width
// to each side (a model dropped onto it stays in view).
Camera framing(const Model& m, std::optional<float> ground);

class Renderer {
 public:
  // The camera starts at framing(m, o.ground).
  Renderer(const Model& m, RenderOptions o = {});
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Draws the pipeline's current state (a GL pipeline's buffers, any other's state()).
  void draw(Pipeline& p);
  // Draws positions from a GL buffer: a vec4 per node (w unused).
  void draw_positions(unsigned buffer);
  void draw(const State& s);
  // RGBA8, rows from the top.
  std::vector<std::uint8_t> pixels();
  void write_png(const std::filesystem::path& file);
  // GPU time of each draw since the last call, ms, and how it was measured.
  std::vector<double> take_draw_ms();
  std::string timing_method() const;
  int width() const;
  int height() const;

  // For interactive views.
  const Camera& camera() const;
  void set_camera(const Camera& c);
  void set_mode(RenderOptions::Mode m);  // throws std::invalid_argument where the model has no surface
  void set_wireframe(bool on);           // surfaces as their edges
  // Colour by speed (each node's displacement since the previous draw over the simulated time
  // between them, set_time) or by strain (a cloth node's larger relative change of its spans
  // along the grid's two directions, a mesh triangle's largest of its edges), from blue at 0
  // to red at `scale` (m/s, or a fraction) and above.
  enum class Colour { plain, speed, strain };
  void set_colour(Colour c, float scale);
  void set_time(double t);  // the simulated time of the state drawn next
  void resize(int width, int height);
  unsigned framebuffer() const;          // the GL framebuffer drawn into (colour attachment 0)
  // The point of the model drawn under pixel (px, py) (from the top left) in the last frame,
  // from its depth buffer; none over the background.
  std::optional<Vec3f> surface_at(double px, double py);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Frames of a run: DIR/frame_<step>.png every `every` steps and at the end, then
// DIR/frames.mp4 through ffmpeg if it is installed.
class FrameWriter {
 public:
  FrameWriter(const Model& m, std::filesystem::path dir, int every, RenderOptions o = {});
  bool due(int step) const { return step % every_ == 0; }
  void after_step(Pipeline& p, int step);       // writes a frame when due(step)
  void write_last(Pipeline& p, int last_step);  // the final frame, if not written
  void finish(Pipeline& p, int last_step);      // write_last, then the MP4
  nlohmann::json manifest() const;              // frames written, render times, how timed

 private:
  void write(Pipeline& p, int step);
  Renderer r_;
  std::filesystem::path dir_;
  int every_, last_written_ = -1, frames_ = 0;
  std::vector<double> draw_ms_;
  std::string movie_;
};

// For a run's manifest: GL vendor, renderer, version and platform and, for a GL pipeline,
// how its shaders find neighbours; null when no GL context was made.
nlohmann::json run_manifest(Pipeline& p);

}  // namespace deformlab::gl
