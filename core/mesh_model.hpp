// Models from meshes: a triangle surface (cloth, shells) or a tetrahedral volume (soft
// bodies), as a general model with its springs spelled out.
//
// Springs:
// - surface: every edge (structural) and, across every interior edge, a spring between the
//   two vertices opposite it (flexion), unless that pair is already a spring;
// - volume: every tetrahedron edge (structural) and, across every interior face, a spring
//   between the two vertices opposite it (flexion, the volume's analogue of bending), unless
//   that pair is already a spring. Volumes have no shear springs.
// Rest lengths come from the positions; node masses are lumped (a third of each triangle's
// area or a quarter of each tetrahedron's volume, times the density) or uniform.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "model.hpp"
#include "vec3.hpp"

namespace deformlab {

struct Mesh {
  std::vector<Vec3f> position;                            // [n]
  std::vector<std::array<std::int32_t, 3>> triangle;       // surfaces
  std::vector<std::array<std::int32_t, 4>> tetrahedron;    // volumes (then `triangle` is unused)
  bool volume() const { return !tetrahedron.empty(); }
};

// Checks a mesh as loaded and repairs what can be repaired, returning a line per repair:
// vertices at identical positions are welded, vertices no element uses are dropped (the
// others keep their order), elements repeated on the same vertices (after welding, in any
// order) are dropped but the first. Throws std::invalid_argument naming the first problem: no
// elements, an index out of range, a NaN or infinite coordinate, a degenerate element
// (repeated vertex, zero area or volume), an edge shared by more than two triangles or a
// face shared by more than two tetrahedra.
std::vector<std::string> repair(Mesh& m);

// For each vertex, the first vertex at its position (itself where none comes before it);
// 0 and -0 are one position.
std::vector<std::int32_t> first_at_same_position(const std::vector<Vec3f>& position);

// Whether some tetrahedron has zero volume (as repair finds it), four vertices in a plane.
bool has_flat_tetrahedron(const Mesh& m);

// Whether a vertex's coordinates are all finite, and "a vertex has a NaN or infinite coordinate
// (nan, 0, 0)": that error's words wherever a mesh's vertices are checked. The coordinates name
// the vertex: a library's vertex order need not be the file's.
bool finite_vertex(const Vec3f& p);
std::string non_finite_vertex(const Vec3f& p);

// The model of a repaired mesh. density > 0: lumped masses (kg/m^2 for surfaces, kg/m^3 for
// volumes); 0: every node weighs mat.node_mass. Model::triangle holds the surface (a
// volume's boundary faces, oriented outwards).
Model mesh_model(const Mesh& m, const Material& mat, float density);

// Upper bounds on the springs mesh_model makes, before it makes them (for memory checks).
std::int64_t mesh_spring_bound(const Mesh& m);

}  // namespace deformlab
