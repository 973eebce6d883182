// Builders: spring counts against the closed forms, neighbour counts, rest lengths, CSR of
// the explicit springs, and what a grid model costs on the host.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <set>

#include "core/model.hpp"
#include "core/springs.hpp"

namespace deformlab {
namespace {

std::array<std::int64_t, 3> count_kinds(const Model& m) {
  std::array<std::int64_t, 3> c{};
  for_each_spring(m, [&](const SpringRef& s) { ++c[int(s.kind)]; });
  return c;
}

TEST(Builders, ClothSpringCountsMatchClosedForm) {
  for (auto [nx, ny] : {std::pair{1, 1}, {2, 3}, {3, 2}, {5, 7}, {37, 53}, {128, 128}}) {
    const Model m = cloth_grid(nx, ny, 0.1f, 0.f, Material{});
    EXPECT_EQ(m.node_count(), nx * ny);
    EXPECT_EQ(count_kinds(m), cloth_spring_counts(nx, ny)) << nx << "x" << ny;
    EXPECT_EQ(count_kinds(explicit_springs(m)), cloth_spring_counts(nx, ny)) << nx << "x" << ny;
  }
  // A hand count for 3x3: 12 structural, 8 shear, 6 flexion.
  EXPECT_EQ(cloth_spring_counts(3, 3), (std::array<std::int64_t, 3>{12, 8, 6}));
}

TEST(Builders, LatticeSpringCountsMatchClosedForm) {
  for (auto [nx, ny, nz] : {std::tuple{1, 1, 1}, {2, 2, 2}, {2, 3, 4}, {5, 4, 3}, {9, 9, 9}}) {
    const Model m = lattice(nx, ny, nz, 0.1f, 0.f, Material{});
    EXPECT_EQ(m.node_count(), nx * ny * nz);
    EXPECT_EQ(count_kinds(m), lattice_spring_counts(nx, ny, nz)) << nx << "x" << ny << "x" << nz;
    EXPECT_EQ(explicit_springs(m).spring_count(), m.spring_count());
  }
  // A 2x2x2 cube: 12 edges, 12 face diagonals + 4 body diagonals, no flexion.
  EXPECT_EQ(lattice_spring_counts(2, 2, 2), (std::array<std::int64_t, 3>{12, 16, 0}));
}

TEST(Builders, InteriorNodesHaveThePapersNeighbours) {
  const Model c = explicit_springs(cloth_grid(7, 7, 0.1f, 0.f, Material{}));
  const int centre = 3 * 7 + 3;
  std::array<int, 3> per_kind{};
  for (int e = c.adj_offset[centre]; e < c.adj_offset[centre + 1]; ++e) ++per_kind[int(c.kind[c.adj_spring[e]])];
  EXPECT_EQ(per_kind, (std::array<int, 3>{4, 4, 4}));

  const Model l = explicit_springs(lattice(5, 5, 5, 0.1f, 0.f, Material{}));
  const int mid = (2 * 5 + 2) * 5 + 2;
  per_kind = {};
  for (int e = l.adj_offset[mid]; e < l.adj_offset[mid + 1]; ++e) ++per_kind[int(l.kind[l.adj_spring[e]])];
  EXPECT_EQ(per_kind, (std::array<int, 3>{6, 12 + 8, 6}));
}

TEST(Builders, RestLengthsAndAdjacencyAreConsistent) {
  const float h = 0.25f;
  const Model m = explicit_springs(lattice(4, 3, 5, h, 1.f, Material{}));
  for (int s = 0; s < m.spring_count(); ++s) {
    const float len = norm(m.rest_position[m.spring_i[s]] - m.rest_position[m.spring_j[s]]);
    EXPECT_NEAR(m.rest_length[s], len, 1e-6f);  // the rest state is (to rounding) unstressed
    const float expect = m.kind[s] == SpringKind::structural ? h : m.kind[s] == SpringKind::flexion ? 2 * h : 0.f;
    if (expect > 0.f) EXPECT_NEAR(m.rest_length[s], expect, 1e-6f);
    else EXPECT_TRUE(std::abs(m.rest_length[s] - h * std::sqrt(2.f)) < 1e-6f ||
                     std::abs(m.rest_length[s] - h * std::sqrt(3.f)) < 1e-6f);
  }
  // One rest length per offset kind: structural h, flexion 2h, face sqrt(2) h, body sqrt(3) h.
  std::set<float> lengths(m.rest_length.begin(), m.rest_length.end());
  EXPECT_EQ(lengths.size(), 4u);
  // Every spring appears once in each end's adjacency, pointing at the other end.
  ASSERT_EQ(m.adj_offset.back(), 2 * m.spring_count());
  for (int v = 0; v < m.node_count(); ++v)
    for (int e = m.adj_offset[v]; e < m.adj_offset[v + 1]; ++e) {
      const int s = m.adj_spring[e];
      EXPECT_TRUE((m.spring_i[s] == v && m.spring_j[s] == m.adj_node[e]) ||
                  (m.spring_j[s] == v && m.spring_i[s] == m.adj_node[e]));
    }
}

// A grid is its stencil: no spring arrays, no adjacency; its host bytes are the rest
// positions and inverse masses (kGridBytesPerNode), as counted before it is built.
TEST(Builders, GridModelsCostOnlyTheirNodes) {
  for (const Model& m : {cloth_grid(300, 200, 0.1f, 0.f, Material{}), lattice(20, 30, 40, 0.1f, 0.f, Material{})}) {
    EXPECT_TRUE(m.spring_i.empty() && m.rest_length.empty() && m.kind.empty() && m.adj_offset.empty());
    EXPECT_EQ(m.host_bytes(), kGridBytesPerNode * m.node_count());
    EXPECT_EQ(model_host_bytes(m.size()), m.host_bytes());
    const Model g = explicit_springs(m);  // the same springs spelled out: about 20x the bytes
    EXPECT_GE(model_host_bytes(g.size()), g.host_bytes());
    EXPECT_GT(g.host_bytes(), 10 * m.host_bytes());
  }
}

// Resident memory grows by the model's bytes and no more when a 2048x2048 cloth is built.
TEST(Builders, BuildingAGridTouchesOnlyItsNodes) {
  auto resident = [] {
    std::ifstream in("/proc/self/statm");
    std::int64_t size = 0, pages = 0;
    in >> size >> pages;
    return pages * 4096;
  };
  const std::int64_t before = resident();
  const Model m = cloth_grid(2048, 2048, 0.001f, 0.f, Material{});
  const double per_node = double(resident() - before) / m.node_count();
#ifdef __SANITIZE_ADDRESS__
  const double shadow = kGridBytesPerNode / 8.0;  // AddressSanitizer's shadow of the arrays
#else
  const double shadow = 0.0;
#endif
  EXPECT_LE(per_node, kGridBytesPerNode + shadow + 0.5) << "bytes per node";
  EXPECT_GE(per_node, kGridBytesPerNode - 0.5) << "bytes per node";  // the arrays are filled
}

TEST(Builders, PinSets) {
  const Model c = cloth_grid(6, 4, 0.1f, 0.f, Material{});
  EXPECT_TRUE(pin_nodes(c, PinSet::none, {}).empty());
  EXPECT_EQ(pin_nodes(c, PinSet::top_corners, {}), (std::vector<int>{0, 5}));
  EXPECT_EQ(pin_nodes(c, PinSet::top_row, {}), (std::vector<int>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(pin_nodes(c, PinSet::list, {NodeSelector::node(7), NodeSelector::node(9)}), (std::vector<int>{7, 9}));
  // A selector's error names its scene key, or its place in the list when it was made in code.
  auto error = [&](std::vector<NodeSelector> list) {
    try {
      pin_nodes(c, PinSet::list, list);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("none");
  };
  EXPECT_EQ(error({NodeSelector::node(7), NodeSelector::node(24)}), "pins[1]: node 24 is outside the model (0..23)");
  NodeSelector read = NodeSelector::node(24);
  read.where = "s.json.model.pins[3]";
  EXPECT_EQ(error({read}), "s.json.model.pins[3]: node 24 is outside the model (0..23)");
  const Model l = lattice(3, 4, 2, 0.1f, 0.f, Material{});
  // lattice top corners: (0, ny-1, 0) and (nx-1, ny-1, 0), the top layer being y max.
  const auto tc = pin_nodes(l, PinSet::top_corners, {});
  ASSERT_EQ(tc.size(), 2u);
  for (int v : tc) EXPECT_FLOAT_EQ(l.rest_position[v].y, 0.3f);
  Model p = c;
  pin(p, pin_nodes(p, PinSet::top_corners, {}));
  EXPECT_TRUE(p.pinned(0) && p.pinned(5) && !p.pinned(1));
}

// A model is damped when any spring is: by kind, or by the per-spring values that replace them.
TEST(Builders, DampedWhenAnySpringIs) {
  Model c = cloth_grid(4, 3, 0.1f, 0.f, Material{});
  EXPECT_FALSE(c.damped());
  c.damping[int(SpringKind::flexion)] = 0.01f;
  EXPECT_TRUE(c.damped());
  Model g = explicit_springs(cloth_grid(4, 3, 0.1f, 0.f, Material{}));
  g.spring_damping.assign(std::size_t(g.spring_count()), 0.f);
  g.damping = {0.02f, 0.02f, 0.02f};  // replaced by the per-spring values
  EXPECT_FALSE(g.damped());
  g.spring_damping.back() = 0.5f;
  EXPECT_TRUE(g.damped());
}

TEST(Builders, RejectBadSizes) {
  EXPECT_THROW(cloth_grid(0, 5, 0.1f, 0.f, Material{}), std::invalid_argument);
  EXPECT_THROW(lattice(2, -1, 2, 0.1f, 0.f, Material{}), std::invalid_argument);
  EXPECT_THROW(cloth_grid(4, 4, 0.f, 0.f, Material{}), std::invalid_argument);
  EXPECT_THROW(cloth_grid(1 << 16, 1 << 15, 0.1f, 0.f, Material{}), std::invalid_argument);
}

}  // namespace
}  // namespace deformlab
