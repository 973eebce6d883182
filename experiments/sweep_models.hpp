// The mesh-model axes of a sweep (sweep.hpp): "models" and "orders", each model cell's scene
// and the cache of built models.
#pragma once
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "experiment.hpp"
#include "sweep.hpp"

namespace deformlab {

// "models": [{"name": ..., "model": {...}}, ...]: names file-name safe and distinct, each model
// a mesh model as a scene would read it (checked here, its files read when its cells run).
std::vector<SweepModel> parse_sweep_models(const nlohmann::json& j, const std::string& where);
// "orders": node order names, distinct.
std::vector<std::string> parse_sweep_orders(const nlohmann::json& j, const std::string& where);
// Under "orders" a model gives no order of its own, and a seed only where they name shuffled.
void check_models_under_orders(const Sweep& s, const std::string& where);

// Throws std::invalid_argument naming the first model whose mesh file is missing or cannot be
// read and repaired, or whose generated shape floats cannot hold where it is placed
// (check_mesh_file; relative files from the experiment's folder): checked before the first cell
// runs. A model generated or filled is meshed, and its model checked, at its first cell.
void require_model_files(const Experiment& x, const Sweep& s);

// The key path of the sweep's model k, or of the model named so, for errors:
// "x.json.sweep.models[k]".
std::string model_key(const Sweep& s, std::size_t k);
std::string model_key(const Sweep& s, const std::string& name);

// The experiment's scene with a model cell's model (relative files from the experiment's
// folder) and order.
Scene model_cell_scene(const Experiment& x, const Sweep& s, const Cell& c);

}  // namespace deformlab
