// The springs of a model, whichever its shape: grids by their stencil, general models by
// their spring lists and adjacency. Stages on the CPU that need springs one by one (the implicit
// solve, energies, the stability bound) walk them here; the GPU kernels read the stencil, the
// adjacency or the spring list directly.
#pragma once
#include <algorithm>
#include <cstdint>

#include "model.hpp"
#include "physics.hpp"

namespace deformlab {

// A grid's index maths (core/node_physics.h), the same for every precision.
using Grid = Physics<float>;

// Model m's grid dimensions, as the index maths reads them (Grid::grid_neighbour).
inline Grid::StepParams grid_extent(const Model& m) {
  Grid::StepParams p{};
  p.nx = m.nx;
  p.ny = m.ny;
  p.nz = m.nz;
  return p;
}

struct SpringRef {
  int i, j;  // end nodes, i < j
  float rest, k, kd;
  SpringKind kind;
};

// f(SpringRef) for every spring once. Grids: node by node, each node's own stencil half.
template <class F>
void for_each_spring(const Model& m, F&& f) {
  if (!m.grid()) {
    for (std::int64_t e = 0; e < m.spring_count(); ++e)
      f(SpringRef{m.spring_i[e], m.spring_j[e], m.rest_length[e], m.spring_k(int(e)), m.spring_kd(int(e)),
                  m.kind[e]});
    return;
  }
  const int size = grid_stencil_size(m.volume());
  const Grid::StepParams extent = grid_extent(m);
  for (int k = 0; k < m.nz; ++k)
    for (int j = 0; j < m.ny; ++j)
      for (int i = 0; i < m.nx; ++i)
        for (int e = size / 2; e < size; ++e) {
          const GridOffset o = grid_offset(m.volume(), e);
          const int v = Grid::grid_neighbour(extent, i, j, k, o.di, o.dj, o.dk);
          if (v < 0) continue;
          const int u = Grid::grid_node(i, j, k, m.nx, m.ny);
          f(SpringRef{std::min(u, v), std::max(u, v), grid_rest_length(m, o), m.stiffness[o.kind], m.damping[o.kind],
                      SpringKind(o.kind)});
        }
}

// f(other node, rest, k, kd) for every spring of node v: grids in stencil order, general
// models in adjacency order.
template <class F>
void for_each_link(const Model& m, int v, F&& f) {
  if (!m.grid()) {
    for (int e = m.adj_offset[v]; e < m.adj_offset[v + 1]; ++e) {
      const int s = m.adj_spring[e];
      f(m.adj_node[e], m.rest_length[s], m.spring_k(s), m.spring_kd(s));
    }
    return;
  }
  const int i = Grid::grid_axis(v, 1, m.nx), j = Grid::grid_axis(v, m.nx, m.ny), k = Grid::grid_axis(v, m.nx * m.ny, m.nz);
  const Grid::StepParams extent = grid_extent(m);
  for (int e = 0; e < grid_stencil_size(m.volume()); ++e) {
    const GridOffset o = grid_offset(m.volume(), e);
    const int w = Grid::grid_neighbour(extent, i, j, k, o.di, o.dj, o.dk);
    if (w >= 0) f(w, grid_rest_length(m, o), m.stiffness[o.kind], m.damping[o.kind]);
  }
}

}  // namespace deformlab
