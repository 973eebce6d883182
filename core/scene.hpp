// Scene files: the model to build and the Params, as JSON. Every key is checked; an
// unknown key or a value of the wrong type is an error naming the key path.
#pragma once
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "model.hpp"
#include "params.hpp"

namespace deformlab {

struct ModelSpec {
  Topology topology = Topology::cloth_grid;
  int nx = 128, ny = 128, nz = 1;
  float spacing = 0.f;  // 0: derived from `width` (cloth: width / (nx - 1))
  float width = 1.f;    // m, along x
  float height = 1.f;   // m, y of the cloth plane / bottom of the lattice
  Material material;
  PinSet pins = PinSet::top_corners;
  std::vector<int> pin_list;
};

// How a drag node is named in a file: an index, or "center" (resolved once the model exists).
struct DragSpec {
  bool enabled = false;
  bool center = false;
  int node = -1;
  bool offsets = true;  // path positions are offsets from the node's rest position
};

struct Scene {
  ModelSpec model;
  Params params;
  DragSpec drag;
};

// Fills `scene` from a JSON object (keys absent keep their current values).
void apply_json(Scene& scene, const nlohmann::json& j, const std::string& where);
// Reads a scene file; throws std::invalid_argument with the file name and the problem.
Scene load_scene(const std::string& path);

// Builds the model (with pins) and resolves the drag node and path; throws
// std::invalid_argument for sizes or settings that cannot be built.
Model build_model(const Scene& s);
Params resolve_params(const Scene& s, const Model& m);

nlohmann::json to_json(const Scene& s);

}  // namespace deformlab
