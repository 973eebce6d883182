// Reading a scene file: every key checked, each error naming its key path.
#include "scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <span>
#include <stdexcept>

#include "json_file.hpp"
#include "memory.hpp"
#include "physics.hpp"  // MAX_SPHERES

namespace deformlab {

using nlohmann::json;

namespace {

void only_keys(const json& j, const std::string& where, std::span<const char* const> keys) {
  if (!j.is_object()) bad_value(where, "expected an object");
  const std::set<std::string> ok(keys.begin(), keys.end());
  for (const auto& [k, v] : j.items())
    if (!ok.count(k)) {
      std::string list;
      for (const auto& s : ok) list += (list.empty() ? "" : ", ") + s;
      bad_value(where + "." + k, "unknown key (expected one of: " + list + ")");
    }
}
void only_keys(const json& j, const std::string& where, std::initializer_list<const char*> keys) {
  only_keys(j, where, std::span(keys.begin(), keys.size()));
}

// A scene object's keys.
constexpr std::array<const char*, 13> kSceneKeys = {"model", "dt", "gravity", "damping", "wind", "ground", "spheres",
                                                    "drag", "threshold", "min_steps", "max_steps", "check_every",
                                                    "runaway_factor"};

// What a number may be: any finite value, > 0 or >= 0.
enum class Range { any, positive, non_negative };

float num(const json& j, const std::string& where, Range r = Range::any) {
  if (!j.is_number()) bad_value(where, "expected a number");
  const double d = j.get<double>();
  if (!std::isfinite(d)) bad_value(where, "expected a finite number");
  if (std::abs(d) > 3.0e38) bad_value(where, "expected a number of magnitude at most 3e38 (it is read as a float)");
  if (r == Range::positive && !(d > 0)) bad_value(where, "expected a number > 0");
  if (r == Range::non_negative && !(d >= 0)) bad_value(where, "expected a number >= 0");
  // Read as float: a size, mass or constant under float's normal range would be 0 or a
  // subnormal whose inverse overflows.
  if (r != Range::any && d != 0 && d < std::numeric_limits<float>::min())
    bad_value(where, std::string(r == Range::positive ? "expected a number of" : "expected 0 or a number of") +
                         " at least 1.18e-38 (the smallest normal float)");
  return float(d);
}

int integer(const json& j, const std::string& where, std::int64_t min = INT32_MIN) {
  if (!j.is_number_integer()) bad_value(where, "expected an integer");
  if (j.is_number_unsigned() && j.get<std::uint64_t>() > std::uint64_t(INT64_MAX))
    bad_value(where, "integer out of range");
  const auto v = j.get<std::int64_t>();
  if (v < min) bad_value(where, "expected an integer >= " + std::to_string(min));
  if (v > INT32_MAX) bad_value(where, "integer out of range");
  return int(v);
}

Vec3f vec3(const json& j, const std::string& where) {
  if (!j.is_array() || j.size() != 3) bad_value(where, "expected [x, y, z]");
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

// A node selector: an index, "center" (when allowed), or {"box": [lo, hi]}, {"below": {"point":
// p, "normal": n}}, {"nearest": p}.
NodeSelector read_selector(const json& j, const std::string& where, bool center) {
  using K = NodeSelector::Kind;
  const char* expected = center ? "expected a node index, \"center\" or {\"nearest\": [x, y, z]}"
                                : "expected a node index or one of {\"box\": ...}, {\"below\": ...}, {\"nearest\": ...}";
  if (j.is_number_integer()) return NodeSelector::node(integer(j, where, 0));
  if (center && j == "center") return {K::center};
  if (!j.is_object() || j.size() != 1) bad_value(where, expected);
  NodeSelector s;
  if (j.contains("nearest")) {
    s = {K::nearest, -1, vec3(j["nearest"], where + ".nearest")};
  } else if (center) {
    bad_value(where, expected);  // a drag handle holds one node
  } else if (j.contains("box")) {
    const auto& b = j["box"];
    if (!b.is_array() || b.size() != 2) bad_value(where + ".box", "expected [[x0, y0, z0], [x1, y1, z1]]");
    s = {K::box, -1, vec3(b[0], where + ".box[0]"), vec3(b[1], where + ".box[1]")};
    for (int c = 0; c < 3; ++c)
      if (s.a[c] > s.b[c]) bad_value(where + ".box", "the first corner must be the lowest in x, y and z");
  } else if (j.contains("below")) {
    only_keys(j["below"], where + ".below", {"point", "normal"});
    if (!j["below"].contains("point") || !j["below"].contains("normal"))
      bad_value(where + ".below", "needs point and normal");
    s = {K::below, -1, vec3(j["below"]["point"], where + ".below.point"), vec3(j["below"]["normal"], where + ".below.normal")};
    if (norm(s.b) == 0.f) bad_value(where + ".below.normal", "expected a non-zero vector");
  } else {
    bad_value(where, expected);
  }
  return s;
}
NodeSelector selector(const json& j, const std::string& where, bool center) {
  NodeSelector s = read_selector(j, where, center);
  s.where = where;
  return s;
}

// "transform": {"rotate": [deg about x, y, z], "translate": [x, y, z]} (x first, then y, then
// z, then the translation), or the matrix's rows (3 or 4 rows of 4; a 4th row is 0 0 0 1).
std::array<float, 12> transform(const json& j, const std::string& where) {
  std::array<float, 12> t{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  if (j.is_array()) {
    if (j.size() != 3 && j.size() != 4) bad_value(where, "expected 3 or 4 rows of 4 numbers");
    for (std::size_t r = 0; r < j.size(); ++r) {
      const std::string w = where + "[" + std::to_string(r) + "]";
      if (!j[r].is_array() || j[r].size() != 4) bad_value(w, "expected a row of 4 numbers");
      for (int c = 0; c < 4; ++c) {
        const float v = num(j[r][c], w + "[" + std::to_string(c) + "]");
        if (r < 3) t[r * 4 + c] = v;
        else if (v != (c == 3 ? 1.f : 0.f)) bad_value(w, "the last row of an affine map is [0, 0, 0, 1]");
      }
    }
    const auto at = [&](int r, int c) { return double(t[r * 4 + c]); };
    const double det = at(0, 0) * (at(1, 1) * at(2, 2) - at(1, 2) * at(2, 1)) -
                       at(0, 1) * (at(1, 0) * at(2, 2) - at(1, 2) * at(2, 0)) +
                       at(0, 2) * (at(1, 0) * at(2, 1) - at(1, 1) * at(2, 0));
    if (det == 0.0) bad_value(where, "its 3 x 3 part is singular: it would flatten the mesh");
    return t;
  }
  only_keys(j, where, {"rotate", "translate"});
  if (j.contains("rotate")) {
    const Vec3f deg = vec3(j["rotate"], where + ".rotate");
    std::array<double, 9> r{1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (int axis = 0; axis < 3; ++axis) {  // r = R_axis * r
      const double a = double(deg[axis]) * M_PI / 180.0, c = std::cos(a), sn = std::sin(a);
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int col = 0; col < 3; ++col) {
        const double ru = r[u * 3 + col], rv = r[v * 3 + col];
        r[u * 3 + col] = c * ru - sn * rv;
        r[v * 3 + col] = sn * ru + c * rv;
      }
    }
    for (int row = 0; row < 3; ++row)
      for (int col = 0; col < 3; ++col) t[row * 4 + col] = float(r[row * 3 + col]);
  }
  if (j.contains("translate")) {
    const Vec3f d = vec3(j["translate"], where + ".translate");
    for (int row = 0; row < 3; ++row) t[row * 4 + 3] = d[row];
  }
  return t;
}

// "generate": {"shape": "sheet", "size": [w, d], "cell_size": h} or {"shape": "box", "size":
// [w, h, d], ...}, optionally "threads": n; refused before meshing where it would make more
// than 2^30 nodes. Lengths lie within [1e-6, 1e6] m, and a shape's sizes within a factor of
// 1e6 of each other: outside that Gmsh's tolerances (relative to the model's size) fail or
// spin, or it merges the points of a side much shorter than the others (1e-6 m beside 1000 m
// ended the process from within Gmsh's threads).
constexpr double kLongestLength = 1e6, kLongestRatio = 1e6;  // m, 1
float length(const json& j, const std::string& where) {
  const float v = num(j, where, Range::positive);
  if (v < float(kShortestLength) || v > float(kLongestLength))
    bad_value(where, "expected a length within [1e-6, 1e6] m");
  return v;
}

MeshShape shape(const json& j, const std::string& where) {
  only_keys(j, where, {"shape", "size", "cell_size", "threads"});
  for (const char* k : {"shape", "size", "cell_size"})
    if (!j.contains(k)) bad_value(where, std::string("needs ") + k);
  MeshShape s;
  if (j["shape"] == "sheet") s.kind = MeshShape::Kind::sheet;
  else if (j["shape"] == "box") s.kind = MeshShape::Kind::box;
  else bad_value(where + ".shape", "expected \"sheet\" or \"box\"");
  const bool sheet = s.kind == MeshShape::Kind::sheet;
  const auto& z = j["size"];
  if (!z.is_array() || z.size() != (sheet ? 2u : 3u))
    bad_value(where + ".size", sheet ? "expected [w, d] (m) for a sheet" : "expected [w, h, d] (m) for a box");
  for (std::size_t k = 0; k < z.size(); ++k) {
    const float v = length(z[k], where + ".size[" + std::to_string(k) + "]");
    s.size[sheet && k == 1 ? 2 : int(k)] = v;
  }
  const std::vector<float> sides = sheet ? std::vector<float>{s.size.x, s.size.z} : std::vector<float>{s.size.x, s.size.y, s.size.z};
  const auto [shortest, longest] = std::minmax_element(sides.begin(), sides.end());
  if (double(*longest) > kLongestRatio * double(*shortest))
    bad_value(where + ".size",
              "its longest side is more than 1e6 times its shortest (Gmsh would merge the shortest's ends)");
  s.cell_size = length(j["cell_size"], where + ".cell_size");

  if (j.contains("threads")) {
    s.threads = integer(j["threads"], where + ".threads", 1);
    if (s.threads > 1024) bad_value(where + ".threads", "expected at most 1024 threads");
  }
  if (const double n = estimated_nodes(s); n > double(std::int64_t(1) << 30))
    bad_value(where + ".cell_size", "would make " + about_nodes(n) + ", over the limit of 2^30");
  return s;
}

void apply_mesh(MeshSpec& m, const json& j, const std::string& where, const std::string& dir) {
  // One source: a file or a generated shape; naming one replaces the other (and, for a
  // shape, a fill of the file).
  if (j.contains("file") && j.contains("generate"))
    bad_value(where + ".generate", "give either \"file\" or \"generate\", not both");
  // "fill": "none" fills nothing, so it is a generated mesh's too (it may undo a base's fill).
  for (const char* k : {"fill", "cell_size"})
    if (j.contains("generate") && j.contains(k) && !(k == std::string("fill") && j[k] == "none"))
      bad_value(where + "." + k, "fills a surface file; a generated mesh takes generate.cell_size");
  if (j.contains("file")) {
    if (!j["file"].is_string() || j["file"].get<std::string>().empty())
      bad_value(where + ".file", "expected a file name");
    const std::filesystem::path f = j["file"].get<std::string>();
    m.file = (f.is_relative() && !dir.empty() ? std::filesystem::path(dir) / f : f).lexically_normal().string();
    m.generate.reset();
  }
  if (j.contains("generate")) {
    m.generate = shape(j["generate"], where + ".generate");
    m.file.clear();
    m.fill = false;
    m.cell_size = 0.f;
  }
  if (j.contains("scale")) {
    if (j["scale"].is_number()) m.scale = Vec3f{1.f, 1.f, 1.f} * num(j["scale"], where + ".scale", Range::positive);
    else m.scale = vec3(j["scale"], where + ".scale");
    for (int c = 0; c < 3; ++c)
      if (!(m.scale[c] > 0.f)) bad_value(where + ".scale", "expected scale factors > 0");
  }
  if (j.contains("transform")) m.transform = transform(j["transform"], where + ".transform");
  if (j.contains("density")) m.density = num(j["density"], where + ".density", Range::positive);
  if (j.contains("fill")) {
    if (j["fill"] == "tetrahedra" && m.generate)
      bad_value(where + ".fill", "a generated mesh is not filled (a box is a volume already)");
    if (j["fill"] == "tetrahedra") m.fill = true;
    else if (j["fill"] == "none") m.fill = false;
    else bad_value(where + ".fill", "expected \"tetrahedra\" or \"none\"");
  }
  if (j.contains("cell_size")) m.cell_size = num(j["cell_size"], where + ".cell_size", Range::non_negative);
  if (j.contains("order")) {
    const auto o = parse_node_order(j["order"].is_string() ? j["order"].get<std::string>() : "");
    if (!o) bad_value(where + ".order", std::string("expected one of: ") + kNodeOrderNames);
    m.order = *o;
  }
  if (j.contains("seed")) m.seed = std::uint64_t(integer(j["seed"], where + ".seed", 0));
  // Keys that would do nothing are refused (the writer leaves them out).
  if (j.contains("cell_size") && !m.fill)
    bad_value(where + ".cell_size",
              "the cell size of a tetrahedral fill, and this mesh is not filled (\"fill\": \"tetrahedra\")");
  if (j.contains("seed") && m.order != NodeOrder::shuffled)
    bad_value(where + ".seed", std::string("seeds the shuffled order, and this mesh's order is ") + to_string(m.order));
}

void apply_model(ModelSpec& m, const json& j, const std::string& where, const std::string& dir) {
  only_keys(j, where, {"type", "size", "spacing", "width", "height", "file", "generate", "scale", "transform", "density",
                       "fill", "cell_size", "order", "seed", "node_mass", "stiffness", "damping", "pins"});
  if (j.contains("type")) {
    const auto t = j["type"].is_string() ? j["type"].get<std::string>() : "";
    if (t == "cloth") m.topology = Topology::cloth_grid;
    else if (t == "lattice") {
      // A layer that makes the model a lattice without a size of its own: the default cube,
      // not the cloth's rows with one layer.
      if (m.topology != Topology::lattice && !j.contains("size")) m.nx = m.ny = m.nz = kDefaultLatticeSide;
      m.topology = Topology::lattice;
    }
    else if (t == "mesh") m.topology = Topology::general;
    else bad_value(where + ".type", "expected \"cloth\", \"lattice\" or \"mesh\"");
  }
  const bool mesh = m.topology == Topology::general;
  if (mesh && j.contains("type") && !j.contains("pins") && m.pins != PinSet::none && m.pins != PinSet::list)
    m.pins_where = where + ".pins (absent: " + (m.pins_where.empty() ? "the default" : "from " + m.pins_where) + ")";
  if (mesh && j.contains("type")) m.mesh.where = where;
  for (const char* k : {"size", "spacing", "width", "height"})
    if (mesh && j.contains(k)) bad_value(where + "." + k, "not a key of a mesh model (its size comes from the file)");
  for (const char* k : {"file", "generate", "scale", "transform", "density", "fill", "cell_size", "order", "seed"})
    if (!mesh && j.contains(k)) bad_value(where + "." + k, "a key of mesh models (\"type\": \"mesh\")");
  if (mesh) apply_mesh(m.mesh, j, where, dir);
  if (j.contains("size")) {
    const auto& s = j["size"];
    const std::size_t want = m.topology == Topology::lattice ? 3 : 2;
    if (!s.is_array() || s.size() != want)
      bad_value(where + ".size", want == 3 ? "expected [nx, ny, nz]" : "expected [nx, ny]");
    m.nx = integer(s[0], where + ".size[0]", 1);
    m.ny = integer(s[1], where + ".size[1]", 1);
    m.nz = want == 3 ? integer(s[2], where + ".size[2]", 1) : 1;
  }
  // A layer gives the spacing or the width (spacing 0: width over the grid's first axis with more
  // than one node), and replaces the other.
  // Grid lengths within [1e-6, 1e6] m, as a generated mesh's (spacing 0: from the width): past
  // that the springs' squared lengths overflow float (a width of 3e38 m ran as a divergence).
  if (j.contains("spacing")) {
    m.spacing = num(j["spacing"], where + ".spacing", Range::non_negative);
    if (m.spacing > 0 && (m.spacing < float(kShortestLength) || m.spacing > float(kLongestLength)))
      bad_value(where + ".spacing", "expected a length within [1e-6, 1e6] m, or 0 (from the width)");
  }
  if (j.contains("width")) {
    if (m.spacing > 0 && j.contains("spacing"))
      bad_value(where + ".width", "give spacing or width, not both (each sets the other)");
    m.width = length(j["width"], where + ".width");
    m.spacing = 0;
  }
  if (j.contains("height")) {
    m.height = num(j["height"], where + ".height");
    if (std::abs(m.height) > float(kLongestLength))
      bad_value(where + ".height", "expected a height within [-1e6, 1e6] m");
  }
  // A mesh's masses come from `density` or `node_mass`: a layer gives one and replaces the other.
  if (j.contains("node_mass")) {
    if (mesh && j.contains("density"))
      bad_value(where + ".node_mass", "give density or node_mass, not both (each sets the masses)");
    m.material.node_mass = num(j["node_mass"], where + ".node_mass", Range::positive);
    m.mesh.density = 0.f;
  }
  for (const char* k : {"stiffness", "damping"})
    if (mesh && j.contains(k) && j[k].is_object() && j[k].contains("shear"))
      bad_value(where + "." + k + ".shear",
                "a mesh has no shear springs (its edges are structural, its bending springs flexion)");
  if (j.contains("stiffness")) per_kind(m.material.stiffness, j["stiffness"], where + ".stiffness", Range::positive);
  if (j.contains("damping")) per_kind(m.material.damping, j["damping"], where + ".damping", Range::non_negative);
  if (j.contains("pins")) {
    const auto& p = j["pins"];
    m.pins_where = where + ".pins";
    if (p.is_array() || p.is_object()) {
      m.pins = PinSet::list;
      m.pin_list.clear();
      const json list = p.is_array() ? p : json::array({p});
      // A selector given twice, as read (1 and 1.0000000001 are one float), is a slip; differing
      // ones may still share nodes.
      std::map<decltype(NodeSelector{}.key()), std::size_t> seen;
      for (std::size_t k = 0; k < list.size(); ++k) {
        std::string w = where + ".pins";
        if (p.is_array()) w += '[' + std::to_string(k) + ']';
        const NodeSelector& s = m.pin_list.emplace_back(selector(list[k], w, false));
        if (const auto [at, added] = seen.emplace(s.key(), k); !added)
          bad_value(w, "the same selector as pins[" + std::to_string(at->second) + "]");
      }
    } else {
      const auto s = p.is_string() ? p.get<std::string>() : "";
      if (s == "none") m.pins = PinSet::none;
      else if (s == "top-corners") m.pins = PinSet::top_corners;
      else if (s == "top-row") m.pins = PinSet::top_row;
      else
        bad_value(where + ".pins", "expected \"none\", \"top-corners\", \"top-row\", a selector or a list of node "
                                   "indices and selectors");
    }
  }
}

void apply_drag(Scene& s, const json& j, const std::string& where) {
  only_keys(j, where, {"node", "mode", "stiffness", "path", "path_is"});
  DragSpec& d = s.drag;
  DragHandle& h = s.params.drag;
  d.enabled = true;
  if (j.contains("node")) d.node = selector(j["node"], where + ".node", true);
  if (j.contains("mode")) {
    if (j["mode"] == "hard") h.as_spring = false;
    else if (j["mode"] == "spring") h.as_spring = true;
    else bad_value(where + ".mode", "expected \"hard\" or \"spring\"");
  }
  if (j.contains("stiffness")) h.stiffness = num(j["stiffness"], where + ".stiffness", Range::positive);
  if (j.contains("path_is")) {
    if (j["path_is"] == "offset") d.offsets = true;
    else if (j["path_is"] == "position") d.offsets = false;
    else bad_value(where + ".path_is", "expected \"offset\" or \"position\"");
  }
  if (j.contains("path")) {
    const auto& p = j["path"];
    if (!p.is_array() || p.empty()) bad_value(where + ".path", "expected a non-empty list of [t, x, y, z]");
    h.path.clear();
    d.path_where = where + ".path";
    for (std::size_t k = 0; k < p.size(); ++k) {
      const std::string w = where + ".path[" + std::to_string(k) + "]";
      if (!p[k].is_array() || p[k].size() != 4) bad_value(w, "expected [t, x, y, z]");
      h.path.push_back({num(p[k][0], w + "[0]", Range::non_negative),
                        {num(p[k][1], w + "[1]"), num(p[k][2], w + "[2]"), num(p[k][3], w + "[3]")}});
      if (k > 0 && !(h.path[k].t > h.path[k - 1].t)) bad_value(w + "[0]", "keyframe times must increase");
    }
  }
  if (j.contains("stiffness") && !h.as_spring)
    bad_value(where + ".stiffness",
              "the spring mode's (\"mode\": \"spring\"); the hard mode puts the node on its path");
  // Keys absent keep the scene's: a drag over a scene without one names both.
  if (d.node.kind == NodeSelector::Kind::index && d.node.index < 0)
    bad_value(where, "needs \"node\" (the scene has no drag node to keep)");
  if (h.path.empty()) bad_value(where, "needs \"path\" (the scene has no drag path to keep)");
}

}  // namespace

void apply_json(Scene& s, const json& j, const std::string& where, const std::string& dir) {
  only_keys(j, where, kSceneKeys);
  Params& p = s.params;
  if (j.contains("model")) apply_model(s.model, j["model"], where + ".model", dir);
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
    if (!a.is_array()) bad_value(where + ".spheres", "expected a list");
    if (a.size() > MAX_SPHERES)
      bad_value(where + ".spheres", "at most " + std::to_string(MAX_SPHERES) + " spheres are supported, the scene has " +
                                        std::to_string(a.size()));
    p.spheres.clear();
    for (std::size_t k = 0; k < a.size(); ++k) {
      const std::string w = where + ".spheres[" + std::to_string(k) + "]";
      only_keys(a[k], w, {"center", "radius"});
      if (!a[k].contains("center") || !a[k].contains("radius")) bad_value(w, "needs center and radius");
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
  // An object that gives both cannot give them the wrong way round; a max_steps alone below the
  // min_steps a scene takes leaves a convergence run no step to stop at, which the run says.
  if (j.contains("min_steps") && j.contains("max_steps") && p.min_steps > p.max_steps)
    bad_value(where + ".min_steps", "min_steps (" + std::to_string(p.min_steps) + ") exceeds max_steps (" +
                                        std::to_string(p.max_steps) + ")");
  if (j.contains("check_every")) p.check_every = integer(j["check_every"], where + ".check_every", 1);
  if (j.contains("runaway_factor"))
    p.runaway_factor = num(j["runaway_factor"], where + ".runaway_factor", Range::positive);
}

bool is_scene_key(const std::string& key) {
  return std::find(kSceneKeys.begin(), kSceneKeys.end(), key) != kSceneKeys.end();
}

Scene load_scene(const std::string& path) {
  Scene s;
  const json j = read_json_file(path, "scene file");
  if (j.is_object() && (j.contains("scene") || j.contains("sweep") || j.contains("base")))
    bad_value(path, "an experiment file (it has \"scene\", \"sweep\" or \"base\"), not a scene: give it as "
                    "--experiment");
  apply_json(s, j, path, std::filesystem::path(path).parent_path().string());
  return s;
}

}  // namespace deformlab
