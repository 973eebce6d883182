// Tiles of a general model for a shared-memory gather (cuda-tiled on meshes): the nodes cut
// into blocks of at most `block` consecutive nodes along the Z-order curve of their rest
// positions (so a block is compact in space whatever the node order in memory), each block
// with its halo: every node outside it that one of its nodes has a spring to. A thread block
// stages its tile (members, then halo) once and gathers every spring from there.
#pragma once
#include <cstdint>
#include <vector>

#include "model.hpp"

namespace deformlab {

struct Tiling {
  // Tile b holds cells tile_node[tile_offset[b] .. tile_offset[b+1]): its members first
  // (members[b] of them), then its halo. [blocks+1], [members + halo], [blocks]
  std::vector<std::int32_t> tile_offset, tile_node, members;
  // The springs of member m of tile b (its CSR adjacency in the model's order), numbered by
  // slot p = tile_offset[b] + m: link_offset[p] .. link_offset[p+1] into link_cell (the other
  // end as a cell of the same tile) and link_spring (the model's spring). Slots of halo cells
  // have no links. [cells+1], [2s], [2s]
  std::vector<std::int32_t> link_offset, link_cell, link_spring;

  int blocks() const { return int(members.size()); }
  int largest_tile() const;  // cells of the largest tile
};

// Throws std::invalid_argument for a grid model or a block size below 1.
Tiling tile_model(const Model& m, int block);

}  // namespace deformlab
