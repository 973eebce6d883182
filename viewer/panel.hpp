// The viewer's panel (Dear ImGui): the stages switched live, the run's clocks and the keys.
// Every change it makes comes back as an Event, so that it is applied, recorded and replayed
// like the keys and the mouse.
#pragma once
#include <string>
#include <vector>

#include "core/profiler.hpp"
#include "gl/render.hpp"
#include "script.hpp"
#include "session.hpp"

namespace deformlab::viewer {

inline constexpr int kPanelWidth = 360;  // pixels at the window's right edge

// What the panel shows and keeps between frames.
struct PanelState {
  int steps_per_frame = 10;
  bool profile = true;  // stage spans (CUDA pipelines then run pass by pass, without graphs)
  bool wireframe = false, points = false;
  int colour = 0;                     // gl::Renderer::Colour: plain, speed, strain
  float scale[3] = {1.f, 1.f, 0.1f};  // red at: -, m/s, strain
  std::string option_text, dt_text;
};

// Measured over the last half second (none yet in the first).
struct Stats {
  bool measured = false;
  double steps_per_s = 0, frames_per_s = 0;  // host clock
  double step_ms = 0;                        // median, on step_clock
  std::string step_clock;
  double draw_ms = 0;  // median, on draw_clock
  std::string draw_clock;
  double displacement = 0;  // largest node displacement of the last step, m
  std::vector<Profiler::Stage> stages;
  std::string drawn_from;  // how the state reaches the renderer
};

struct PanelActions {
  std::vector<Event> events;  // keys, settings, screenshots
  bool profile_changed = false;
};

PanelActions show_panel(PanelState& p, const Stats& s, Session& session, const std::string& message, bool paused,
                        bool recording);

}  // namespace deformlab::viewer
