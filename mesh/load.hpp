// Mesh files: triangle surfaces through assimp (OBJ, PLY, STL, glTF and the other formats it
// reads), tetrahedral volumes from Gmsh's .msh through the Gmsh API, and a closed surface
// filled with tetrahedra by Gmsh's 3D mesher.
#pragma once
#include <stdexcept>
#include <string>

#include "core/mesh_model.hpp"

namespace deformlab {

// A mesh file that could not be written: the message names that file, so callers that name
// their input in errors leave this one as it is.
struct WriteError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// Reads a mesh as its library gives it (Gmsh: .msh, nodes in Gmsh's order; assimp: everything
// else, vertices in the order assimp delivers them: for OBJ, the order in which faces first use
// them). Polygons are split into triangles; vertices at one position (bit for bit, 0 and -0
// alike) within an object of the file (a node of its scene graph, all its materials' and
// primitives' meshes) are joined (OBJ and STL repeat a vertex per face), and those shared
// between objects are left for repair() to weld and count. Positions no face of their object
// uses, points and lines are left out and counted in `notes`.
// Throws std::invalid_argument naming the file and the problem.
Mesh load_mesh(const std::string& path, std::vector<std::string>& notes);

// Whether the file starts with a section that Gmsh reads as a mesh ("$MeshFormat", "$Comments",
// or an older format's "$NO", "$ELM", "$PTS", "$PARA"): Gmsh reads any other .msh file as a
// .geo script.
bool starts_as_gmsh_mesh(const std::string& path);

// The closed surface filled with tetrahedra (Gmsh, its nodes kept); cell_size > 0 caps the
// tetrahedra's edges. With `save_to`, Gmsh also writes the filled mesh there (write_gmsh_model).
// Throws std::invalid_argument when Gmsh cannot fill it, WriteError when it cannot write it.
Mesh fill_tetrahedra(const Mesh& surface, float cell_size, const std::string& save_to = {});

// The mesh libraries' versions, "assimp 5.2.5, Gmsh 4.11.1", for manifests (build_info).
std::string mesh_library_versions();

}  // namespace deformlab
