// A scene against its model (the checks that need the model built), the estimates and
// descriptions of its parts, and the scene written back as JSON (scene_read.cpp reads it).
#include "scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "number_text.hpp"

namespace deformlab {

using nlohmann::json;

namespace {

// Nodes of a Gmsh sheet per h^2 of its area and h of its rim, of a Gmsh box per h^3 of its
// volume and h^2 of its surface, with cell size h (estimated_nodes; fitted to meshes of 50 k
// to 1 M nodes).
constexpr double kSheetPerArea = 1.314, kSheetPerRim = 0.631, kBoxPerVolume = 0.600, kBoxPerSurface = 0.952;

json to_json(const NodeSelector& s) {
  auto v3 = [](const Vec3f& v) { return json::array({v.x, v.y, v.z}); };
  using K = NodeSelector::Kind;
  switch (s.kind) {
    case K::index: return s.index;
    case K::center: return "center";
    case K::nearest: return {{"nearest", v3(s.a)}};
    case K::box: return {{"box", {v3(s.a), v3(s.b)}}};
    case K::below: return {{"below", {{"point", v3(s.a)}, {"normal", v3(s.b)}}}};
  }
  return nullptr;
}

// A free node that starts deeper in the ground or a sphere than a step may move it (runaway_factor
// x extent) is pushed out by more at the first step, which a run takes for divergence: refused.
void require_start_outside_colliders(const Model& m, const Params& p) {
  const double bound = p.runaway_distance(m.extent());
  for (int i = 0; i < m.node_count(); ++i) {
    if (m.pinned(i) || p.hard_dragged(i)) continue;
    const Vec3f x = m.rest_position[i];
    std::string where;
    double depth = 0;
    if (p.ground && double(*p.ground) - x.y > bound) depth = double(*p.ground) - x.y, where = "below the ground";
    for (std::size_t k = 0; k < p.spheres.size() && where.empty(); ++k)
      if (const double d = double(p.spheres[k].radius) - norm(x - p.spheres[k].center); d > bound)
        depth = d, where = "inside spheres[" + std::to_string(k) + "]";
    if (!where.empty())
      throw std::invalid_argument("node " + std::to_string(m.file_index(i)) + " starts " + significant_trimmed(depth, 3) +
                                  " m " + where + ", deeper than a step may move a node (runaway_factor x model extent: " +
                                  significant_trimmed(bound, 3) + " m); its first step would be taken for divergence");
  }
}

// A hard drag sets its node on the path each step: a step along it longer than a step may move a
// node (runaway_factor x extent) would be taken for divergence. The path is linear between keys,
// so the longest step starts or ends on a key (or at t = 0, from the node's rest position).
// `inserted`: the path's first key is the rest position, not one of the scene's (`where` names
// the scene's path).
void require_drag_steps_in_bound(const Model& m, const Params& p, bool inserted, const std::string& where) {
  if (!p.drag.active() || p.drag.as_spring) return;
  const double bound = p.runaway_distance(m.extent()), dt = p.dt;
  const auto& path = p.drag.path;
  std::vector<double> starts = {0.0};
  for (const Keyframe& k : path) starts.insert(starts.end(), {double(k.t), double(k.t) - dt});
  for (const double t : starts) {
    if (t < 0 || (t > 0 && t >= double(path.back().t))) continue;  // the first step moves it from rest
    const Vec3f from = t == 0 ? m.rest_position[p.drag.node] : p.drag.target(t);
    const double step = norm(p.drag.target(t + dt) - from);
    if (step <= bound) continue;
    // The key the step heads for; the first one where the step from rest jumps onto it, a key at
    // t = 0 with no other within the step.
    std::size_t key = 0;
    if (t > 0 || inserted || (path.size() > 1 && double(path[1].t) <= t + dt))
      while (key + 1 < path.size() && double(path[key].t) < t + dt) ++key;
    throw std::invalid_argument(where + "[" + std::to_string(key - std::size_t(inserted)) + "]: the handle moves " +
                                significant_trimmed(step, 3) + " m in the step from t = " + significant_trimmed(t, 6) +
                                " s" + (t == 0 ? " (from the node's rest position)" : "") +
                                ", more than a step may move a node (runaway_factor x model extent: " +
                                significant_trimmed(bound, 3) +
                                " m); the step would be taken for divergence (slow the path or use the spring mode)");
  }
}

}  // namespace

Params resolve_params(const Scene& s, const Model& m) {
  Params p = s.params;
  if (s.drag.enabled) {
    const std::string where = s.drag.node.where.empty() ? "drag node" : s.drag.node.where;
    int node = -1;
    try {
      node = select_nodes(m, s.drag.node).at(0);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(where + ": " + e.what());
    }
    if (m.pinned(node))
      throw std::invalid_argument(where + ": node " + std::to_string(m.file_index(node)) +
                                  " is pinned (model.pins), so the drag would not move it");
    p.drag.node = node;
    if (s.drag.offsets)
      for (auto& k : p.drag.path) k.position = m.rest_position[node] + k.position;
  } else {
    p.drag = {};
  }
  validate(p, m.node_count());
  require_start_outside_colliders(m, p);
  // The handle takes its node where it rests at t = 0: a path whose first key comes later
  // starts with the way from there to that key, not with a jump onto it. (After the checks,
  // whose messages count the scene's own keyframes.)
  const bool inserted = p.drag.active() && p.drag.path.front().t > 0.f;
  if (inserted) p.drag.path.insert(p.drag.path.begin(), Keyframe{0.f, m.rest_position[p.drag.node]});
  require_drag_steps_in_bound(m, p, inserted, s.drag.path_where);
  return p;
}

const char* to_string(MeshShape::Kind k) { return k == MeshShape::Kind::sheet ? "sheet" : "box"; }

double estimated_filled_nodes(double volume, double cell_size) {
  return kBoxPerVolume * volume / (double(cell_size) * cell_size * cell_size);
}

double estimated_nodes(const MeshShape& s) {
  const double h = s.cell_size, x = s.size.x, y = s.size.y, z = s.size.z;
  if (s.kind == MeshShape::Kind::sheet) return kSheetPerArea * x * z / (h * h) + kSheetPerRim * 2 * (x + z) / h;
  return kBoxPerVolume * x * y * z / (h * h * h) + kBoxPerSurface * 2 * (x * y + y * z + z * x) / (h * h);
}

std::string describe(const MeshShape& g) {
  std::ostringstream os;
  os << "Gmsh " << to_string(g.kind) << " " << g.size.x << " x ";
  if (g.kind == MeshShape::Kind::box) os << g.size.y << " x ";
  os << g.size.z << " m, cell " << g.cell_size << " m";
  if (g.threads > 0) os << ", " << g.threads << (g.threads == 1 ? " thread" : " threads");
  return os.str();
}

std::string describe(const ModelSpec& m) {
  switch (m.topology) {
    case Topology::cloth_grid: return "cloth " + std::to_string(m.nx) + "x" + std::to_string(m.ny);
    case Topology::lattice:
      return "lattice " + std::to_string(m.nx) + "x" + std::to_string(m.ny) + "x" + std::to_string(m.nz);
    case Topology::general: break;
  }
  const std::string order = ", order " + std::string(to_string(m.mesh.order));
  if (m.mesh.generate) return "mesh: " + describe(*m.mesh.generate) + order;
  return "mesh " + m.mesh.file + (m.mesh.fill ? " filled with tetrahedra" : "") + order;
}

namespace {

// Every number of `j` that is a float's value written as that float's shortest decimal (0.002,
// not the double 0.0020000000949949026; shortest_decimal).
void shortest_floats(json& j) {
  if (j.is_structured()) {
    for (auto& v : j) shortest_floats(v);
  } else if (j.is_number_float() && double(float(j.get<double>())) == j.get<double>()) {
    j = shortest_decimal(float(j.get<double>()));
  }
}

}  // namespace

json to_json(const Scene& s) {
  auto v3 = [](const Vec3f& v) { return json::array({v.x, v.y, v.z}); };
  auto kinds = [](const std::array<float, kSpringKinds>& a) {
    return json{{"structural", a[0]}, {"shear", a[1]}, {"flexion", a[2]}};
  };
  const ModelSpec& m = s.model;
  const Params& p = s.params;
  json model{{"node_mass", m.material.node_mass}, {"stiffness", kinds(m.material.stiffness)},
             {"damping", kinds(m.material.damping)}};
  if (m.topology == Topology::general) {
    model["stiffness"].erase("shear");
    model["damping"].erase("shear");
    const MeshSpec& ms = m.mesh;
    json rows = json::array();
    for (int r = 0; r < 3; ++r) rows.push_back({ms.transform[r * 4], ms.transform[r * 4 + 1], ms.transform[r * 4 + 2], ms.transform[r * 4 + 3]});
    model.update({{"type", "mesh"}, {"scale", v3(ms.scale)}, {"transform", rows}, {"order", to_string(ms.order)}});
    if (ms.order == NodeOrder::shuffled) model["seed"] = ms.seed;
    if (const auto& g = ms.generate) {
      const bool sheet = g->kind == MeshShape::Kind::sheet;
      model["generate"] = {{"shape", to_string(g->kind)}, {"cell_size", g->cell_size},
                           {"size", sheet ? json::array({g->size.x, g->size.z}) : v3(g->size)}};
      if (g->threads > 0) model["generate"]["threads"] = g->threads;
    } else {
      model.update({{"file", ms.file}, {"fill", ms.fill ? "tetrahedra" : "none"}});
      if (ms.fill) model["cell_size"] = ms.cell_size;
    }
    if (ms.density > 0) model["density"] = ms.density, model.erase("node_mass");  // it sets the masses
  } else {
    model.update({{"type", m.topology == Topology::lattice ? "lattice" : "cloth"}, {"height", m.height}});
    if (m.spacing > 0) model["spacing"] = m.spacing;  // it sets the width
    else model["width"] = m.width;
    model["size"] = m.topology == Topology::lattice ? json::array({m.nx, m.ny, m.nz}) : json::array({m.nx, m.ny});
  }
  switch (m.pins) {
    case PinSet::none: model["pins"] = "none"; break;
    case PinSet::top_corners: model["pins"] = "top-corners"; break;
    case PinSet::top_row: model["pins"] = "top-row"; break;
    case PinSet::list:
      model["pins"] = json::array();
      for (const auto& sel : m.pin_list) model["pins"].push_back(to_json(sel));
      break;
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
    j["drag"] = {{"node", to_json(s.drag.node)},
                 {"mode", p.drag.as_spring ? "spring" : "hard"},
                 {"path_is", s.drag.offsets ? "offset" : "position"}, {"path", path}};
    if (p.drag.as_spring) j["drag"]["stiffness"] = p.drag.stiffness;
  } else {
    j["drag"] = nullptr;
  }
  shortest_floats(j);
  return j;
}

}  // namespace deformlab
