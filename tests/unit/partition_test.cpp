// Tiles of general models (core/partition.hpp): every node a member of exactly one tile,
// every tile's halo complete (each spring's far end is a cell of the member's tile) and
// minimal (each halo cell is some member's neighbour outside the tile), links in the
// model's CSR order, on a shuffled surface and volume.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <set>

#include "core/mesh_model.hpp"
#include "core/node_order.hpp"
#include "core/partition.hpp"
#include "tests/support/test_states.hpp"

namespace deformlab::test {
namespace {

Model shuffled(Mesh mesh) {
  repair(mesh);
  Model m = mesh_model(mesh, Material{}, 0.f);
  reorder(m, node_order(m, NodeOrder::shuffled, 5));
  return m;
}

void expect_tiling(const Model& m, int block) {
  const Tiling t = tile_model(m, block);
  const int n = m.node_count();
  ASSERT_EQ(t.blocks(), (n + block - 1) / block);
  ASSERT_EQ(t.tile_offset.size(), std::size_t(t.blocks()) + 1);
  ASSERT_EQ(t.link_offset.size(), t.tile_node.size() + 1);
  std::vector<int> member_of(n, -1);
  for (int b = 0; b < t.blocks(); ++b) {
    const int c0 = t.tile_offset[b], cells = t.tile_offset[b + 1] - c0, members = t.members[b];
    ASSERT_GE(members, 1);
    ASSERT_LE(members, block);
    ASSERT_LE(cells, t.largest_tile());
    const std::vector<int> tile(t.tile_node.begin() + c0, t.tile_node.begin() + c0 + cells);
    EXPECT_EQ(std::set<int>(tile.begin(), tile.end()).size(), tile.size()) << "a cell repeated in tile " << b;
    std::set<int> reached;  // members' neighbours outside the tile
    for (int c = 0; c < members; ++c) {
      const int v = tile[c];
      ASSERT_EQ(member_of[v], -1) << "node " << v << " in two tiles";
      member_of[v] = b;
      const int first = m.adj_offset[v], degree = m.adj_offset[v + 1] - first;
      ASSERT_EQ(t.link_offset[c0 + c + 1] - t.link_offset[c0 + c], degree);
      for (int q = 0; q < degree; ++q) {
        const int l = t.link_offset[c0 + c] + q;
        ASSERT_GE(t.link_cell[l], 0);
        ASSERT_LT(t.link_cell[l], cells);
        EXPECT_EQ(tile[t.link_cell[l]], m.adj_node[first + q]) << "node " << v << " link " << q;
        EXPECT_EQ(t.link_spring[l], m.adj_spring[first + q]);
        if (t.link_cell[l] >= members) reached.insert(m.adj_node[first + q]);
      }
    }
    for (int c = members; c < cells; ++c) {
      EXPECT_EQ(t.link_offset[c0 + c + 1], t.link_offset[c0 + c]) << "a halo cell with links";
      EXPECT_TRUE(reached.count(tile[c])) << "halo node " << tile[c] << " of tile " << b << " is no member's neighbour";
    }
    EXPECT_EQ(reached.size(), std::size_t(cells - members)) << "tile " << b;
  }
  EXPECT_EQ(std::count(member_of.begin(), member_of.end(), -1), 0) << "nodes in no tile";
}

TEST(Tiling, CoversEveryNodeOnceWithCompleteHalos) {
  const Model surface = shuffled(triangulated_square(30, 20, 0.2f));
  const Model volume = shuffled(tetrahedralised_box(8, 6, 5, 0.2f));
  for (int block : {1, 7, 64, 128, 1000}) {
    SCOPED_TRACE(block);
    expect_tiling(surface, block);
    expect_tiling(volume, block);
  }
}

TEST(Tiling, TilesAreCompactInSpaceWhateverTheNodeOrder) {
  // The Z-order cut keeps a 128-node tile's halo within a small multiple of its members
  // even when neighbours lie anywhere in memory.
  const Model m = shuffled(triangulated_square(64, 64, 0.2f));
  const Tiling t = tile_model(m, 128);
  const double halo = double(t.tile_node.size() - std::size_t(m.node_count())) / m.node_count();
  std::printf("halo cells per member of 128-node tiles on a shuffled 64x64 sheet: %.3f\n", halo);
  EXPECT_LT(halo, 1.0);
  EXPECT_GT(halo, 0.0);
}

TEST(Tiling, RefusesGridsAndEmptyTiles) {
  EXPECT_THROW(tile_model(cloth_grid(4, 4, 0.1f, 0.f, Material{}), 16), std::invalid_argument);
  EXPECT_THROW(tile_model(shuffled(triangulated_square(3, 3)), 0), std::invalid_argument);
}

}  // namespace
}  // namespace deformlab::test
