// The viewer's input as data: what the mouse, the keys and the panel did at which frame, so a
// session can be saved (--save-script) and replayed (--script) with the same steps per frame.
//   {"events": [{"frame": 10, "event": "press", "x": 400, "y": 300, "button": "left"},
//               {"frame": 11, "event": "move", "x": 420, "y": 280}, {"frame": 30, "event": "release"},
//               {"frame": 40, "event": "set", "pipeline": "omp"}, {"frame": 60, "event": "quit"}]}
#pragma once
#include <map>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

namespace deformlab::viewer {

struct Event {
  enum class Kind { press, move, release, scroll, key, set, screenshot, quit } kind = Kind::move;
  int frame = 0;
  double x = 0, y = 0;          // cursor, pixels from the window's top left (press, move); scroll offset
  std::string button = "left";  // press: left, right, middle
  bool shift = false;           // press: with shift held (left: toggles a pin)
  std::string key;              // key: its name, one of kKeys
  // set: any of "pipeline", "integrator", "dt", "options" (NAME=VALUE, ...) to change.
  std::map<std::string, std::string> settings;
  std::string file;  // screenshot: the PNG to write
};

// The keys the viewer acts on, by the names scripts give them (the panel lists what each does);
// the window passes on no others.
inline const std::vector<std::string> kKeys = {"space", "backspace", "c", "m", "n", "p", "r", "v", "w"};

// Throws std::invalid_argument naming the file and the first bad event.
std::vector<Event> read_script(const std::string& path);
void write_script(const std::string& path, const std::vector<Event>& events);

nlohmann::json to_json(const Event& e);

}  // namespace deformlab::viewer
