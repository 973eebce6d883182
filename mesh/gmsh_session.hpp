// Gmsh through its API for the mesh loaders and generators (load.cpp, generate.cpp).
#pragma once
#include <gmsh.h>

#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/mesh_model.hpp"

namespace deformlab {

// Gmsh for the length of one task; its errors become exceptions with Gmsh's message (a failed
// allocation stays std::bad_alloc).
class GmshSession {
 public:
  GmshSession() {
    gmsh::initialize(0, nullptr, false);
    gmsh::option::setNumber("General.Terminal", 0);
    gmsh::option::setNumber("General.AbortOnError", 2);
  }
  ~GmshSession() { gmsh::finalize(); }
  GmshSession(const GmshSession&) = delete;
  GmshSession& operator=(const GmshSession&) = delete;

  template <class F>
  static void run(const std::string& what, F&& f) {
    try {
      f();
    } catch (const std::invalid_argument&) {
      throw;
    } catch (const std::bad_alloc&) {
      throw;
    } catch (...) {
      std::string error;
      gmsh::logger::getLastError(error);
      throw std::invalid_argument(what + ": " + (error.empty() ? "Gmsh failed" : error));
    }
  }
};

// The current Gmsh model's linear tetrahedra or, if it has none, its triangles; `what` names
// it in errors. With `notes`, a volume's triangles that bound no tetrahedron are counted there.
Mesh read_gmsh_model(const std::string& what, std::vector<std::string>* notes = nullptr);
// The current Gmsh model into `path` as binary MSH 4.1, through a partial file beside it that
// is renamed once Gmsh is done (a failed write leaves an existing file as it was, and throws
// WriteError); load_mesh reads it back as the same mesh: nodes, their order and the elements.
void write_gmsh_model(const std::string& path);

}  // namespace deformlab
