// Models from meshes (core/mesh_model.hpp) and node order (core/node_order.hpp): spring and
// element counts against closed forms, lumped masses, every malformed input refused or
// repaired as stated, a mesh of a grid against the grid model, order round trips.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "core/cpu_backend.hpp"
#include "core/energy.hpp"
#include "core/mesh_model.hpp"
#include "core/node_order.hpp"
#include "tests/support/test_states.hpp"

namespace deformlab::test {
namespace {

std::array<std::int64_t, kSpringKinds> kinds_of(const Model& m) {
  std::array<std::int64_t, kSpringKinds> k{};
  for (auto kind : m.kind) ++k[int(kind)];
  return k;
}

Model model_of(Mesh mesh, float density = 0.f) {
  EXPECT_TRUE(repair(mesh).empty());
  return mesh_model(mesh, Material{}, density);
}

std::string error_of(Mesh mesh) {
  try {
    repair(mesh);
    mesh_model(mesh, Material{}, 0.f);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(MeshModel, TriangulatedSquareCountsAreClosedForm) {
  for (auto [nx, ny] : {std::pair{2, 2}, {5, 3}, {17, 11}}) {
    const Model m = model_of(triangulated_square(nx, ny));
    const std::int64_t edges = std::int64_t(nx - 1) * ny + nx * (ny - 1) + (nx - 1) * (ny - 1);
    const std::int64_t boundary = 2 * (nx - 1) + 2 * (ny - 1);
    EXPECT_EQ(m.node_count(), nx * ny);
    EXPECT_EQ(m.triangle.size(), 6u * (nx - 1) * (ny - 1));
    // One bending spring per interior edge: the opposite pairs of a same-diagonal
    // triangulation are all distinct and none is an edge.
    EXPECT_EQ(kinds_of(m), (std::array<std::int64_t, 3>{edges, 0, edges - boundary})) << nx << "x" << ny;
  }
}

TEST(MeshModel, TetrahedraCountsAreClosedForm) {
  // One tetrahedron: 6 edges, no interior face, 4 boundary faces oriented outwards.
  Mesh one;
  one.position = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  one.tetrahedron = {{0, 1, 2, 3}};
  const Model t = model_of(one);
  EXPECT_EQ(kinds_of(t), (std::array<std::int64_t, 3>{6, 0, 0}));
  ASSERT_EQ(t.triangle.size(), 12u);
  const Vec3f centre{0.25f, 0.25f, 0.25f};
  for (std::size_t f = 0; f < 12; f += 3) {
    const Vec3f a = t.rest_position[t.triangle[f]], b = t.rest_position[t.triangle[f + 1]],
                c = t.rest_position[t.triangle[f + 2]];
    EXPECT_LT(dot(cross(b - a, c - a), centre - a), 0.f) << "face " << f / 3 << " points inwards";
  }
  // A cube in 5 tetrahedra: 12 edges + 6 face diagonals; the central one's 4 faces are
  // interior, across each lies a body diagonal.
  Mesh five;
  for (int c = 0; c < 8; ++c) five.position.push_back({float(c & 1), float(c >> 1 & 1), float(c >> 2 & 1)});
  five.tetrahedron = {{1, 2, 4, 7}, {0, 1, 2, 4}, {3, 1, 2, 7}, {5, 1, 4, 7}, {6, 2, 4, 7}};
  const Model f = model_of(five, 1000.f);
  EXPECT_EQ(kinds_of(f), (std::array<std::int64_t, 3>{18, 0, 4}));
  EXPECT_EQ(f.triangle.size(), 3u * 12);
  // A cube in 6 tetrahedra around its diagonal: 12 + 6 + 1 edges; 6 interior faces around
  // the diagonal, each with a bending pair of two ring vertices one apart.
  const Model six = model_of(tetrahedralised_box(2, 2, 2));
  EXPECT_EQ(kinds_of(six), (std::array<std::int64_t, 3>{19, 0, 6}));
  EXPECT_EQ(six.triangle.size(), 3u * 12);
  // Lumped masses add up to density x volume (1 m^3 x 1000 kg/m^3).
  double total = 0;
  for (float w : f.inv_mass) total += 1.0 / w;
  EXPECT_NEAR(total, 1000.0, 1e-3);
}

// A tetrahedron whose fourth vertex lies in the plane of the other three is flat, by the test that
// repair refuses it with; one 1e-9 m off the plane of a 1 mm cell is not.
TEST(MeshModel, FlatTetrahedraAreFound) {
  Mesh m{{{0, 0, 0}, {1e-3f, 0, 0}, {0, 1e-3f, 0}, {1e-3f, 1e-3f, 0}}, {}, {{0, 1, 2, 3}}};
  EXPECT_TRUE(has_flat_tetrahedron(m));
  EXPECT_THROW(repair(m), std::invalid_argument);
  m.position[3].z = 1e-9f;
  EXPECT_FALSE(has_flat_tetrahedron(m));
  EXPECT_TRUE(repair(m).empty());
}

TEST(MeshModel, SurfaceMassesAreDensityTimesArea) {
  const Model m = model_of(triangulated_square(9, 5, 0.3f), 0.2f);
  double total = 0, area = 0;
  for (float w : m.inv_mass) total += 1.0 / w;
  for (std::size_t t = 0; t < m.triangle.size(); t += 3) {
    const Vec3d a(m.rest_position[m.triangle[t]]), b(m.rest_position[m.triangle[t + 1]]), c(m.rest_position[m.triangle[t + 2]]);
    area += 0.5 * norm(cross(b - a, c - a));
  }
  EXPECT_NEAR(total, 0.2 * area, 1e-6 * total);
  // A corner node carries less than an interior one (fewer triangles around it).
  EXPECT_GT(m.inv_mass[0], m.inv_mass[9 * 2 + 4]);
}

// Forces from one explicit Euler step from rest velocity: F = m v1 / dt.
std::vector<Vec3d> forces(const Model& m, const State& s0) {
  Params p;
  p.gravity = {0, 0, 0};
  p.damping = 0;
  auto cpu = make_cpu_pipeline({m, p, Integrator::explicit_euler, {}}, Precision::f64, false);
  const State s1 = advance(*cpu, s0, 1);
  std::vector<Vec3d> f(s1.v.size());
  for (std::size_t i = 0; i < f.size(); ++i) f[i] = Vec3d(s1.v[i]) * (1.0 / (double(p.dt) * m.inv_mass[i]));
  return f;
}

// At rest no spring pulls. Stretched, the forces obey the virial identity of springs:
// sum_i F_i . x_i = -sum_springs k (|d| - L) |d|, whatever the mesh.
TEST(MeshModel, RestIsAnEquilibriumAndStretchedForcesObeyTheVirial) {
  const Model m = model_of(tetrahedralised_box(4, 4, 4, 0.3f));
  for (const auto& f : forces(m, rest_state(m))) EXPECT_LT(norm(f), 1e-4) << "N";
  State big = rest_state(m);
  const Vec3f c{0.075f, 1.075f, 0.075f};
  for (auto& x : big.x) x = c + (x - c) * 1.02f;
  const auto f = forces(m, big);
  double virial = 0, expected = 0;
  for (int i = 0; i < m.node_count(); ++i) virial += dot(f[i], Vec3d(big.x[i]));
  for (std::size_t e = 0; e < m.spring_i.size(); ++e) {
    const double d = norm(Vec3d(big.x[m.spring_j[e]]) - Vec3d(big.x[m.spring_i[e]]));
    expected -= m.spring_k(int(e)) * (d - m.rest_length[e]) * d;
  }
  EXPECT_LT(expected, 0.0);
  EXPECT_NEAR(virial, expected, 1e-4 * std::abs(expected));
}

// The triangulated grid's structural springs along x and z are the grid's; with its
// diagonals and bending springs switched off, its forces are the grid model's with shear
// and flexion switched off, on any state.
TEST(MeshModel, MeshOfAGridGivesTheGridsForces) {
  const int nx = 9, ny = 7;
  Model mesh = model_of(triangulated_square(nx, ny));
  Model grid = cloth_grid(nx, ny, 0.05f, 1.f, Material{});
  grid.stiffness = {500.f, 0.f, 0.f};
  mesh.spring_stiffness.resize(mesh.spring_i.size());
  for (std::size_t e = 0; e < mesh.spring_i.size(); ++e) {
    const Vec3f d = mesh.rest_position[mesh.spring_j[e]] - mesh.rest_position[mesh.spring_i[e]];
    const bool axis = mesh.kind[e] == SpringKind::structural && (d.x == 0.f || d.z == 0.f);
    mesh.spring_stiffness[e] = axis ? 500.f : 0.f;
  }
  // The grid is centred on x = z = 0; the mesh starts at 0: move the mesh onto the grid.
  for (auto& x : mesh.rest_position) x -= Vec3f{0.2f, 0.f, 0.15f};
  ASSERT_LT(max_diff(mesh.rest_position, grid.rest_position), 1e-6);
  const Params p = small_params();
  const State s0 = perturbed_state(grid, 3u);
  auto run = [&](const Model& m) {
    auto cpu = make_cpu_pipeline({m, p, Integrator::explicit_euler, {}}, Precision::f64, false);
    return advance(*cpu, s0, 1);
  };
  const State a = run(grid), b = run(mesh);
  EXPECT_LT(max_velocity_diff(a, b), 1e-5) << "same springs, same forces (float rest lengths)";
  EXPECT_GT(max_velocity_diff(a, s0), 1e-2) << "the state must be loaded";
}

TEST(MeshModel, RepairsWeldDuplicatesAndDropUnreferencedVertices) {
  Mesh m = triangulated_square(3, 3);
  m.position.push_back(m.position[4]);  // a copy of the centre, used by the last triangle
  m.position.push_back({5, 5, 5});      // used by nothing
  m.triangle.back()[0] = 9;
  const auto lines = repair(m);
  EXPECT_EQ(lines, (std::vector<std::string>{"welded 1 duplicate vertices", "dropped 1 unreferenced vertices"}));
  EXPECT_EQ(m.position.size(), 9u);
  EXPECT_EQ(mesh_model(m, Material{}, 0.f).spring_count(), model_of(triangulated_square(3, 3)).spring_count());
}

TEST(MeshModel, RepeatedElementsAreDroppedNotMadeIntoSelfSprings) {
  // Found by the mesh fuzzer: a triangle repeated on a welded copy of a vertex gave a spring
  // from a node to itself across the shared edge.
  Mesh m = triangulated_square(3, 3);
  m.triangle.push_back({m.triangle[2][2], m.triangle[2][0], m.triangle[2][1]});  // triangle 2 again, rotated
  m.position.push_back(m.position[0]);
  m.triangle.push_back({9, m.triangle[0][1], m.triangle[0][2]});  // triangle 0 on a copy of vertex 0
  Mesh box = tetrahedralised_box(2, 2, 2);
  box.tetrahedron.push_back({box.tetrahedron[3][1], box.tetrahedron[3][0], box.tetrahedron[3][2], box.tetrahedron[3][3]});
  EXPECT_EQ(repair(m), (std::vector<std::string>{"welded 1 duplicate vertices", "dropped 2 repeated triangles"}));
  EXPECT_EQ(repair(box), std::vector<std::string>{"dropped 1 repeated tetrahedra"});
  EXPECT_EQ(mesh_model(m, Material{}, 0.f).spring_count(), model_of(triangulated_square(3, 3)).spring_count());
  const Model b = mesh_model(box, Material{}, 0.f);
  Mesh plain_box = tetrahedralised_box(2, 2, 2);
  repair(plain_box);
  EXPECT_EQ(b.spring_count(), mesh_model(plain_box, Material{}, 0.f).spring_count());
  for (std::size_t s = 0; s < b.spring_i.size(); ++s) EXPECT_LT(b.spring_i[s], b.spring_j[s]);
}

TEST(MeshModel, MalformedMeshesAreRefusedByName) {
  Mesh empty;
  EXPECT_EQ(error_of(empty), "the mesh has no triangles or tetrahedra");
  Mesh nan = triangulated_square(3, 3);
  nan.position[5].y = NAN;
  EXPECT_EQ(error_of(nan), "a vertex has a NaN or infinite coordinate (0.1, nan, 0.05)");
  Mesh outside = triangulated_square(3, 3);
  outside.triangle[2][1] = 40;
  EXPECT_EQ(error_of(outside), "element 2 refers to vertex 40, outside 0..8");
  Mesh repeated = triangulated_square(3, 3);
  repeated.triangle[3] = {1, 4, 1};
  EXPECT_EQ(error_of(repeated), "triangle 3 is degenerate: a vertex repeats");
  Mesh welded = triangulated_square(3, 3);
  welded.position[1] = welded.position[0];  // two corners of triangle 1 fall together
  EXPECT_EQ(error_of(welded), "triangle 1 is degenerate: a vertex repeats (after welding duplicates)");
  Mesh flat = triangulated_square(3, 3);
  flat.triangle.push_back({0, 4, 8});  // three points on the square's diagonal
  EXPECT_EQ(error_of(flat), "triangle 8 is degenerate: zero area");
  Mesh fin = triangulated_square(3, 3);
  fin.position.push_back({0.05f, 1.1f, 0.05f});
  fin.triangle.push_back({0, 4, 9});  // a third triangle on edge 0-4
  EXPECT_EQ(error_of(fin), "edge 0-4 is shared by 3 triangles (non-manifold; node indices from 0, as pins take them)");
  Mesh flat_tet = tetrahedralised_box(2, 2, 2);
  flat_tet.tetrahedron.push_back({0, 1, 2, 3});  // four corners of one face
  EXPECT_EQ(error_of(flat_tet), "tetrahedron 6 is degenerate: zero volume");
  Mesh three = tetrahedralised_box(2, 2, 2);
  three.position.push_back({-0.05f, 1.f, 0.025f});
  three.tetrahedron.push_back({0, 7, 1, 8});  // a third tetrahedron on face 0-1-7
  EXPECT_NE(error_of(three).find("is shared by 3 tetrahedra (non-manifold; node indices from 0"), std::string::npos) << error_of(three);
}

double mean_span(const Model& m) {
  double sum = 0;
  for (std::size_t e = 0; e < m.spring_i.size(); ++e) sum += m.spring_j[e] - m.spring_i[e];
  return sum / double(m.spring_i.size());
}

TEST(NodeOrder, EveryOrderIsAPermutationAndRoundTrips) {
  Mesh mesh = tetrahedralised_box(7, 6, 5, 0.2f);
  const Model file = model_of(mesh);
  const std::int64_t file_band = bandwidth(file);
  std::set<std::pair<int, int>> springs;
  for (std::size_t e = 0; e < file.spring_i.size(); ++e) springs.insert({file.spring_i[e], file.spring_j[e]});
  for (auto o : {NodeOrder::shuffled, NodeOrder::rcm, NodeOrder::morton}) {
    Model m = file;
    const auto order = node_order(m, o, 5);
    std::vector<std::int32_t> sorted = order;
    std::sort(sorted.begin(), sorted.end());
    for (int v = 0; v < m.node_count(); ++v) ASSERT_EQ(sorted[v], v) << to_string(o);
    reorder(m, order);
    // Each node keeps its position, mass and springs under its file index.
    for (int v = 0; v < m.node_count(); ++v) {
      ASSERT_EQ(m.rest_position[v], file.rest_position[m.file_node[v]]);
      ASSERT_EQ(m.inv_mass[v], file.inv_mass[m.file_node[v]]);
    }
    std::set<std::pair<int, int>> back;
    for (std::size_t e = 0; e < m.spring_i.size(); ++e) {
      ASSERT_LT(m.spring_i[e], m.spring_j[e]);
      const int a = m.file_node[m.spring_i[e]], b = m.file_node[m.spring_j[e]];
      back.insert({std::min(a, b), std::max(a, b)});
      ASSERT_FLOAT_EQ(m.rest_length[e], norm(m.rest_position[m.spring_i[e]] - m.rest_position[m.spring_j[e]]));
    }
    EXPECT_EQ(back, springs) << to_string(o);
    // Reordering again composes: file_node still names the file's nodes.
    Model twice = m;
    reorder(twice, node_order(twice, NodeOrder::shuffled, 9));
    for (int v = 0; v < twice.node_count(); ++v) ASSERT_EQ(twice.rest_position[v], file.rest_position[twice.file_node[v]]);
    if (o == NodeOrder::rcm) {
      EXPECT_LE(bandwidth(m), file_band) << "RCM narrows the band of a box";
    }
    if (o == NodeOrder::shuffled) {
      EXPECT_GT(mean_span(m), 2 * mean_span(file)) << "a shuffle spreads the springs";
    }
  }
}

TEST(NodeOrder, SelectorsPickTheSameNodesInEveryOrder) {
  Model file = model_of(triangulated_square(8, 6, 0.2f));
  Model shuffled = file;
  reorder(shuffled, node_order(shuffled, NodeOrder::shuffled, 3));
  using K = NodeSelector::Kind;
  const NodeSelector selectors[] = {NodeSelector::node(13), {K::nearest, -1, {0.2f, 1.f, 0.1f}},
                                    {K::box, -1, {-1.f, 0.f, -1.f}, {0.12f, 2.f, 0.12f}},
                                    {K::below, -1, {0.f, 1.f, 0.2f}, {0.f, 0.f, 1.f}}, {K::center}};
  for (const auto& s : selectors) {
    std::vector<int> a = select_nodes(file, s), b;
    for (int v : select_nodes(shuffled, s)) b.push_back(shuffled.file_node[v]);
    std::sort(b.begin(), b.end());
    EXPECT_EQ(a, b) << "selector kind " << int(s.kind);
    EXPECT_FALSE(a.empty());
  }
  EXPECT_EQ(select_nodes(file, NodeSelector::node(13)), std::vector<int>{13});
  EXPECT_THROW(select_nodes(file, {K::box, -1, {5.f, 5.f, 5.f}, {6.f, 6.f, 6.f}}), std::invalid_argument);
  EXPECT_THROW(node_order(cloth_grid(4, 4, 0.1f, 1.f, Material{}), NodeOrder::rcm, 1), std::invalid_argument);
}

}  // namespace
}  // namespace deformlab::test
