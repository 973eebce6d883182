#include "partition.hpp"

#include <algorithm>
#include <stdexcept>

#include "node_order.hpp"

namespace deformlab {

int Tiling::largest_tile() const {
  int most = 0;
  for (int b = 0; b < blocks(); ++b) most = std::max(most, tile_offset[b + 1] - tile_offset[b]);
  return most;
}

Tiling tile_model(const Model& m, int block) {
  if (m.grid()) throw std::invalid_argument("tiling a grid model: grids are tiled by their stencil");
  if (block < 1) throw std::invalid_argument("tile of " + std::to_string(block) + " nodes");
  const int n = m.node_count(), blocks = (n + block - 1) / block;
  // Members: consecutive runs of the Z-order, each sorted by node index (coalesced loads).
  const std::vector<std::int32_t> z = node_order(m, NodeOrder::morton, 0);
  std::vector<std::int32_t> block_of(n), cell_of(n);
  std::vector<std::vector<std::int32_t>> halo(blocks);
  Tiling t;
  t.members.resize(blocks);
  t.tile_offset.assign(blocks + 1, 0);
#pragma omp parallel for schedule(static)
  for (int b = 0; b < blocks; ++b) {
    const auto first = z.begin() + std::int64_t(b) * block, last = z.begin() + std::min<std::int64_t>(n, (b + 1LL) * block);
    std::vector<std::int32_t> mine(first, last);
    std::sort(mine.begin(), mine.end());
    t.members[b] = int(mine.size());
    for (int c = 0; c < int(mine.size()); ++c) {
      block_of[mine[c]] = b;
      cell_of[mine[c]] = c;
    }
  }
  // Halos: every neighbour in another block, by node index.
#pragma omp parallel for schedule(dynamic, 64)
  for (int b = 0; b < blocks; ++b) {
    const std::int64_t first = std::int64_t(b) * block, last = std::min<std::int64_t>(n, first + block);
    auto& h = halo[b];
    for (std::int64_t k = first; k < last; ++k)
      for (int e = m.adj_offset[z[k]]; e < m.adj_offset[z[k] + 1]; ++e)
        if (block_of[m.adj_node[e]] != b) h.push_back(m.adj_node[e]);
    std::sort(h.begin(), h.end());
    h.erase(std::unique(h.begin(), h.end()), h.end());
  }
  for (int b = 0; b < blocks; ++b) t.tile_offset[b + 1] = t.tile_offset[b] + t.members[b] + int(halo[b].size());
  const std::int64_t cells = t.tile_offset[blocks];
  t.tile_node.resize(cells);
  t.link_offset.assign(cells + 1, 0);
  // Cells in place, and each member's link count (halo cells have none).
#pragma omp parallel for schedule(static)
  for (int b = 0; b < blocks; ++b) {
    const std::int64_t first = std::int64_t(b) * block;
    for (int c = 0; c < t.members[b]; ++c) {
      const int v = z[first + c];
      t.tile_node[t.tile_offset[b] + cell_of[v]] = v;
      t.link_offset[t.tile_offset[b] + cell_of[v] + 1] = m.adj_offset[v + 1] - m.adj_offset[v];
    }
    std::copy(halo[b].begin(), halo[b].end(), t.tile_node.begin() + t.tile_offset[b] + t.members[b]);
  }
  for (std::int64_t p = 0; p < cells; ++p) t.link_offset[p + 1] += t.link_offset[p];
  t.link_cell.resize(t.link_offset[cells]);
  t.link_spring.resize(t.link_offset[cells]);
#pragma omp parallel for schedule(dynamic, 64)
  for (int b = 0; b < blocks; ++b) {
    const auto& h = halo[b];
    for (int c = 0; c < t.members[b]; ++c) {
      const std::int64_t p = t.tile_offset[b] + c;
      const int v = t.tile_node[p];
      std::int64_t l = t.link_offset[p];
      for (int e = m.adj_offset[v]; e < m.adj_offset[v + 1]; ++e, ++l) {
        const int u = m.adj_node[e];
        t.link_cell[l] = block_of[u] == b ? cell_of[u]
                                          : t.members[b] + int(std::lower_bound(h.begin(), h.end(), u) - h.begin());
        t.link_spring[l] = m.adj_spring[e];
      }
    }
  }
  return t;
}

}  // namespace deformlab
