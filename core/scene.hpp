// Scene files: the model to build and the Params, as JSON. Every key is checked; an
// unknown key or a value of the wrong type is an error naming the key path.
#pragma once
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "model.hpp"
#include "node_order.hpp"
#include "params.hpp"

namespace deformlab {

// A mesh made by Gmsh's unstructured meshers instead of read from a file: a triangle sheet
// in the x-z plane (y = 0, centred on x = z = 0) or a tetrahedral box (centred on x = z = 0,
// from y = 0 up), its elements' edges about `cell_size` long.
struct MeshShape {
  enum class Kind : std::uint8_t { sheet, box } kind = Kind::sheet;
  Vec3f size{};  // m: sheet [w, 0, d] (x, z), box [w, h, d]
  float cell_size = 0.f;
  // Gmsh's threads (0: every core). On more than one a mesh differs a little from call to call;
  // on one a sheet is the same mesh each time (mesh/generate.cpp).
  int threads = 0;
};
const char* to_string(MeshShape::Kind k);
// The nodes Gmsh makes of a shape, estimated from its area and rim (a sheet) or volume and
// surface (a box), as measured on Gmsh 4.8's meshes: within 1% from 50 k nodes up.
double estimated_nodes(const MeshShape& s);
// The nodes Gmsh makes filling `volume` m^3 with tetrahedra of `cell_size`, by the same measure
// (its interior's share, which dominates at sizes worth estimating).
double estimated_filled_nodes(double volume, double cell_size);
// "Gmsh box 0.4 x 0.4 x 0.4 m, cell 0.00347 m" (and its threads where set).
std::string describe(const MeshShape& s);

// A model read from a mesh file or generated (ModelSpec::topology general).
struct MeshSpec {
  std::string file;  // OBJ, PLY, STL, glTF (surfaces) or Gmsh .msh (volumes); relative to the scene file
  std::optional<MeshShape> generate;  // instead of a file
  Vec3f scale{1.f, 1.f, 1.f};
  // Row-major affine map applied after the scale (the last row is 0 0 0 1).
  std::array<float, 12> transform{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  float density = 0.f;      // kg/m^2 (surfaces) or kg/m^3 (volumes); 0: node_mass for every node
  bool fill = false;        // fill a closed surface with tetrahedra
  float cell_size = 0.f;    // fill: largest tetrahedron edge, m (0: what the surface gives)
  NodeOrder order = NodeOrder::file;
  std::uint64_t seed = 1;   // order "shuffled"
  std::string where;        // the scene key of the layer that made the model a mesh, for errors
};

// A lattice's nodes along each axis where a scene makes one without giving its size.
inline constexpr int kDefaultLatticeSide = 32;

struct ModelSpec {
  Topology topology = Topology::cloth_grid;  // general: a mesh (read or generated)
  int nx = 128, ny = 128, nz = 1;
  float spacing = 0.f;  // 0: derived from `width` (width / (nx - 1); build_model_in_file_order)
  float width = 1.f;    // m, along x (along the next axis with more than one node where nx = 1)
  float height = 1.f;   // m, y of the cloth plane / bottom of the lattice
  MeshSpec mesh;
  Material material;
  PinSet pins = PinSet::top_corners;
  std::vector<NodeSelector> pin_list;
  // The scene key that names the pins in errors: where they were read, or, where a scene layer
  // made the model a mesh without giving pins, that layer's key for them marked absent.
  std::string pins_where;
};

// The shortest length a model takes (a grid's spacing, a generated mesh's sizes, a file mesh's
// springs), m: below it the spring force's floor on |d|^2 (node_physics.h) is within reach of
// float rounding.
constexpr double kShortestLength = 1e-6;

// The drag node: an index, "center" or the node nearest a point (resolved once the model exists).
struct DragSpec {
  bool enabled = false;
  NodeSelector node = NodeSelector::node(-1);
  bool offsets = true;  // path positions are offsets from the node's rest position
  std::string path_where = "drag.path";  // the scene key the path was read from, for errors
};

struct Scene {
  ModelSpec model;
  Params params;
  DragSpec drag;
};

// Fills `scene` from a JSON object (keys absent keep their current values). A relative mesh
// file is taken relative to `dir` (the folder of the file that names it).
void apply_json(Scene& scene, const nlohmann::json& j, const std::string& where, const std::string& dir = "");
// Whether `key` is one of a scene object's keys.
bool is_scene_key(const std::string& key);
// Reads a scene file; throws std::invalid_argument with the file name and the problem.
Scene load_scene(const std::string& path);

// The scene's Params for a built model (mesh/scene_model.hpp builds it): the drag node and its
// path resolved; throws std::invalid_argument for settings that do not fit the model.
Params resolve_params(const Scene& s, const Model& m);

nlohmann::json to_json(const Scene& s);

// "cloth 128x128", "lattice 8x8x8", "mesh data/bunny.ply filled with tetrahedra, order rcm",
// "mesh: Gmsh sheet 1.0 x 1.0 m, cell 0.001 m, order rcm"
std::string describe(const ModelSpec& m);

}  // namespace deformlab
