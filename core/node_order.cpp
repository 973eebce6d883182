#include "node_order.hpp"

#include <algorithm>
#include <numeric>
#include <parallel/algorithm>
#include <random>
#include <stdexcept>

namespace deformlab {

const char* to_string(NodeOrder o) {
  switch (o) {
    case NodeOrder::file: return "file";
    case NodeOrder::shuffled: return "shuffled";
    case NodeOrder::rcm: return "rcm";
    case NodeOrder::morton: return "morton";
  }
  return "?";
}

std::optional<NodeOrder> parse_node_order(const std::string& s) {
  for (auto o : {NodeOrder::file, NodeOrder::shuffled, NodeOrder::rcm, NodeOrder::morton})
    if (s == to_string(o)) return o;
  return std::nullopt;
}

namespace {

int degree(const Model& m, int v) { return m.adj_offset[v + 1] - m.adj_offset[v]; }

// Cuthill-McKee from a pseudo-peripheral node of each component (the last node reached by a
// breadth-first search from its lowest-degree node), neighbours by increasing degree; reversed.
std::vector<std::int32_t> reverse_cuthill_mckee(const Model& m) {
  const int n = m.node_count();
  std::vector<std::int32_t> order, level;
  order.reserve(n);
  std::vector<char> seen(n, 0), probe(n, 0);
  std::vector<int> by_degree(n);
  std::iota(by_degree.begin(), by_degree.end(), 0);
  std::stable_sort(by_degree.begin(), by_degree.end(), [&](int a, int b) { return degree(m, a) < degree(m, b); });
  auto bfs = [&](int start, std::vector<char>& mark, std::vector<std::int32_t>& out) {
    const std::size_t first = out.size();
    mark[start] = 1;
    out.push_back(start);
    std::vector<int> next;
    for (std::size_t k = first; k < out.size(); ++k) {
      next.clear();
      for (int e = m.adj_offset[out[k]]; e < m.adj_offset[out[k] + 1]; ++e)
        if (!mark[m.adj_node[e]]) { mark[m.adj_node[e]] = 1; next.push_back(m.adj_node[e]); }
      std::stable_sort(next.begin(), next.end(), [&](int a, int b) { return degree(m, a) < degree(m, b); });
      out.insert(out.end(), next.begin(), next.end());
    }
  };
  for (int s : by_degree) {
    if (seen[s]) continue;
    level.clear();
    bfs(s, probe, level);  // the component, to find its far end
    bfs(level.back(), seen, order);
  }
  std::reverse(order.begin(), order.end());
  return order;
}

// Spreads the low 21 bits of v to every third bit.
std::uint64_t spread(std::uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffull;
  v = (v | v << 16) & 0x1f0000ff0000ffull;
  v = (v | v << 8) & 0x100f00f00f00f00full;
  v = (v | v << 4) & 0x10c30c30c30c30c3ull;
  v = (v | v << 2) & 0x1249249249249249ull;
  return v;
}

std::vector<std::int32_t> morton(const Model& m) {
  const int n = m.node_count();
  Vec3f lo = m.rest_position[0], hi = lo;
  for (const auto& p : m.rest_position)
    for (int c = 0; c < 3; ++c) { lo[c] = std::min(lo[c], p[c]); hi[c] = std::max(hi[c], p[c]); }
  // One scale for the three axes (the bounding cube): scaled per axis, a thin axis (a sheet's
  // slight relief) would take as many bits as the wide ones and scramble the curve.
  const double span = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  std::vector<std::pair<std::uint64_t, std::int32_t>> keys(n);
#pragma omp parallel for
  for (int v = 0; v < n; ++v) {
    std::uint64_t code = 0;
    for (int c = 0; c < 3; ++c) {
      const double u = span > 0 ? double(m.rest_position[v][c] - lo[c]) / span : 0.0;
      code |= spread(std::uint64_t(std::min(u, 1.0) * 2097151.0)) << c;
    }
    keys[v] = {code, v};
  }
  __gnu_parallel::sort(keys.begin(), keys.end());
  std::vector<std::int32_t> order(n);
  for (int k = 0; k < n; ++k) order[k] = keys[k].second;
  return order;
}

}  // namespace

std::vector<std::int32_t> node_order(const Model& m, NodeOrder o, std::uint64_t seed) {
  std::vector<std::int32_t> order(m.node_count());
  std::iota(order.begin(), order.end(), 0);
  if (o != NodeOrder::file && m.grid()) throw std::invalid_argument("node order applies to meshes, not grids");
  switch (o) {
    case NodeOrder::file: break;
    case NodeOrder::shuffled: std::shuffle(order.begin(), order.end(), std::mt19937_64(seed)); break;
    case NodeOrder::rcm: order = reverse_cuthill_mckee(m); break;
    case NodeOrder::morton: order = morton(m); break;
  }
  return order;
}

void reorder(Model& m, const std::vector<std::int32_t>& order) {
  const int n = m.node_count();
  if (int(order.size()) != n) throw std::invalid_argument("a node order must list every node once");
  std::vector<std::int32_t> inv(n, -1);
  for (int k = 0; k < n; ++k) {
    if (order[k] < 0 || order[k] >= n || inv[order[k]] >= 0)
      throw std::invalid_argument("a node order must list every node once");
    inv[order[k]] = k;
  }
  auto permute = [&](auto& a) {
    auto b = a;
    for (int k = 0; k < n; ++k) b[k] = a[order[k]];
    a.swap(b);
  };
  std::vector<std::int32_t> file(n);
  for (int k = 0; k < n; ++k) file[k] = m.file_index(order[k]);
  m.file_node.swap(file);
  permute(m.rest_position);
  permute(m.inv_mass);
  for (auto& v : m.triangle) v = inv[v];
  // Springs by their new end nodes.
  const std::size_t s = m.spring_i.size();
  std::vector<std::pair<std::uint64_t, std::int32_t>> keys(s);
#pragma omp parallel for
  for (std::int64_t e = 0; e < std::int64_t(s); ++e) {
    const std::uint32_t a = inv[m.spring_i[e]], b = inv[m.spring_j[e]];
    keys[e] = {(std::uint64_t(std::min(a, b)) << 32) | std::max(a, b), std::int32_t(e)};
  }
  __gnu_parallel::sort(keys.begin(), keys.end());
  auto by_key = [&](auto& a) {
    if (a.empty()) return;
    auto b = a;
    for (std::size_t e = 0; e < s; ++e) b[e] = a[keys[e].second];
    a.swap(b);
  };
  by_key(m.rest_length);
  by_key(m.kind);
  by_key(m.spring_stiffness);
  by_key(m.spring_damping);
  for (std::size_t e = 0; e < s; ++e) {
    m.spring_i[e] = std::int32_t(keys[e].first >> 32);
    m.spring_j[e] = std::int32_t(keys[e].first & 0xffffffffu);
  }
  m.build_adjacency();
}

std::int64_t bandwidth(const Model& m) {
  std::int64_t b = 0;
  for (std::size_t e = 0; e < m.spring_i.size(); ++e) b = std::max<std::int64_t>(b, m.spring_j[e] - m.spring_i[e]);
  return b;
}

}  // namespace deformlab
