// Model: everything that does not change during a run (cf. MuJoCo's mjModel).
// Sizes: n = node_count(), s = spring_count().
//
// Two shapes behind one interface (core/springs.hpp walks the springs of either):
// - a grid (cloth or lattice) is its stencil: dimensions, spacing, per-kind constants, rest
//   positions and inverse masses; no spring arrays and no adjacency. Host bytes per node:
//   kGridBytesPerNode.
// - a general model spells its springs out (spring_i/j, rest lengths, kinds, optional
//   per-spring constants) with their CSR adjacency.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <tuple>
#include <vector>

#include "grid_stencil.hpp"
#include "memory.hpp"
#include "vec3.hpp"

namespace deformlab {

enum class SpringKind : std::uint8_t { structural = 0, shear = 1, flexion = 2 };
inline constexpr int kSpringKinds = 3;
const char* to_string(SpringKind k);

// How nodes are laid out. A grid's springs are its stencil (grid_stencil.hpp) at every node;
// general models have spring lists (explicit_springs() turns a grid into one).
enum class Topology : std::uint8_t { general, cloth_grid, lattice };

struct Model {
  Topology topology = Topology::general;
  int nx = 0, ny = 0, nz = 0;  // grid dims (cloth: nz = 1); node (i,j,k) = (k*ny + j)*nx + i
  float spacing = 0.f;         // rest distance between structural neighbours (grids)

  std::vector<Vec3f> rest_position;  // [n] rest (initial) positions
  std::vector<float> inv_mass;       // [n] 1/m; 0 marks a pinned node

  // General models only (empty for grids):
  std::vector<std::int32_t> spring_i, spring_j;  // [s] end nodes, i < j
  std::vector<float> rest_length;                // [s]
  std::vector<SpringKind> kind;                  // [s]
  std::array<float, kSpringKinds> stiffness{};   // per kind, N/m (all models)
  std::array<float, kSpringKinds> damping{};     // per kind, along the spring axis, N s/m (all models)
  // [s] or empty: per-spring stiffness (N/m) and damping (N s/m) of general models, which
  // then replace the per-kind values. Grids keep per-kind values.
  std::vector<float> spring_stiffness, spring_damping;

  // Node -> incident springs (CSR): node v's springs are adj_spring[adj_offset[v] ..
  // adj_offset[v+1]), adj_node holds the spring's other end. [n+1], [2s], [2s].
  std::vector<std::int32_t> adj_offset, adj_spring, adj_node;

  // Models from mesh files (empty otherwise):
  std::vector<std::int32_t> triangle;   // [3t] surface triangles (a volume's boundary), for drawing
  std::vector<std::int32_t> file_node;  // [n] or empty: node v is node file_node[v] of the mesh as loaded
  std::vector<std::string> repairs;     // what loading repaired, a line each ("welded 12 duplicate vertices")

  int node_count() const { return int(rest_position.size()); }
  std::int64_t spring_count() const;  // grids: in closed form
  bool pinned(int v) const { return inv_mass[v] == 0.f; }
  bool grid() const { return topology != Topology::general; }
  bool volume() const { return topology == Topology::lattice || nz > 1; }  // lattice stencil
  // Constants of general spring e.
  float spring_k(int e) const { return spring_stiffness.empty() ? stiffness[int(kind[e])] : spring_stiffness[e]; }
  float spring_kd(int e) const { return spring_damping.empty() ? damping[int(kind[e])] : spring_damping[e]; }
  // Whether any spring is damped (a kernel may then skip the neighbours' velocities).
  bool damped() const;
  // Recomputes adj_* from spring_i/j (ordered by spring index within each node).
  void build_adjacency();
  // Node v's index in the mesh as loaded (v itself unless the nodes were reordered).
  int file_index(int v) const { return file_node.empty() ? v : file_node[v]; }
  // Largest distance between two rest positions' bounding-box corners.
  float extent() const;
  ModelSize size() const { return {node_count(), spring_count(), grid()}; }
  // Bytes the model holds on the host (its arrays' capacities).
  std::int64_t host_bytes() const;
};

// Host bytes per node of a grid model: rest position (12) and inverse mass (4).
inline constexpr std::int64_t kGridBytesPerNode = 16;

struct Material {
  std::array<float, kSpringKinds> stiffness{500.f, 500.f, 100.f};
  std::array<float, kSpringKinds> damping{0.f, 0.f, 0.f};
  float node_mass = 0.01f;  // kg per node
};

// Throws std::invalid_argument for more than 2^30 nodes (the count in double: a lattice's can
// pass what 64 bits hold).
void check_node_count(double nodes);

// Cloth: nx x ny nodes in the x-z plane at height y0, centred on x = z = 0, spacing h.
// Grid row j = 0 is the "top" row (its corners are the "top corners").
Model cloth_grid(int nx, int ny, float spacing, float y0, const Material& m);
// Lattice: nx x ny x nz nodes, y up (layer j = ny-1 is the top), centred on x = z = 0,
// bottom layer at height y0. Shear springs are the 12 face and 8 body diagonals.
Model lattice(int nx, int ny, int nz, float spacing, float y0, const Material& m);

// Spring counts in closed form, per kind (what the builders must produce).
std::array<std::int64_t, kSpringKinds> cloth_spring_counts(std::int64_t nx, std::int64_t ny);
std::array<std::int64_t, kSpringKinds> lattice_spring_counts(std::int64_t nx, std::int64_t ny,
                                                             std::int64_t nz);

// Nodes named in a scene: by index (in the file's order for meshes), or by position so that
// one scene fits any mesh: every node inside a box, every node on or below a plane, the node
// nearest a point, or the centre (a grid's middle node; else the node nearest the middle of
// the rest shape's bounding box).
struct NodeSelector {
  enum class Kind : std::uint8_t { index, box, below, nearest, center } kind = Kind::index;
  int index = -1;
  Vec3f a{}, b{};  // box: lowest and highest corner; below: a point of the plane and its upward normal; nearest: a
  std::string where;  // the scene key it was read from, for errors (empty: made in code)
  static NodeSelector node(int v) { return {Kind::index, v}; }
  bool single() const { return kind == Kind::index || kind == Kind::nearest || kind == Kind::center; }
  // What it selects by, without `where`: equal for two selectors that pick the same nodes alike.
  auto key() const { return std::tuple(kind, index, a.x, a.y, a.z, b.x, b.y, b.z); }
};
// The model's nodes a selector picks, in ascending order (model numbering); throws
// std::invalid_argument when an index is outside the model or a selector picks nothing (its
// callers put the selector's scene key before the message).
std::vector<int> select_nodes(const Model& m, const NodeSelector& s);

enum class PinSet : std::uint8_t { none, top_corners, top_row, list };
// Nodes of a pin set: top corners / top row of a grid or lattice, or every node the list's
// selectors pick. Errors name the scene key: `where` (the set's) or the selector's own.
std::vector<int> pin_nodes(const Model& m, PinSet set, const std::vector<NodeSelector>& list,
                           const std::string& where = "");
void pin(Model& m, const std::vector<int>& nodes);

// Rest length of a grid's springs along offset o: spacing x |o|.
float grid_rest_length(const Model& m, const GridOffset& o);

// The same model with its springs spelled out as a general model (same springs, in the
// order for_each_spring visits them).
Model explicit_springs(const Model& grid);

}  // namespace deformlab
