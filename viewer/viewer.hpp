// `deformlab view`: the simulation in a window, stepped continuously, poked with the mouse,
// its stages switched and timed live from a panel.
#pragma once
#include <string>
#include <vector>

#include "panel.hpp"
#include "script.hpp"
#include "session.hpp"
#include "window.hpp"

namespace deformlab::viewer {

struct ViewOptions {
  int steps_per_frame = 10;
  std::vector<Event> script;  // events to replay (script.hpp)
  std::string save_script;  // where to save this session's events at the end
  std::string record;       // an MP4 recorded from the first frame
  double seconds = 0.0;     // with `record`: this many seconds of video (30 frames a second), then quit
  int frames = 0;           // quit after this many frames (0: when the window closes)
  std::string summary;      // a JSON summary of the session written at the end
};

// Runs the viewer until the window closes or an option or the script ends it; returns the
// process exit code (0; 1 when a screenshot, recording or summary could not be written).
int run(Window& w, Session& s, const ViewOptions& o);

}  // namespace deformlab::viewer
