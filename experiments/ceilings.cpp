#include "ceilings.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/json_file.hpp"
#include "core/profiler.hpp"

namespace deformlab {

using nlohmann::json;

namespace {

double positive_at(const json& j, const char* object, const char* key) {
  if (!j.contains(object) || !j[object].is_object()) return 0;
  const json& o = j[object];
  if (!o.contains(key) || !o[key].is_number()) return 0;
  const double v = o[key].get<double>();
  return v > 0 ? v : 0;
}

std::optional<Bound> bytes_at(double bytes, double gb_s, const std::string& what) {
  if (gb_s <= 0) return std::nullopt;
  return Bound{bytes / (gb_s * 1e9) * 1e3, what};
}

// One pass over `n` nodes on `e`, moving `bytes` per node where it moves bytes; `what` says
// what it moves.
std::optional<Bound> pass_at(const Ceilings& c, Engine e, double bytes, double n, const std::string& what) {
  switch (e) {
    case Engine::cuda: return bytes_at(bytes * n, c.copy_gb_s, what + " at the CUDA copy bandwidth");
    case Engine::gl_compute:
      return bytes_at(bytes * n, c.compute_copy_gb_s, what + " at the compute-shader copy bandwidth");
    case Engine::gl_transform_feedback:
      if (c.tf_vertices_s <= 0) return std::nullopt;
      return Bound{n / c.tf_vertices_s * 1e3, "one transform feedback vertex per node and evaluation"};
    case Engine::cpu: break;
  }
  return std::nullopt;
}

}  // namespace

Ceilings ceilings_of(const json& cal) {
  Ceilings c;
  if (!cal.is_object()) return c;
  c.copy_gb_s = positive_at(cal, "copy", "GB_per_s");
  c.compute_copy_gb_s = positive_at(cal, "compute_copy", "GB_per_s");
  c.tf_vertices_s = positive_at(cal, "transform_feedback", "vertices_per_s");
  c.floor_us = positive_at(cal, "floor", "us_per_hand_off");
  if (const json d = cal.value("device", json::object()); d.is_object() && d.value("name", json()).is_string())
    c.device = d["name"];
  return c;
}

json read_calibration(const std::filesystem::path& file) {
  const json j = read_json_file(file.string(), "calibration file");
  if (!j.is_object())
    throw std::invalid_argument(file.string() + ": not a JSON object (expected `deformlab calibrate --out`'s file)");
  // The measures a report divides by, each where given a number in a range a device can have.
  struct Measure {
    const char *object, *key;
    double least, most;
  };
  for (const Measure& m : {Measure{"copy", "GB_per_s", 1e-3, 1e6}, Measure{"compute_copy", "GB_per_s", 1e-3, 1e6},
                           Measure{"compute_copy_gl_buffers", "GB_per_s", 1e-3, 1e6},
                           Measure{"transform_feedback", "vertices_per_s", 1, 1e14},
                           Measure{"floor", "us_per_hand_off", 1e-3, 1e6}}) {
    if (!j.contains(m.object)) continue;
    const std::string at = file.string() + "." + m.object;
    if (!j[m.object].is_object()) throw std::invalid_argument(at + ": expected an object");
    if (!j[m.object].contains(m.key)) continue;
    const json& v = j[m.object][m.key];
    if (!v.is_number() || !(v.get<double>() >= m.least && v.get<double>() <= m.most)) {
      std::ostringstream range;
      range << m.least << " to " << m.most;
      throw std::invalid_argument(at + "." + m.key + ": expected a number from " + range.str());
    }
  }
  // What the report names beside the ceilings: the device and where the compute-shader copy ran.
  if (j.contains("device") && (!j["device"].is_object() || (j["device"].contains("name") && !j["device"]["name"].is_string())))
    throw std::invalid_argument(file.string() + ".device: expected an object whose \"name\" is text");
  if (j.contains("compute_copy") && j["compute_copy"].contains("memory") && !j["compute_copy"]["memory"].is_string())
    throw std::invalid_argument(file.string() + ".compute_copy.memory: expected text (gl or cuda)");
  if (!ceilings_of(j).any())
    throw std::invalid_argument(file.string() +
                                ": no ceilings in it (copy.GB_per_s, compute_copy.GB_per_s, "
                                "transform_feedback.vertices_per_s or floor.us_per_hand_off)");
  return j;
}

double mesh_adjacency_bytes(std::int64_t nodes, std::int64_t springs) {
  return nodes > 0 ? 4.0 + 16.0 * 2.0 * double(springs) / double(nodes) : 0.0;
}

std::optional<Bound> stage_ceiling(const Ceilings& c, const PipelineTraits& t, const std::string& stage,
                                   std::int64_t nodes, Integrator integrator, double adjacency_b) {
  const double evals = info(integrator).force_passes, n = double(nodes) * evals;
  // "x, v read ... (48 B/node)", or with a mesh's adjacency "(48 + 196 = 244 B/node)".
  auto per_node = [&](int state_b) {
    std::ostringstream os;
    if (adjacency_b > 0) {
      const long adj = std::lround(adjacency_b);
      os << "and the adjacency (" << state_b << " + " << adj << " = " << state_b + adj << " B/node)";
    } else {
      os << "(" << state_b << " B/node)";
    }
    return os.str();
  };
  if (stage == span::force)
    return pass_at(c, t.force, 48 + adjacency_b, n, "x, v read, a written once per evaluation " + per_node(48));
  if (stage == span::update)
    return pass_at(c, t.update, 80, n, "x, v, a read, x, v written once per evaluation (80 B/node)");
  if (!t.hands_off()) {
    if (stage != span::step && stage != span::force_update) return std::nullopt;
    return pass_at(c, t.force, 64 + adjacency_b, n, "x, v read and written once per evaluation " + per_node(64));
  }
  if (stage == span::hand_off && c.floor_us > 0)
    return Bound{2 * evals * c.floor_us * 1e-3, "two hand-offs per evaluation at the floor"};
  if (stage != span::step) return std::nullopt;
  const auto f = stage_ceiling(c, t, span::force, nodes, integrator, adjacency_b);
  const auto u = stage_ceiling(c, t, span::update, nodes, integrator);
  const auto h = stage_ceiling(c, t, span::hand_off, nodes, integrator);
  if (!f || !u || !h) return std::nullopt;
  return Bound{f->ms + u->ms + h->ms, "its force and update ceilings plus two floors per evaluation"};
}

}  // namespace deformlab
