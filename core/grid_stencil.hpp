// The neighbour stencil of grid models, written once: the builders make a grid's springs from
// it, and every backend finds a grid node's neighbours by it (the CPU and GL pipelines by
// looping over it, the CUDA kernels as compile-time constants).
#pragma once
#include "vec3.hpp"

namespace deformlab {

struct GridOffset {
  int di, dj, dk;
  int kind;  // SpringKind: 0 structural, 1 shear, 2 flexion
};

// Entry e of the cloth (volume = false) or lattice stencil: every neighbour of a node in the
// order its spring forces are summed. First the springs owned by lower-numbered nodes (the
// negated own offsets by decreasing linear offset), then the node's own springs (cloth:
// 2 structural, 2 shear, 2 flexion; lattice: 3 structural, 6 face- and 4 body-diagonal shear,
// 3 flexion). The own half is what the builders emit, node by node. (The tables are local so
// that CUDA device code can read them as constants.)
inline constexpr int kClothStencil = 12, kLatticeStencil = 32;
DL_HD constexpr GridOffset grid_offset(bool volume, int e) {
  constexpr GridOffset cloth[kClothStencil] = {
      {0, -2, 0, 2}, {-1, -1, 0, 1}, {0, -1, 0, 0}, {1, -1, 0, 1}, {-2, 0, 0, 2}, {-1, 0, 0, 0},  // incoming
      {1, 0, 0, 0},  {-1, 1, 0, 1},  {0, 1, 0, 0},  {1, 1, 0, 1},  {2, 0, 0, 2},  {0, 2, 0, 2}};  // own
  constexpr GridOffset lattice[kLatticeStencil] = {
      {0, 0, -2, 2},  {-1, -1, -1, 1}, {0, -1, -1, 1}, {1, -1, -1, 1}, {-1, 0, -1, 1}, {0, 0, -1, 0},
      {1, 0, -1, 1},  {-1, 1, -1, 1},  {0, 1, -1, 1},  {1, 1, -1, 1},  {0, -2, 0, 2},  {-1, -1, 0, 1},
      {0, -1, 0, 0},  {1, -1, 0, 1},   {-2, 0, 0, 2},  {-1, 0, 0, 0},                                   // incoming
      {1, 0, 0, 0},   {-1, 1, 0, 1},   {0, 1, 0, 0},   {1, 1, 0, 1},   {-1, -1, 1, 1}, {0, -1, 1, 1},
      {1, -1, 1, 1},  {-1, 0, 1, 1},   {0, 0, 1, 0},   {1, 0, 1, 1},   {-1, 1, 1, 1},  {0, 1, 1, 1},
      {1, 1, 1, 1},   {2, 0, 0, 2},    {0, 2, 0, 2},   {0, 0, 2, 2}};                                   // own
  return volume ? lattice[e] : cloth[e];
}
DL_HD constexpr int grid_stencil_size(bool volume) { return volume ? kLatticeStencil : kClothStencil; }

}  // namespace deformlab
