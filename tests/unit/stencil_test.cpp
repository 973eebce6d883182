// The grid stencil in core (core/grid_stencil.hpp): its shape, that the builders' springs are
// exactly its in-bounds pairs, that the CPU pipeline's stencil path gives the state of the
// adjacency path, and per-spring constants in general models.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <set>
#include <tuple>

#include "core/cpu_backend.hpp"
#include "core/springs.hpp"
#include "tests/support/test_states.hpp"

namespace deformlab {
namespace {

int kind_of(const GridOffset& o) {
  const int a = std::abs(o.di), b = std::abs(o.dj), c = std::abs(o.dk);
  if (a == 2 || b == 2 || c == 2) return 2;
  return a + b + c == 1 ? 0 : 1;
}

TEST(GridStencil, EveryNeighbourOnceIncomingThenOwn) {
  for (bool volume : {false, true}) {
    const int n = grid_stencil_size(volume), half = n / 2;
    std::set<std::tuple<int, int, int>> seen;
    for (int e = 0; e < n; ++e) {
      const GridOffset o = grid_offset(volume, e);
      EXPECT_EQ(o.kind, kind_of(o)) << "entry " << e;
      EXPECT_TRUE(volume || o.dk == 0);
      EXPECT_TRUE(seen.insert({o.di, o.dj, o.dk}).second) << "entry " << e << " repeats an offset";
      // Own offsets point to higher-numbered nodes; each incoming one is an own one negated.
      const auto linear = [](const GridOffset& g) { return (g.dk * 100 + g.dj) * 100 + g.di; };
      EXPECT_EQ(linear(o) > 0, e >= half) << "entry " << e;
      if (e < half) {
        bool negated = false;
        for (int f = half; f < n; ++f) {
          const GridOffset p = grid_offset(volume, f);
          negated = negated || (p.di == -o.di && p.dj == -o.dj && p.dk == -o.dk);
        }
        EXPECT_TRUE(negated) << "entry " << e;
        // by decreasing linear offset of the own offset they negate
        if (e > 0) {
          EXPECT_GT(linear(o), linear(grid_offset(volume, e - 1)));
        }
      }
    }
    EXPECT_EQ(int(seen.size()), volume ? 32 : 12);  // cloth: 4 + 4 + 4; lattice: 6 + 20 + 6
  }
}

// The gathers skip the per-neighbour check where grid_interior holds, and the CUDA tiles take a
// halo of STENCIL_REACH: both must agree with the stencil's table.
TEST(GridStencil, InteriorNodesAreThoseWithEveryNeighbourInTheGrid) {
  for (bool volume : {false, true}) {
    int reach = 0;
    for (int e = 0; e < grid_stencil_size(volume); ++e) {
      const GridOffset o = grid_offset(volume, e);
      reach = std::max({reach, std::abs(o.di), std::abs(o.dj), std::abs(o.dk)});
    }
    EXPECT_EQ(reach, STENCIL_REACH);
    Grid::StepParams p{};
    p.nx = 7;
    p.ny = 6;
    p.nz = volume ? 5 : 1;
    int interior = 0;
    for (int k = 0; k < p.nz; ++k)
      for (int j = 0; j < p.ny; ++j)
        for (int i = 0; i < p.nx; ++i) {
          bool all_in = true;
          for (int e = 0; e < grid_stencil_size(volume); ++e) {
            const GridOffset o = grid_offset(volume, e);
            all_in = all_in && Grid::grid_neighbour(p, i, j, k, o.di, o.dj, o.dk) >= 0;
          }
          EXPECT_EQ(Grid::grid_interior(p, i, j, k, volume), all_in) << i << ", " << j << ", " << k;
          interior += all_in;
        }
    EXPECT_EQ(interior, volume ? 3 * 2 * 1 : 3 * 2);
  }
}

// Each node's stencil neighbours inside the grid (and for_each_link's) are the adjacency of
// the grid's explicit springs (each node's own stencil half), spring for spring (kind and
// rest length), and in the same order once the grid is at least 5 nodes wide.
TEST(GridStencil, BuildersSpringsAreTheStencilsInBoundsPairs) {
  const std::vector<Model> models = {test::small_cloth(1, 1), test::small_cloth(2, 3), test::small_cloth(5, 4),
                                     test::small_cloth(37, 53), test::small_lattice(2, 3, 4),
                                     test::small_lattice(5, 6, 5)};
  for (const Model& m : models) {
    const Model g = explicit_springs(m);
    ASSERT_EQ(g.spring_count(), m.spring_count());
    const bool wide = m.nx >= 5 && m.ny >= 5 && (!m.volume() || m.nz >= 5);
    for (int v = 0; v < m.node_count(); ++v) {
      const int i = Grid::grid_axis(v, 1, m.nx), j = Grid::grid_axis(v, m.nx, m.ny),
                k = Grid::grid_axis(v, m.nx * m.ny, m.nz);
      std::vector<std::tuple<int, int, float>> by_stencil, by_springs;  // other node, kind, rest length
      for (int e = 0; e < grid_stencil_size(m.volume()); ++e) {
        const GridOffset o = grid_offset(m.volume(), e);
        const int a = i + o.di, b = j + o.dj, c = k + o.dk;
        if (a < 0 || a >= m.nx || b < 0 || b >= m.ny || c < 0 || c >= m.nz) continue;
        by_stencil.emplace_back(Grid::grid_node(a, b, c, m.nx, m.ny), o.kind, grid_rest_length(m, o));
      }
      std::vector<std::tuple<int, float, float>> by_links;  // other node, rest length, k
      for_each_link(m, v, [&](int w, float rest, float k, float) { by_links.emplace_back(w, rest, k); });
      ASSERT_EQ(by_links.size(), by_stencil.size());
      for (std::size_t q = 0; q < by_links.size(); ++q)
        EXPECT_EQ(by_links[q], std::tuple(std::get<0>(by_stencil[q]), std::get<2>(by_stencil[q]),
                                          m.stiffness[std::get<1>(by_stencil[q])]));
      for (int e = g.adj_offset[v]; e < g.adj_offset[v + 1]; ++e) {
        const int s = g.adj_spring[e];
        by_springs.emplace_back(g.adj_node[e], int(g.kind[s]), g.rest_length[s]);
      }
      if (!wide) {
        std::sort(by_stencil.begin(), by_stencil.end());
        std::sort(by_springs.begin(), by_springs.end());
      }
      ASSERT_EQ(by_stencil, by_springs) << m.nx << "x" << m.ny << "x" << m.nz << ", node " << v;
    }
  }
}

// The CPU pipeline sums a grid node's springs by the stencil, a general model's by adjacency:
// bitwise the same state where the orders agree (grids 5 wide), within float rounding elsewhere.
TEST(GridStencil, StencilAndAdjacencyPathsAgree) {
  for (auto [m, bitwise] : {std::pair{test::small_cloth(37, 53), true}, {test::small_lattice(6, 5, 7), true},
                            {test::small_cloth(3, 4), false}, {test::small_lattice(2, 3, 4), false}}) {
    m.damping = {0.02f, 0.02f, 0.01f};
    const Model general = explicit_springs(m);
    const Params p = test::small_params();
    const State s0 = test::perturbed_state(m, 3);
    auto grid = make_cpu_pipeline({m, p, Integrator::rk4}, Precision::f32, false);
    auto csr = make_cpu_pipeline({general, p, Integrator::rk4}, Precision::f32, false);
    const State a = test::advance(*grid, s0, 20), b = test::advance(*csr, s0, 20);
    if (bitwise) {
      EXPECT_EQ(test::max_position_diff(a, b), 0.0) << m.nx << "x" << m.ny << "x" << m.nz;
      EXPECT_EQ(test::max_velocity_diff(a, b), 0.0);
    } else {
      EXPECT_LT(test::max_position_diff(a, b), 1e-6) << m.nx << "x" << m.ny << "x" << m.nz;
      EXPECT_LT(test::max_velocity_diff(a, b), 1e-4);
    }
  }
}

// Per-spring constants replace the per-kind ones: equal values give the same state; a stiffer
// spring changes the motion of its ends.
TEST(GridStencil, PerSpringConstantsOfGeneralModels) {
  Model m = explicit_springs(test::small_cloth(8, 8));
  m.damping = {0.02f, 0.02f, 0.01f};
  Model per_spring = m;
  for (int e = 0; e < m.spring_count(); ++e) {
    per_spring.spring_stiffness.push_back(m.stiffness[int(m.kind[e])]);
    per_spring.spring_damping.push_back(m.damping[int(m.kind[e])]);
  }
  const Params p = test::small_params();
  const State s0 = test::perturbed_state(m, 5);
  auto a = make_cpu_pipeline({m, p, Integrator::semi_implicit_euler}, Precision::f32, false);
  auto b = make_cpu_pipeline({per_spring, p, Integrator::semi_implicit_euler}, Precision::f32, false);
  const State sa = test::advance(*a, s0, 10), sb = test::advance(*b, s0, 10);
  EXPECT_EQ(test::max_position_diff(sa, sb), 0.0);

  const int e = m.spring_count() / 2;
  per_spring.spring_stiffness[e] *= 10.f;
  auto c = make_cpu_pipeline({per_spring, p, Integrator::semi_implicit_euler}, Precision::f32, false);
  const State sc = test::advance(*c, s0, 1);
  const State s1 = test::advance(*a, s0, 1);
  for (int v = 0; v < m.node_count(); ++v) {
    const bool end = v == m.spring_i[e] || v == m.spring_j[e];
    EXPECT_EQ(sc.v[v] == s1.v[v], !end) << "node " << v << (end ? " (an end of the stiffer spring)" : "");
  }
}

}  // namespace
}  // namespace deformlab
