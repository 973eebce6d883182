#include "mesh_model.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <parallel/algorithm>
#include <sstream>
#include <stdexcept>
#include <tuple>

namespace deformlab {

namespace {

[[noreturn]] void bad(const std::string& what) { throw std::invalid_argument(what); }

using Key = std::uint64_t;  // a node pair (i < j) as one sortable number
Key pair_key(std::int32_t a, std::int32_t b) {
  if (a > b) std::swap(a, b);
  return (Key(std::uint32_t(a)) << 32) | std::uint32_t(b);
}
std::int32_t key_i(Key k) { return std::int32_t(k >> 32); }
std::int32_t key_j(Key k) { return std::int32_t(k & 0xffffffffu); }

template <class V>
void sort_all(V& v) { __gnu_parallel::sort(v.begin(), v.end()); }

Vec3d dpos(const Mesh& m, std::int32_t v) { return Vec3d(m.position[v]); }

double triangle_area(const Mesh& m, const std::array<std::int32_t, 3>& t) {
  return 0.5 * norm(cross(dpos(m, t[1]) - dpos(m, t[0]), dpos(m, t[2]) - dpos(m, t[0])));
}
double tetrahedron_volume(const Mesh& m, const std::array<std::int32_t, 4>& t) {
  const Vec3d a = dpos(m, t[0]);
  return std::abs(dot(cross(dpos(m, t[1]) - a, dpos(m, t[2]) - a), dpos(m, t[3]) - a)) / 6.0;
}
template <std::size_t N>
double longest_edge(const Mesh& m, const std::array<std::int32_t, N>& t) {
  double l = 0;
  for (std::size_t a = 0; a < N; ++a)
    for (std::size_t b = a + 1; b < N; ++b) l = std::max(l, norm(dpos(m, t[a]) - dpos(m, t[b])));
  return l;
}

template <std::size_t N>
bool repeats(const std::array<std::int32_t, N>& t) {
  for (std::size_t a = 0; a < N; ++a)
    for (std::size_t b = a + 1; b < N; ++b)
      if (t[a] == t[b]) return true;
  return false;
}

// Applies f to every index of every element.
template <class F>
void for_each_index(Mesh& m, F&& f) {
  for (auto& t : m.triangle) for (auto& v : t) f(v);
  for (auto& t : m.tetrahedron) for (auto& v : t) f(v);
}

// Whether an element's size (area, volume) is below 1e-12 of what its longest edge spans.
template <std::size_t N, class SizeFn>
bool zero_size(const Mesh& m, const std::array<std::int32_t, N>& t, SizeFn size) {
  return !(size(m, t) > 1e-12 * std::pow(longest_edge(m, t), double(N - 1)));
}

// Degenerate if a vertex repeats or its size is zero.
template <std::size_t N, class SizeFn>
void check_elements(const Mesh& m, const std::vector<std::array<std::int32_t, N>>& elements, const char* name,
                    SizeFn size, bool welded) {
  for (std::size_t e = 0; e < elements.size(); ++e) {
    const auto& t = elements[e];
    const std::string which = std::string(name) + " " + std::to_string(e);
    if (repeats(t)) bad(which + " is degenerate: a vertex repeats" + (welded ? " (after welding duplicates)" : ""));
    if (zero_size(m, t, size)) bad(which + " is degenerate: zero " + (N == 3 ? "area" : "volume"));
  }
}

// Keeps the first of elements with the same vertices (in any order or orientation); returns
// how many it dropped.
template <std::size_t N>
std::int64_t drop_duplicates(std::vector<std::array<std::int32_t, N>>& elements) {
  std::vector<std::pair<std::array<std::int32_t, N>, std::int64_t>> keyed(elements.size());
  for (std::size_t e = 0; e < elements.size(); ++e) {
    keyed[e] = {elements[e], std::int64_t(e)};
    std::sort(keyed[e].first.begin(), keyed[e].first.end());
  }
  sort_all(keyed);
  std::vector<char> drop(elements.size(), 0);
  std::int64_t dropped = 0;
  for (std::size_t k = 1; k < keyed.size(); ++k)
    if (keyed[k].first == keyed[k - 1].first) drop[std::size_t(keyed[k].second)] = 1, ++dropped;
  std::size_t kept = 0;
  for (std::size_t e = 0; e < elements.size(); ++e)
    if (!drop[e]) elements[kept++] = elements[e];
  elements.resize(kept);
  return dropped;
}

}  // namespace

bool finite_vertex(const Vec3f& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

std::string non_finite_vertex(const Vec3f& p) {
  std::ostringstream os;
  os << "a vertex has a NaN or infinite coordinate (" << p.x << ", " << p.y << ", " << p.z << ")";
  return os.str();
}

std::vector<std::int32_t> first_at_same_position(const std::vector<Vec3f>& position) {
  const std::int64_t n = std::int64_t(position.size());
  std::vector<std::int32_t> by_position(n), first(n);
  std::iota(by_position.begin(), by_position.end(), 0);
  auto less = [&](std::int32_t a, std::int32_t b) {
    const Vec3f &p = position[a], &q = position[b];
    return std::tie(p.x, p.y, p.z, a) < std::tie(q.x, q.y, q.z, b);
  };
  __gnu_parallel::sort(by_position.begin(), by_position.end(), less);
  for (std::int64_t k = 0; k < n; ++k) {
    const std::int32_t v = by_position[k];
    first[v] = k > 0 && position[v] == position[by_position[k - 1]] ? first[by_position[k - 1]] : v;
  }
  return first;
}

std::vector<std::string> repair(Mesh& m) {
  const std::int64_t n = std::int64_t(m.position.size());
  if (m.triangle.empty() && m.tetrahedron.empty()) bad("the mesh has no triangles or tetrahedra");
  if (!m.triangle.empty() && !m.tetrahedron.empty()) bad("the mesh mixes triangles and tetrahedra");
  if (n > (std::int64_t(1) << 30)) bad("mesh of " + std::to_string(n) + " vertices exceeds the limit of 2^30 nodes");
  for (const Vec3f& p : m.position)
    if (!finite_vertex(p)) bad(non_finite_vertex(p));
  std::int64_t element = 0;
  for_each_index(m, [&](std::int32_t v) {
    if (v < 0 || v >= n)
      bad("element " + std::to_string(element / (m.volume() ? 4 : 3)) + " refers to vertex " + std::to_string(v) +
          ", outside 0.." + std::to_string(n - 1));
    ++element;
  });

  // Weld vertices at identical positions onto the first of them.
  std::vector<std::int32_t> remap = first_at_same_position(m.position);
  std::int64_t welded = 0;
  for (std::int64_t v = 0; v < n; ++v) welded += remap[v] != v;
  // Drop what no element uses (welded duplicates among them); the rest keep their order.
  std::vector<std::int32_t> used(n, 0);
  for_each_index(m, [&](std::int32_t& v) { v = remap[v]; used[v] = 1; });
  std::int32_t kept = 0;
  for (std::int64_t v = 0; v < n; ++v) {
    if (used[v]) m.position[kept] = m.position[v];
    remap[v] = used[v] ? kept++ : -1;
  }
  m.position.resize(kept);
  for_each_index(m, [&](std::int32_t& v) { v = remap[v]; });
  const std::int64_t unreferenced = n - kept - welded;

  check_elements(m, m.triangle, "triangle", triangle_area, welded > 0);
  check_elements(m, m.tetrahedron, "tetrahedron", tetrahedron_volume, welded > 0);
  // A repeated element would add a self-spring across its own sides.
  const std::int64_t repeated = drop_duplicates(m.triangle) + drop_duplicates(m.tetrahedron);
  std::vector<std::string> lines;
  if (welded) lines.push_back("welded " + std::to_string(welded) + " duplicate vertices");
  if (unreferenced) lines.push_back("dropped " + std::to_string(unreferenced) + " unreferenced vertices");
  if (repeated)
    lines.push_back("dropped " + std::to_string(repeated) + " repeated " + (m.volume() ? "tetrahedra" : "triangles"));
  return lines;
}

bool has_flat_tetrahedron(const Mesh& m) {
  return std::any_of(m.tetrahedron.begin(), m.tetrahedron.end(),
                     [&](const auto& t) { return zero_size(m, t, tetrahedron_volume); });
}

std::int64_t mesh_spring_bound(const Mesh& m) {
  return m.volume() ? 8 * std::int64_t(m.tetrahedron.size()) : 9 * std::int64_t(m.triangle.size()) / 2;
}

namespace {

// An element's side (a triangle's edge, a tetrahedron's face) with the vertex opposite it.
template <std::size_t N>
struct Side {
  std::array<std::int32_t, N> v;  // sorted
  std::int32_t opposite;
  bool operator<(const Side& o) const { return v < o.v; }
};

// Groups equal sides: boundary sides go to `boundary`, interior ones give a flexion pair.
template <std::size_t N, class Boundary>
void walk_sides(std::vector<Side<N>>& sides, std::vector<Key>& flexion, Boundary&& boundary) {
  sort_all(sides);
  for (std::size_t a = 0, b = 0; a < sides.size(); a = b) {
    while (b < sides.size() && sides[b].v == sides[a].v) ++b;
    if (b - a == 2) {
      flexion.push_back(pair_key(sides[a].opposite, sides[a + 1].opposite));
    } else if (b - a == 1) {
      boundary(sides[a]);
    } else {
      std::string nodes;
      for (auto v : sides[a].v) {
        if (!nodes.empty()) nodes += '-';
        nodes += std::to_string(v);
      }
      bad(std::string(N == 2 ? "edge " : "face ") + nodes + " is shared by " + std::to_string(b - a) +
          (N == 2 ? " triangles" : " tetrahedra") + " (non-manifold; node indices from 0, as pins take them)");
    }
  }
}

}  // namespace

Model mesh_model(const Mesh& mesh, const Material& mat, float density) {
  if (!(mat.node_mass > 0.f) || !std::isfinite(mat.node_mass)) bad("node mass must be positive");
  Model m;
  m.topology = Topology::general;
  m.rest_position = mesh.position;
  m.stiffness = mat.stiffness;
  m.damping = mat.damping;
  const std::int64_t n = std::int64_t(mesh.position.size());

  std::vector<double> mass(n, density > 0 ? 0.0 : double(mat.node_mass));
  if (density > 0) {
    for (const auto& t : mesh.triangle)
      for (auto v : t) mass[v] += density * triangle_area(mesh, t) / 3.0;
    for (const auto& t : mesh.tetrahedron)
      for (auto v : t) mass[v] += density * tetrahedron_volume(mesh, t) / 4.0;
  }
  m.inv_mass.resize(n);
  for (std::int64_t v = 0; v < n; ++v) {
    m.inv_mass[v] = float(1.0 / mass[v]);
    if (!std::isfinite(m.inv_mass[v])) {
      std::ostringstream what;
      what << "node " << v << "'s mass, " << mass[v] << " kg, is too small for float arithmetic (its inverse "
           << "overflows): raise the density";
      bad(what.str());
    }
  }

  std::vector<Key> edges, flexion;
  if (!mesh.volume()) {
    edges.reserve(3 * mesh.triangle.size());
    std::vector<Side<2>> sides;
    sides.reserve(3 * mesh.triangle.size());
    m.triangle.reserve(3 * mesh.triangle.size());
    for (const auto& t : mesh.triangle) {
      for (int c = 0; c < 3; ++c) {
        const std::int32_t a = t[(c + 1) % 3], b = t[(c + 2) % 3];
        sides.push_back({{std::min(a, b), std::max(a, b)}, t[c]});
      }
      m.triangle.insert(m.triangle.end(), t.begin(), t.end());
    }
    walk_sides(sides, flexion, [&](const Side<2>&) {});
    for (std::size_t a = 0; a < sides.size(); ++a)
      if (a == 0 || sides[a].v != sides[a - 1].v) edges.push_back(pair_key(sides[a].v[0], sides[a].v[1]));
  } else {
    edges.reserve(6 * mesh.tetrahedron.size());
    std::vector<Side<3>> sides;
    sides.reserve(4 * mesh.tetrahedron.size());
    for (const auto& t : mesh.tetrahedron) {
      for (int a = 0; a < 4; ++a)
        for (int b = a + 1; b < 4; ++b) edges.push_back(pair_key(t[a], t[b]));
      for (int c = 0; c < 4; ++c) {
        std::array<std::int32_t, 3> f{t[(c + 1) % 4], t[(c + 2) % 4], t[(c + 3) % 4]};
        // Outward: the face's normal points away from the opposite vertex.
        const Vec3d p = dpos(mesh, f[0]);
        if (dot(cross(dpos(mesh, f[1]) - p, dpos(mesh, f[2]) - p), dpos(mesh, t[c]) - p) > 0) std::swap(f[1], f[2]);
        Side<3> s{f, t[c]};
        std::sort(s.v.begin(), s.v.end());
        sides.push_back(s);
        m.triangle.insert(m.triangle.end(), f.begin(), f.end());  // kept below only if on the boundary
      }
    }
    // Boundary faces in their outward orientation: find each sorted side's oriented copy.
    std::vector<std::int32_t> oriented;
    oriented.swap(m.triangle);
    std::vector<std::array<std::int32_t, 3>> boundary;
    walk_sides(sides, flexion, [&](const Side<3>& s) { boundary.push_back(s.v); });
    sort_all(boundary);
    for (std::size_t f = 0; f < oriented.size(); f += 3) {
      std::array<std::int32_t, 3> key{oriented[f], oriented[f + 1], oriented[f + 2]};
      std::sort(key.begin(), key.end());
      if (std::binary_search(boundary.begin(), boundary.end(), key))
        m.triangle.insert(m.triangle.end(), oriented.begin() + f, oriented.begin() + f + 3);
    }
    sort_all(edges);
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  }
  // Flexion pairs once each, and none that is already an edge.
  sort_all(flexion);
  flexion.erase(std::unique(flexion.begin(), flexion.end()), flexion.end());
  std::vector<Key> bending;
  std::set_difference(flexion.begin(), flexion.end(), edges.begin(), edges.end(), std::back_inserter(bending));

  // Springs in node-pair order, both kinds merged.
  const std::size_t s = edges.size() + bending.size();
  m.spring_i.reserve(s); m.spring_j.reserve(s); m.rest_length.reserve(s); m.kind.reserve(s);
  auto add = [&](Key k, SpringKind kind) {
    m.spring_i.push_back(key_i(k));
    m.spring_j.push_back(key_j(k));
    m.rest_length.push_back(float(norm(dpos(mesh, key_i(k)) - dpos(mesh, key_j(k)))));
    m.kind.push_back(kind);
  };
  for (std::size_t a = 0, b = 0; a < edges.size() || b < bending.size();) {
    if (b == bending.size() || (a < edges.size() && edges[a] < bending[b])) add(edges[a++], SpringKind::structural);
    else add(bending[b++], SpringKind::flexion);
  }
  m.build_adjacency();
  return m;
}

}  // namespace deformlab
