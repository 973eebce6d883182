#include "script.hpp"

#include <cfloat>
#include <climits>
#include <cmath>
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <string>

#include "core/integrator.hpp"
#include "core/json_file.hpp"
#include "experiments/pipelines.hpp"
#include "experiments/output.hpp"

namespace deformlab::viewer {
namespace {

// Each kind of event with the keys it takes besides "frame" and "event".
struct KindKeys {
  const char* name;
  Event::Kind kind;
  std::set<std::string> keys;
};
const KindKeys kKinds[] = {
    {"press", Event::Kind::press, {"x", "y", "button", "shift"}},
    {"move", Event::Kind::move, {"x", "y"}},
    {"release", Event::Kind::release, {}},
    {"scroll", Event::Kind::scroll, {"x", "y"}},
    {"key", Event::Kind::key, {"key"}},
    {"set", Event::Kind::set, {"pipeline", "integrator", "dt", "options"}},
    {"screenshot", Event::Kind::screenshot, {"file"}},
    {"quit", Event::Kind::quit, {}},
};

const char* kind_name(Event::Kind k) {
  for (const auto& e : kKinds)
    if (e.kind == k) return e.name;
  return "?";
}

Event from_json(const nlohmann::json& j) {
  if (!j.is_object()) throw std::invalid_argument("an event must be an object");
  Event e;
  const std::string kind = j.contains("event") && j["event"].is_string() ? j["event"].get<std::string>() : "";
  const KindKeys* of = nullptr;
  for (const auto& k : kKinds)
    if (kind == k.name) of = &k;
  if (!of) throw std::invalid_argument("unknown event '" + kind + "'");
  e.kind = of->kind;
  auto text = [](const nlohmann::json& v, const std::string& key) {
    if (!v.is_string()) throw std::invalid_argument(key + " must be a string");
    return v.get<std::string>();
  };
  // Window coordinates and scroll steps: a cursor far outside any window made the drag's target
  // or the camera not finite.
  auto number = [](const nlohmann::json& v, const std::string& key) {
    if (!v.is_number() || !(std::abs(v.get<double>()) <= 1e6)) throw std::invalid_argument(key + " must be a number within ±1e6");
    return v.get<double>();
  };
  for (const auto& [key, v] : j.items()) {
    if (key == "event") continue;
    if (key != "frame" && !of->keys.count(key))
      throw std::invalid_argument("unknown key '" + key + "' of a " + kind + " event");
    if (key == "frame") {
      if (!v.is_number_integer() || v.get<std::int64_t>() < 0 || v.get<std::int64_t>() > INT_MAX)
        throw std::invalid_argument("frame must be a whole number >= 0");
      e.frame = v.get<int>();
    } else if (key == "x") e.x = number(v, key);
    else if (key == "y") e.y = number(v, key);
    else if (key == "button") e.button = text(v, key);
    else if (key == "shift") {
      if (!v.is_boolean()) throw std::invalid_argument("shift must be true or false");
      e.shift = v.get<bool>();
    } else if (key == "key") {
      e.key = text(v, key);
      if (std::find(kKeys.begin(), kKeys.end(), e.key) == kKeys.end()) {
        std::string names;
        for (const auto& k : kKeys) names += (names.empty() ? "" : ", ") + k;
        throw std::invalid_argument("key '" + e.key + "' is not a key the viewer acts on (" + names + ")");
      }
    } else if (key == "file") {
      e.file = text(v, key);
    } else if (key == "dt" && v.is_number()) {  // set: a number as --dt takes it; text, as the panel
      // records what was typed there, is replayed as typed (and refused, if it is, as the panel did)
      if (!(v.get<double>() >= double(FLT_MIN) && v.get<double>() <= double(FLT_MAX)))
        throw std::invalid_argument("dt must be a number of seconds > 0 within float's normal range");
      e.settings[key] = v.dump();
    } else if (key == "pipeline" && (!v.is_string() || !pipelines().find(v.get<std::string>()))) {
      throw std::invalid_argument(v.is_string() ? "unknown pipeline '" + v.get<std::string>() + "' (valid: " + pipelines().names() + ")"
                                                : "pipeline must be a string");
    } else if (key == "integrator" && (!v.is_string() || !parse_integrator(v.get<std::string>()))) {
      throw std::invalid_argument(v.is_string() ? "unknown integrator '" + v.get<std::string>() + "' (valid: " + integrator_names() + ")"
                                                : "integrator must be a string");
    } else {
      e.settings[key] = text(v, key);
    }
  }
  if (e.kind == Event::Kind::key && e.key.empty()) throw std::invalid_argument("a key event needs a key");
  if (e.kind == Event::Kind::press && e.button != "left" && e.button != "right" && e.button != "middle")
    throw std::invalid_argument("button must be left, right or middle");
  if (e.kind == Event::Kind::screenshot && e.file.empty()) throw std::invalid_argument("a screenshot needs a file");
  if (e.kind == Event::Kind::screenshot && std::filesystem::path(e.file).extension() != ".png")
    throw std::invalid_argument("screenshot '" + e.file + "': expected a file name ending in .png (screenshots are PNG)");
  if (e.kind == Event::Kind::set && e.settings.empty())
    throw std::invalid_argument("a set event needs one of pipeline, integrator, dt and options");
  return e;
}

}  // namespace

nlohmann::json to_json(const Event& e) {
  nlohmann::json j = {{"frame", e.frame}, {"event", kind_name(e.kind)}};
  switch (e.kind) {
    case Event::Kind::press:
      j["button"] = e.button;
      if (e.shift) j["shift"] = true;
      [[fallthrough]];
    case Event::Kind::move:
    case Event::Kind::scroll:
      j["x"] = e.x;
      j["y"] = e.y;
      break;
    case Event::Kind::key: j["key"] = e.key; break;
    case Event::Kind::set:
      for (const auto& [k, v] : e.settings) j[k] = v;
      break;
    case Event::Kind::screenshot: j["file"] = e.file; break;
    default: break;
  }
  return j;
}

std::vector<Event> read_script(const std::string& path) {
  const nlohmann::json j = read_json_file(path, "script file");
  if (!j.is_object() || !j.contains("events") || !j["events"].is_array() || j.size() != 1)
    throw std::invalid_argument("script file " + path + ": expected {\"events\": [...]}");
  std::vector<Event> out;
  for (std::size_t k = 0; k < j["events"].size(); ++k) {
    try {
      out.push_back(from_json(j["events"][k]));
    } catch (const std::exception& e) {  // nlohmann's type errors too
      throw std::invalid_argument("script file " + path + ", event " + std::to_string(k) + ": " + e.what());
    }
    if (k > 0 && out[k].frame < out[k - 1].frame)
      throw std::invalid_argument("script file " + path + ", event " + std::to_string(k) + ": frames must not decrease");
  }
  return out;
}

void write_script(const std::string& path, const std::vector<Event>& events) {
  nlohmann::json list = nlohmann::json::array();
  for (const Event& e : events) list.push_back(to_json(e));
  write_atomically(path, nlohmann::json{{"events", list}}.dump(1) + "\n");
}

}  // namespace deformlab::viewer
