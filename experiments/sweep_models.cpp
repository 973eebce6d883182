#include "sweep_models.hpp"

#include <algorithm>
#include <filesystem>
#include <set>
#include <stdexcept>

#include "core/json_file.hpp"
#include "mesh/scene_model.hpp"

namespace deformlab {

using nlohmann::json;

namespace {

// The experiment's scene with model `m`; under a sweep's orders its seed is read for the
// shuffled order (each cell then takes its own).
Scene model_scene(const Experiment& x, const Sweep& s, const json& m, const std::string& where) {
  Scene scene = x.scene;
  scene.model.topology = Topology::general;
  if (!s.orders.empty()) scene.model.mesh.order = NodeOrder::shuffled;
  apply_json(scene, {{"model", m}}, where, x.dir);
  return scene;
}

}  // namespace

std::string model_key(const Sweep& s, std::size_t k) { return s.where + ".sweep.models[" + std::to_string(k) + "]"; }

std::string model_key(const Sweep& s, const std::string& name) {
  const auto m = std::find_if(s.models.begin(), s.models.end(), [&](const SweepModel& e) { return e.name == name; });
  return model_key(s, std::size_t(m - s.models.begin()));
}

std::vector<SweepModel> parse_sweep_models(const json& j, const std::string& where) {
  if (!j.is_array() || j.empty()) bad_value(where, "expected a non-empty list of {\"name\": ..., \"model\": {...}}");
  std::vector<SweepModel> out;
  std::set<std::string> names;
  for (std::size_t k = 0; k < j.size(); ++k) {
    const std::string w = where + "[" + std::to_string(k) + "]";
    const json& e = j[k];
    if (!e.is_object() || e.size() != 2 || !e.contains("name") || !e.contains("model"))
      bad_value(w, "expected {\"name\": ..., \"model\": {...}}");
    const std::string name = e["name"].is_string() ? e["name"].get<std::string>() : "";
    if (!is_plain_name(name)) bad_value(w + ".name", kPlainName);
    if (name.find("__") != std::string::npos)
      bad_value(w + ".name", "'" + name + "' holds \"__\", which joins the parts of a cell's name (a cell of "
                             "another model could take the same name)");
    if (!names.insert(name).second) bad_value(w + ".name", "model '" + name + "' is named twice");
    // Alone, as under a sweep's orders: its seed read for the shuffled order (model_scene reads
    // it over the experiment's scene before the first cell).
    Scene probe;
    probe.model.topology = Topology::general;
    probe.model.mesh.order = NodeOrder::shuffled;
    apply_json(probe, {{"model", e["model"]}}, w);
    if (probe.model.topology != Topology::general)
      bad_value(w + ".model.type", "sweep models are meshes (\"type\": \"mesh\")");
    out.push_back({name, e["model"]});
  }
  return out;
}

std::vector<std::string> parse_sweep_orders(const json& j, const std::string& where) {
  if (!j.is_array() || j.empty()) bad_value(where, std::string("expected a non-empty list of: ") + kNodeOrderNames);
  std::vector<std::string> out;
  for (const auto& o : j) {
    if (!o.is_string() || !parse_node_order(o.get<std::string>()))
      bad_value(where, std::string("expected a list of: ") + kNodeOrderNames);
    if (std::find(out.begin(), out.end(), o.get<std::string>()) != out.end())
      bad_value(where, "order '" + o.get<std::string>() + "' is named twice");
    out.push_back(o.get<std::string>());
  }
  return out;
}

void check_models_under_orders(const Sweep& s, const std::string& where) {
  if (s.orders.empty()) return;
  const bool shuffled = std::find(s.orders.begin(), s.orders.end(), "shuffled") != s.orders.end();
  for (std::size_t k = 0; k < s.models.size(); ++k) {
    const json& m = s.models[k].model;
    const std::string w = where + ".models[" + std::to_string(k) + "].model";
    if (m.contains("order")) bad_value(w + ".order", "the sweep's \"orders\" give every cell its order");
    if (m.contains("seed") && !shuffled)
      bad_value(w + ".seed", "seeds the shuffled order, which the sweep's \"orders\" leave out");
  }
}

void require_model_files(const Experiment& x, const Sweep& s) {
  for (std::size_t k = 0; k < s.models.size(); ++k) {
    const std::string at = model_key(s, k), w = at + ".model";
    Scene scene = model_scene(x, s, s.models[k].model, at);
    std::error_code ec;
    const std::string& file = scene.model.mesh.file;
    if (!file.empty() && !std::filesystem::is_regular_file(file, ec))
      bad_value(w + ".file", "'" + file + "': " +
                                 (ec && ec != std::errc::no_such_file_or_directory ? ec.message() : "no such file"));
    try {
      check_mesh_file(scene);  // its errors name the file, or the key (pins, the drag node)
    } catch (const std::invalid_argument& e) {
      if (!scene.model.mesh.generate) throw;
      throw std::invalid_argument(at + ": " + e.what());  // a generated shape placed where floats cannot hold it
    }
  }
}

Scene model_cell_scene(const Experiment& x, const Sweep& s, const Cell& c) {
  const auto m = std::find_if(s.models.begin(), s.models.end(), [&](const SweepModel& e) { return e.name == c.model; });
  Scene scene = model_scene(x, s, m->model, model_key(s, std::size_t(m - s.models.begin())));
  if (!c.order.empty()) scene.model.mesh.order = *parse_node_order(c.order);
  return scene;
}

const Model& ModelCache::model(const Scene& scene, const Cell& c) {
  const std::string base = c.model.empty() ? "size " + std::to_string(c.size) : "model " + c.model;
  const bool file_order = scene.model.topology != Topology::general || scene.model.mesh.order == NodeOrder::file;
  const std::string order = file_order ? "file" : to_string(scene.model.mesh.order);
  if (base != base_key_ || !base_) {
    ordered_.reset();  // free the old ones before building the next
    base_.reset();
    base_key_.clear();
    base_ = std::make_unique<Model>(build_model_in_file_order(scene));
    base_key_ = base;
    order_key_.clear();
    ++bases_;
  }
  if (order != order_key_) {
    ordered_.reset();
    order_key_.clear();
    if (!file_order) {
      ordered_ = std::make_unique<Model>(*base_);
      apply_node_order(*ordered_, scene.model);
    }
    order_key_ = order;
    ++models_;
  }
  return file_order ? *base_ : *ordered_;
}

}  // namespace deformlab
