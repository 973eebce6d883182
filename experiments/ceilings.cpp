#include "ceilings.hpp"

#include <fstream>
#include <stdexcept>

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

std::optional<Bound> vertices_at(double vertices, double per_s) {
  if (per_s <= 0) return std::nullopt;
  return Bound{vertices / per_s * 1e3, "one transform feedback vertex per node and evaluation"};
}

bool starts_with(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

}  // namespace

Ceilings ceilings_of(const json& cal) {
  Ceilings c;
  if (!cal.is_object()) return c;
  c.copy_gb_s = positive_at(cal, "copy", "GB_per_s");
  c.compute_copy_gb_s = positive_at(cal, "compute_copy", "GB_per_s");
  c.tf_vertices_s = positive_at(cal, "transform_feedback", "vertices_per_s");
  c.floor_us = positive_at(cal, "floor", "us_per_hand_off");
  return c;
}

json read_calibration(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::invalid_argument("cannot read the calibration file " + file.string());
  const json j = json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object())
    throw std::invalid_argument(file.string() + ": not a JSON object (expected `deformlab calibrate --out`'s file)");
  if (!ceilings_of(j).any())
    throw std::invalid_argument(file.string() +
                                ": no ceilings in it (copy.GB_per_s, compute_copy.GB_per_s, "
                                "transform_feedback.vertices_per_s or floor.us_per_hand_off)");
  return j;
}

std::optional<Bound> stage_ceiling(const Ceilings& c, const std::string& pipeline, const std::string& stage,
                                   std::int64_t nodes, Integrator integrator) {
  const double evals = info(integrator).force_passes, n = double(nodes) * evals;
  const bool hybrid = starts_with(pipeline, "hybrid");
  const bool tf_update = pipeline == "glsl-tf" || pipeline == "hybrid";
  const std::string copy = "at the CUDA copy bandwidth";
  if (stage == span::force && (hybrid || starts_with(pipeline, "cuda-")))
    return bytes_at(48 * n, c.copy_gb_s, "x, v read, a written once per evaluation (48 B/node) " + copy);
  if (stage == span::update && starts_with(pipeline, "cuda-"))
    return bytes_at(80 * n, c.copy_gb_s, "x, v, a read, x, v written once per evaluation (80 B/node) " + copy);
  if (stage == span::update && hybrid)
    return tf_update ? vertices_at(n, c.tf_vertices_s)
                     : bytes_at(80 * n, c.compute_copy_gb_s,
                                "x, v, a read, x, v written once per evaluation (80 B/node) at the compute-shader "
                                "copy bandwidth");
  if (stage == span::hand_off && hybrid && c.floor_us > 0)
    return Bound{2 * evals * c.floor_us * 1e-3, "two hand-offs per evaluation at the floor"};
  const bool whole = stage == "step" || stage == span::force_update;
  if (whole && starts_with(pipeline, "cuda-"))
    return bytes_at(64 * n, c.copy_gb_s, "x, v read and written once per evaluation (64 B/node) " + copy);
  if (whole && pipeline == "glsl-compute")
    return bytes_at(64 * n, c.compute_copy_gb_s,
                    "x, v read and written once per evaluation (64 B/node) at the compute-shader copy bandwidth");
  if (whole && pipeline == "glsl-tf") return vertices_at(n, c.tf_vertices_s);
  if (stage == "step" && hybrid) {
    const auto f = stage_ceiling(c, pipeline, span::force, nodes, integrator);
    const auto u = stage_ceiling(c, pipeline, span::update, nodes, integrator);
    const auto h = stage_ceiling(c, pipeline, span::hand_off, nodes, integrator);
    if (!f || !u || !h) return std::nullopt;
    return Bound{f->ms + u->ms + h->ms, "its force and update ceilings plus two floors per evaluation"};
  }
  return std::nullopt;
}

}  // namespace deformlab
