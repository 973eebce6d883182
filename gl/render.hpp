// Drawing a state into an offscreen framebuffer (points, or a lit surface: a cloth grid's with
// normals from its neighbours, a mesh's triangles with flat normals, all computed on the GPU), PNG frames and an MP4 through ffmpeg when it is installed.
// Works for every pipeline: GL pipelines are drawn from their own buffers, others uploaded.
#pragma once
#include <cstdint>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/model.hpp"
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
  // side (a model dropped onto it stays in view).
  std::optional<float> ground;
};

class Renderer {
 public:
  // The camera frames the model's rest positions and stays fixed.
  Renderer(const Model& m, RenderOptions o = {});
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Draws the pipeline's current state (a GL pipeline's buffers, any other's state()).
  void draw(Pipeline& p);
  void draw(const State& s);
  // RGBA8, rows from the top.
  std::vector<std::uint8_t> pixels();
  void write_png(const std::filesystem::path& file);
  // GPU time of each draw since the last call, ms, and how it was measured.
  std::vector<double> take_draw_ms();
  std::string timing_method() const;
  int width() const;
  int height() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Frames of a run: DIR/frame_<step>.png every `every` steps and at the end, then
// DIR/frames.mp4 through ffmpeg if it is installed.
class FrameWriter {
 public:
  FrameWriter(const Model& m, std::filesystem::path dir, int every, RenderOptions o = {});
  void after_step(Pipeline& p, int step);     // writes a frame when step % every == 0
  void finish(Pipeline& p, int last_step);  // the final frame (if not written), then the MP4
  nlohmann::json manifest() const;          // frames written, render times, how timed

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
