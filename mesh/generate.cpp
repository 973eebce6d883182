#include "generate.hpp"

#include <cmath>
#include <stdexcept>
#include <thread>
#include <vector>

#include "core/mesh_model.hpp"
#include "gmsh_session.hpp"

namespace deformlab {

namespace {

// Gmsh 4.8's 2D Delaunay slows down faster than linearly on one large surface (on 2 cores:
// 64 k nodes/s at 80 k nodes, 17 k nodes/s at 330 k), so a sheet is meshed as a grid of
// rectangles of about this many nodes each, sharing their edges (one conforming mesh; nodes
// line up along the seams, and Gmsh's order goes tile by tile).
constexpr double kNodesPerTile = 5000;

// The sheet as tx x tz plane surfaces of the built-in kernel, sharing points and lines: tiles as
// near square as the sheet allows (a strip one tile across takes them all along its length; thin
// tiles, narrower than a cell, made Gmsh place twice the nodes, slowly).
void add_sheet(const MeshShape& s) {
  namespace geo = gmsh::model::geo;
  const double tiles = estimated_nodes(s) / kNodesPerTile, aspect = double(s.size.x) / double(s.size.z);
  int tx = std::max(1, int(std::ceil(std::sqrt(tiles * aspect))));
  int tz = std::max(1, int(std::ceil(std::sqrt(tiles / aspect))));
  if (tz == 1) tx = std::max(1, int(std::ceil(tiles)));
  if (tx == 1) tz = std::max(1, int(std::ceil(tiles)));
  std::vector<int> point, along_x, along_z;  // at (i, k): i + k * (tx + 1)
  for (int k = 0; k <= tz; ++k)
    for (int i = 0; i <= tx; ++i)
      point.push_back(geo::addPoint(s.size.x * (double(i) / tx - 0.5), 0, s.size.z * (double(k) / tz - 0.5)));
  auto at = [&](int i, int k) { return std::size_t(i + k * (tx + 1)); };
  for (int k = 0; k <= tz; ++k)
    for (int i = 0; i <= tx; ++i) {
      along_x.push_back(i < tx ? geo::addLine(point[at(i, k)], point[at(i + 1, k)]) : 0);
      along_z.push_back(k < tz ? geo::addLine(point[at(i, k)], point[at(i, k + 1)]) : 0);
    }
  for (int k = 0; k < tz; ++k)
    for (int i = 0; i < tx; ++i)
      geo::addPlaneSurface({geo::addCurveLoop(
          {along_x[at(i, k)], along_z[at(i + 1, k)], -along_x[at(i, k + 1)], -along_z[at(i, k)]})});
  geo::synchronize();
}

void add_box(const MeshShape& s) {
  gmsh::model::occ::addBox(-0.5 * s.size.x, 0, -0.5 * s.size.z, s.size.x, s.size.y, s.size.z);
  gmsh::model::occ::synchronize();
}

}  // namespace

// Algorithms, as measured on a 2-core machine (Gmsh 4.8, generate_shape alone):
// - sheets: 2D Delaunay (Mesh.Algorithm 5) over tiles: 62 k nodes/s at 50 k nodes, 70 k at
//   200 k, 83 k at 1 M; Frontal-Delaunay (6) made 22 k nodes/s at 330 k (and 12% fewer nodes
//   per area). Gmsh meshes the tiles on its 2D threads.
// - boxes: HXT (Mesh.Algorithm3D 10), parallel: 54 k nodes/s at 57 k nodes, 62 k at 210 k,
//   39 k at 1 M on 2 threads (42 k at 490 k on one); Delaunay (1, serial) made 5.6 k nodes/s at
//   130 k. Gmsh 4.8 runs HXT on one thread unless Mesh.MaxNumThreads3D is set, so every
//   stage's thread count is set here.
// On more than one thread both make a slightly different mesh on every call (a 146 k-node sheet:
// 146,333 to 146,388 nodes). On one a sheet is the same mesh each time; a box is not within one
// process (Gmsh 4.8 hands HXT the boundary's nodes in the order of their addresses).
// HXT leaves a flat tetrahedron, four nodes in a plane, which a model refuses, in many boxes of
// two cells a side (within one process, 4 to 22 calls in 40 on 2 threads, 13 to 19 on one; none
// at 3 to 10 cells a side, nor in a 0.2 x 0.1 x 0.3 m box of 0.01 m cells): such a box is meshed
// again with Gmsh's serial Delaunay (Mesh.Algorithm3D 1), which left none in those boxes.
Mesh generate_shape(const MeshShape& s, const std::string& save_to) {
  GmshSession gmsh;
  Mesh m;
  const std::string what = std::string("generating a Gmsh ") + to_string(s.kind);
  GmshSession::run(what, [&] {
    gmsh::model::add("generated");
    const double threads = s.threads > 0 ? unsigned(s.threads) : std::max(1u, std::thread::hardware_concurrency());
    for (const char* o : {"General.NumThreads", "Mesh.MaxNumThreads1D", "Mesh.MaxNumThreads2D", "Mesh.MaxNumThreads3D"})
      gmsh::option::setNumber(o, threads);
    gmsh::option::setNumber("Mesh.MeshSizeMin", s.cell_size);
    gmsh::option::setNumber("Mesh.MeshSizeMax", s.cell_size);
    gmsh::option::setNumber("Mesh.MeshSizeFromPoints", 0);
    gmsh::option::setNumber("Mesh.MeshSizeFromCurvature", 0);
    gmsh::option::setNumber("Mesh.MeshSizeExtendFromBoundary", 0);
    gmsh::option::setNumber("Mesh.Algorithm", 5);
    gmsh::option::setNumber("Mesh.Algorithm3D", 10);
    const bool sheet = s.kind == MeshShape::Kind::sheet;
    if (sheet) add_sheet(s);
    else add_box(s);
    gmsh::model::mesh::generate(sheet ? 2 : 3);
    m = read_gmsh_model(what);
    if (!sheet && has_flat_tetrahedron(m)) {
      gmsh::model::mesh::clear();
      gmsh::option::setNumber("Mesh.Algorithm3D", 1);
      gmsh::model::mesh::generate(3);
      m = read_gmsh_model(what);
    }
    if (!save_to.empty()) write_gmsh_model(save_to);
  });
  return m;
}

}  // namespace deformlab
