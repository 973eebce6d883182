#include "scene.hpp"

#include <cmath>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>

#include "json_file.hpp"

namespace deformlab {

using nlohmann::json;

namespace {

[[noreturn]] void bad(const std::string& where, const std::string& what) {
  throw std::invalid_argument(where + ": " + what);
}

void only_keys(const json& j, const std::string& where, std::initializer_list<const char*> keys) {
  if (!j.is_object()) bad(where, "expected an object");
  const std::set<std::string> ok(keys.begin(), keys.end());
  for (const auto& [k, v] : j.items())
    if (!ok.count(k)) {
      std::string list;
      for (const auto& s : ok) list += (list.empty() ? "" : ", ") + s;
      bad(where + "." + k, "unknown key (expected one of: " + list + ")");
    }
}

// What a number may be: any finite value, > 0 or >= 0.
enum class Range { any, positive, non_negative };

float num(const json& j, const std::string& where, Range r = Range::any) {
  if (!j.is_number()) bad(where, "expected a number");
  const double d = j.get<double>();
  if (!std::isfinite(d) || std::abs(d) > 3.0e38) bad(where, "expected a finite number");
  if (r == Range::positive && !(d > 0)) bad(where, "expected a number > 0");
  if (r == Range::non_negative && !(d >= 0)) bad(where, "expected a number >= 0");
  return float(d);
}

int integer(const json& j, const std::string& where, std::int64_t min = INT32_MIN) {
  if (!j.is_number_integer()) bad(where, "expected an integer");
  const auto v = j.get<std::int64_t>();
  if (v < min) bad(where, "expected an integer >= " + std::to_string(min));
  if (v > INT32_MAX) bad(where, "integer out of range");
  return int(v);
}

Vec3f vec3(const json& j, const std::string& where) {
  if (!j.is_array() || j.size() != 3) bad(where, "expected [x, y, z]");
  return {num(j[0], where + "[0]"), num(j[1], where + "[1]"), num(j[2], where + "[2]")};
}

void per_kind(std::array<float, kSpringKinds>& out, const json& j, const std::string& where, Range r) {
  if (j.is_number()) {
    out.fill(num(j, where, r));
    return;
  }
  only_keys(j, where, {"structural", "shear", "flexion"});
  for (int k = 0; k < kSpringKinds; ++k) {
    const char* name = to_string(SpringKind(k));
    if (j.contains(name)) out[k] = num(j[name], where + "." + name, r);
  }
}

void apply_model(ModelSpec& m, const json& j, const std::string& where) {
  only_keys(j, where, {"type", "size", "spacing", "width", "height", "node_mass", "stiffness", "damping", "pins"});
  if (j.contains("type")) {
    const auto t = j["type"].is_string() ? j["type"].get<std::string>() : "";
    if (t == "cloth") m.topology = Topology::cloth_grid;
    else if (t == "lattice") m.topology = Topology::lattice;
    else bad(where + ".type", "expected \"cloth\" or \"lattice\"");
  }
  if (j.contains("size")) {
    const auto& s = j["size"];
    const std::size_t want = m.topology == Topology::lattice ? 3 : 2;
    if (!s.is_array() || s.size() != want)
      bad(where + ".size", want == 3 ? "expected [nx, ny, nz]" : "expected [nx, ny]");
    m.nx = integer(s[0], where + ".size[0]", 1);
    m.ny = integer(s[1], where + ".size[1]", 1);
    m.nz = want == 3 ? integer(s[2], where + ".size[2]", 1) : 1;
  }
  if (j.contains("spacing")) m.spacing = num(j["spacing"], where + ".spacing", Range::non_negative);  // 0: from width
  if (j.contains("width")) m.width = num(j["width"], where + ".width", Range::positive);
  if (j.contains("height")) m.height = num(j["height"], where + ".height");
  if (j.contains("node_mass")) m.material.node_mass = num(j["node_mass"], where + ".node_mass", Range::positive);
  if (j.contains("stiffness")) per_kind(m.material.stiffness, j["stiffness"], where + ".stiffness", Range::positive);
  if (j.contains("damping")) per_kind(m.material.damping, j["damping"], where + ".damping", Range::non_negative);
  if (j.contains("pins")) {
    const auto& p = j["pins"];
    if (p.is_array()) {
      m.pins = PinSet::list;
      m.pin_list.clear();
      std::set<int> seen;
      for (std::size_t k = 0; k < p.size(); ++k) {
        const std::string w = where + ".pins[" + std::to_string(k) + "]";
        const int node = integer(p[k], w, 0);
        if (!seen.insert(node).second) bad(w, "node " + std::to_string(node) + " is listed twice");
        m.pin_list.push_back(node);
      }
    } else {
      const auto s = p.is_string() ? p.get<std::string>() : "";
      if (s == "none") m.pins = PinSet::none;
      else if (s == "top-corners") m.pins = PinSet::top_corners;
      else if (s == "top-row") m.pins = PinSet::top_row;
      else bad(where + ".pins", "expected \"none\", \"top-corners\", \"top-row\" or a list of node indices");
    }
  }
}

void apply_drag(Scene& s, const json& j, const std::string& where) {
  only_keys(j, where, {"node", "mode", "stiffness", "path", "path_is"});
  DragSpec& d = s.drag;
  DragHandle& h = s.params.drag;
  d.enabled = true;
  if (j.contains("node")) {
    if (j["node"] == "center") { d.center = true; d.node = -1; }
    else { d.center = false; d.node = integer(j["node"], where + ".node", 0); }
  }
  if (j.contains("mode")) {
    if (j["mode"] == "hard") h.as_spring = false;
    else if (j["mode"] == "spring") h.as_spring = true;
    else bad(where + ".mode", "expected \"hard\" or \"spring\"");
  }
  if (j.contains("stiffness")) h.stiffness = num(j["stiffness"], where + ".stiffness", Range::positive);
  if (j.contains("path_is")) {
    if (j["path_is"] == "offset") d.offsets = true;
    else if (j["path_is"] == "position") d.offsets = false;
    else bad(where + ".path_is", "expected \"offset\" or \"position\"");
  }
  if (j.contains("path")) {
    const auto& p = j["path"];
    if (!p.is_array() || p.empty()) bad(where + ".path", "expected a non-empty list of [t, x, y, z]");
    h.path.clear();
    for (std::size_t k = 0; k < p.size(); ++k) {
      const std::string w = where + ".path[" + std::to_string(k) + "]";
      if (!p[k].is_array() || p[k].size() != 4) bad(w, "expected [t, x, y, z]");
      h.path.push_back({num(p[k][0], w + "[0]"), {num(p[k][1], w + "[1]"), num(p[k][2], w + "[2]"), num(p[k][3], w + "[3]")}});
      if (k > 0 && !(h.path[k].t > h.path[k - 1].t)) bad(w + "[0]", "keyframe times must increase");
    }
  }
}

}  // namespace

void apply_json(Scene& s, const json& j, const std::string& where) {
  only_keys(j, where, {"model", "dt", "gravity", "damping", "wind", "ground", "spheres", "drag", "threshold",
                       "min_steps", "max_steps", "check_every", "runaway_factor"});
  Params& p = s.params;
  if (j.contains("model")) apply_model(s.model, j["model"], where + ".model");
  if (j.contains("dt")) p.dt = num(j["dt"], where + ".dt", Range::positive);
  if (j.contains("gravity")) p.gravity = vec3(j["gravity"], where + ".gravity");
  if (j.contains("damping")) p.damping = num(j["damping"], where + ".damping", Range::non_negative);
  if (j.contains("wind")) p.wind = vec3(j["wind"], where + ".wind");
  if (j.contains("ground")) {
    if (j["ground"].is_null()) p.ground.reset();
    else p.ground = num(j["ground"], where + ".ground");
  }
  if (j.contains("spheres")) {
    const auto& a = j["spheres"];
    if (!a.is_array()) bad(where + ".spheres", "expected a list");
    p.spheres.clear();
    for (std::size_t k = 0; k < a.size(); ++k) {
      const std::string w = where + ".spheres[" + std::to_string(k) + "]";
      only_keys(a[k], w, {"center", "radius"});
      if (!a[k].contains("center") || !a[k].contains("radius")) bad(w, "needs center and radius");
      p.spheres.push_back({vec3(a[k]["center"], w + ".center"), num(a[k]["radius"], w + ".radius", Range::positive)});
    }
  }
  if (j.contains("drag")) {
    if (j["drag"].is_null()) { s.drag = {}; p.drag = {}; }
    else apply_drag(s, j["drag"], where + ".drag");
  }
  if (j.contains("threshold")) p.threshold = num(j["threshold"], where + ".threshold", Range::positive);
  if (j.contains("min_steps")) p.min_steps = integer(j["min_steps"], where + ".min_steps", 0);
  if (j.contains("max_steps")) p.max_steps = integer(j["max_steps"], where + ".max_steps", 1);
  if ((j.contains("min_steps") || j.contains("max_steps")) && p.min_steps > p.max_steps)
    bad(where + (j.contains("min_steps") ? ".min_steps" : ".max_steps"),
        "min_steps (" + std::to_string(p.min_steps) + ") exceeds max_steps (" + std::to_string(p.max_steps) + ")");
  if (j.contains("check_every")) p.check_every = integer(j["check_every"], where + ".check_every", 1);
  if (j.contains("runaway_factor"))
    p.runaway_factor = num(j["runaway_factor"], where + ".runaway_factor", Range::positive);
}

Scene load_scene(const std::string& path) {
  Scene s;
  apply_json(s, read_json_file(path, "scene file"), path);
  return s;
}

Model build_model(const Scene& s) {
  const ModelSpec& m = s.model;
  if (m.nx < 1 || m.ny < 1 || m.nz < 1)
    throw std::invalid_argument("model size must be positive in every dimension");
  float h = m.spacing;
  if (h == 0.f) h = m.nx > 1 ? m.width / float(m.nx - 1) : m.width;
  Model model = m.topology == Topology::lattice ? lattice(m.nx, m.ny, m.nz, h, m.height, m.material)
                                                : cloth_grid(m.nx, m.ny, h, m.height, m.material);
  pin(model, pin_nodes(model, m.pins, m.pin_list));
  return model;
}

Params resolve_params(const Scene& s, const Model& m) {
  Params p = s.params;
  if (s.drag.enabled) {
    int node = s.drag.node;
    if (s.drag.center) node = ((m.nz / 2) * m.ny + m.ny / 2) * m.nx + m.nx / 2;
    if (node < 0 || node >= m.node_count())
      throw std::invalid_argument("drag node " + std::to_string(node) + " is outside the model (0.." +
                                  std::to_string(m.node_count() - 1) + ")");
    p.drag.node = node;
    if (s.drag.offsets)
      for (auto& k : p.drag.path) k.position = m.rest_position[node] + k.position;
  } else {
    p.drag = {};
  }
  validate(p, m.node_count());
  return p;
}

json to_json(const Scene& s) {
  auto v3 = [](const Vec3f& v) { return json::array({v.x, v.y, v.z}); };
  auto kinds = [](const std::array<float, kSpringKinds>& a) {
    return json{{"structural", a[0]}, {"shear", a[1]}, {"flexion", a[2]}};
  };
  const ModelSpec& m = s.model;
  const Params& p = s.params;
  json model{{"type", m.topology == Topology::lattice ? "lattice" : "cloth"},
             {"spacing", m.spacing}, {"width", m.width}, {"height", m.height},
             {"node_mass", m.material.node_mass}, {"stiffness", kinds(m.material.stiffness)},
             {"damping", kinds(m.material.damping)}};
  model["size"] = m.topology == Topology::lattice ? json::array({m.nx, m.ny, m.nz}) : json::array({m.nx, m.ny});
  switch (m.pins) {
    case PinSet::none: model["pins"] = "none"; break;
    case PinSet::top_corners: model["pins"] = "top-corners"; break;
    case PinSet::top_row: model["pins"] = "top-row"; break;
    case PinSet::list: model["pins"] = m.pin_list; break;
  }
  json j{{"model", model}, {"dt", p.dt}, {"gravity", v3(p.gravity)}, {"damping", p.damping},
         {"wind", v3(p.wind)}, {"threshold", p.threshold}, {"min_steps", p.min_steps},
         {"max_steps", p.max_steps}, {"check_every", p.check_every}, {"runaway_factor", p.runaway_factor}};
  j["ground"] = p.ground ? json(*p.ground) : json(nullptr);
  j["spheres"] = json::array();
  for (const auto& sp : p.spheres) j["spheres"].push_back({{"center", v3(sp.center)}, {"radius", sp.radius}});
  if (s.drag.enabled) {
    json path = json::array();
    for (const auto& k : p.drag.path) path.push_back({k.t, k.position.x, k.position.y, k.position.z});
    j["drag"] = {{"node", s.drag.center ? json("center") : json(s.drag.node)},
                 {"mode", p.drag.as_spring ? "spring" : "hard"}, {"stiffness", p.drag.stiffness},
                 {"path_is", s.drag.offsets ? "offset" : "position"}, {"path", path}};
  } else {
    j["drag"] = nullptr;
  }
  return j;
}

}  // namespace deformlab
