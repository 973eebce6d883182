#include "model.hpp"

#include "memory.hpp"
#include "springs.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace deformlab {

const char* to_string(SpringKind k) {
  switch (k) {
    case SpringKind::structural: return "structural";
    case SpringKind::shear: return "shear";
    case SpringKind::flexion: return "flexion";
  }
  return "?";
}

void Model::build_adjacency() {
  const int n = node_count(), s = int(spring_i.size());
  adj_offset.assign(n + 1, 0);
  for (int e = 0; e < s; ++e) {
    ++adj_offset[spring_i[e] + 1];
    ++adj_offset[spring_j[e] + 1];
  }
  for (int v = 0; v < n; ++v) adj_offset[v + 1] += adj_offset[v];
  adj_spring.assign(2 * std::size_t(s), 0);
  adj_node.assign(2 * std::size_t(s), 0);
  std::vector<std::int32_t> fill(adj_offset.begin(), adj_offset.end() - 1);
  for (int e = 0; e < s; ++e) {
    const int a = spring_i[e], b = spring_j[e];
    adj_spring[fill[a]] = e; adj_node[fill[a]++] = b;
    adj_spring[fill[b]] = e; adj_node[fill[b]++] = a;
  }
}

std::int64_t Model::spring_count() const {
  if (!grid()) return std::int64_t(spring_i.size());
  const auto k = topology == Topology::lattice ? lattice_spring_counts(nx, ny, nz) : cloth_spring_counts(nx, ny);
  return k[0] + k[1] + k[2];
}

bool Model::damped() const {
  const auto nonzero = [](float d) { return d != 0.f; };
  if (grid() || spring_damping.empty()) return std::any_of(damping.begin(), damping.end(), nonzero);
  return std::any_of(spring_damping.begin(), spring_damping.end(), nonzero);
}

std::int64_t Model::host_bytes() const {
  auto bytes = [](const auto& v) { return std::int64_t(v.capacity() * sizeof(v[0])); };
  return bytes(rest_position) + bytes(inv_mass) + bytes(spring_i) + bytes(spring_j) + bytes(rest_length) +
         bytes(kind) + bytes(spring_stiffness) + bytes(spring_damping) + bytes(adj_offset) + bytes(adj_spring) +
         bytes(adj_node) + bytes(triangle) + bytes(file_node);
}

float Model::extent() const {
  if (rest_position.empty()) return 0.f;
  Vec3f lo = rest_position[0], hi = rest_position[0];
  for (const auto& p : rest_position)
    for (int c = 0; c < 3; ++c) { lo[c] = std::min(lo[c], p[c]); hi[c] = std::max(hi[c], p[c]); }
  return norm(hi - lo);
}

namespace {

// Grid builders index node (i, j, k) as (k*ny + j)*nx + i with axes mapped by `pos`; the
// arrays are filled in parallel (a 268 M-node grid builds in seconds).
template <class PosFn>
Model build_grid(Topology t, int nx, int ny, int nz, float h, const Material& mat, PosFn pos) {
  if (nx < 1 || ny < 1 || nz < 1) throw std::invalid_argument("grid dimensions must be positive");
  if (!(h > 0.f) || !std::isfinite(h)) throw std::invalid_argument("grid spacing must be positive");
  if (!(mat.node_mass > 0.f) || !std::isfinite(mat.node_mass))
    throw std::invalid_argument("node mass must be positive");
  Model m;
  m.topology = t;
  m.nx = nx; m.ny = ny; m.nz = nz;
  m.spacing = h;
  m.stiffness = mat.stiffness;
  m.damping = mat.damping;
  const std::int64_t rows = std::int64_t(ny) * nz, n = rows * nx;
  m.rest_position.resize(std::size_t(n));
  m.inv_mass.resize(std::size_t(n));
  const float w = 1.f / mat.node_mass;
#pragma omp parallel for schedule(static)
  for (std::int64_t r = 0; r < rows; ++r) {
    const int j = int(r % ny), k = int(r / ny);
    for (int i = 0; i < nx; ++i) {
      m.rest_position[std::size_t(r * nx + i)] = pos(i, j, k);
      m.inv_mass[std::size_t(r * nx + i)] = w;
    }
  }
  return m;
}

}  // namespace

void check_node_count(double nodes) {
  if (nodes > double(std::int64_t(1) << 30))
    throw std::invalid_argument("a model of " + about_nodes(nodes) + " exceeds the limit of 2^30 nodes");
}

Model cloth_grid(int nx, int ny, float h, float y0, const Material& mat) {
  if (nx >= 1 && ny >= 1) check_node_count(double(nx) * ny);
  const float cx = 0.5f * float(nx - 1) * h, cz = 0.5f * float(ny - 1) * h;
  return build_grid(Topology::cloth_grid, nx, ny, 1, h, mat, [&](int i, int j, int) {
    return Vec3f{float(i) * h - cx, y0, float(j) * h - cz};
  });
}

Model lattice(int nx, int ny, int nz, float h, float y0, const Material& mat) {
  if (nx >= 1 && ny >= 1 && nz >= 1) check_node_count(double(nx) * ny * nz);
  const float cx = 0.5f * float(nx - 1) * h, cz = 0.5f * float(nz - 1) * h;
  return build_grid(Topology::lattice, nx, ny, nz, h, mat, [&](int i, int j, int k) {
    return Vec3f{float(i) * h - cx, y0 + float(j) * h, float(k) * h - cz};
  });
}

std::array<std::int64_t, kSpringKinds> cloth_spring_counts(std::int64_t nx, std::int64_t ny) {
  auto p = [](std::int64_t v) { return std::max<std::int64_t>(v, 0); };
  return {p(nx - 1) * ny + nx * p(ny - 1), 2 * p(nx - 1) * p(ny - 1),
          p(nx - 2) * ny + nx * p(ny - 2)};
}

std::array<std::int64_t, kSpringKinds> lattice_spring_counts(std::int64_t nx, std::int64_t ny,
                                                             std::int64_t nz) {
  auto p = [](std::int64_t v) { return std::max<std::int64_t>(v, 0); };
  const std::int64_t structural = p(nx - 1) * ny * nz + nx * p(ny - 1) * nz + nx * ny * p(nz - 1);
  const std::int64_t face = 2 * (p(nx - 1) * p(ny - 1) * nz + p(nx - 1) * ny * p(nz - 1) +
                                 nx * p(ny - 1) * p(nz - 1));
  const std::int64_t body = 4 * p(nx - 1) * p(ny - 1) * p(nz - 1);
  const std::int64_t flexion = p(nx - 2) * ny * nz + nx * p(ny - 2) * nz + nx * ny * p(nz - 2);
  return {structural, face + body, flexion};
}

std::vector<int> select_nodes(const Model& m, const NodeSelector& s) {
  const int n = m.node_count();
  std::vector<int> out;
  using K = NodeSelector::Kind;
  switch (s.kind) {
    case K::index: {
      if (s.index < 0 || s.index >= n)
        throw std::invalid_argument("node " + std::to_string(s.index) + " is outside the model (0.." +
                                    std::to_string(n - 1) + ")");
      int v = s.index;
      if (!m.file_node.empty()) v = int(std::find(m.file_node.begin(), m.file_node.end(), s.index) - m.file_node.begin());
      return {v};
    }
    case K::box:
    case K::below:
      for (int v = 0; v < n; ++v) {
        const Vec3f& p = m.rest_position[v];
        const bool in = s.kind == K::box ? (p.x >= s.a.x && p.y >= s.a.y && p.z >= s.a.z && p.x <= s.b.x &&
                                            p.y <= s.b.y && p.z <= s.b.z)
                                         : dot(p - s.a, s.b) <= 0.f;
        if (in) out.push_back(v);
      }
      if (out.empty())
        throw std::invalid_argument(std::string(s.kind == K::box ? "the box" : "the half-space below the plane") +
                                    " holds no node of the model");
      return out;
    case K::center:
      if (m.grid()) return {Grid::grid_node(m.nx / 2, m.ny / 2, m.nz / 2, m.nx, m.ny)};
      [[fallthrough]];
    case K::nearest: {
      Vec3f target = s.a;
      if (s.kind == K::center) {
        Vec3f lo = m.rest_position[0], hi = lo;
        for (const auto& p : m.rest_position)
          for (int c = 0; c < 3; ++c) { lo[c] = std::min(lo[c], p[c]); hi[c] = std::max(hi[c], p[c]); }
        target = (lo + hi) * 0.5f;
      }
      // Ties go to the lowest index in the file, so the pick does not depend on node order.
      int best = 0;
      double best_d = INFINITY;
      for (int v = 0; v < n; ++v) {
        const double d = norm(Vec3d(m.rest_position[v] - target));
        if (d < best_d || (d == best_d && m.file_index(v) < m.file_index(best))) { best = v; best_d = d; }
      }
      return {best};
    }
  }
  return out;
}

std::vector<int> pin_nodes(const Model& m, PinSet set, const std::vector<NodeSelector>& list,
                           const std::string& where) {
  std::vector<int> out;
  auto needs_grid = [&](const char* name) {
    if (m.topology == Topology::general)
      throw std::invalid_argument((where.empty() ? "" : where + ": ") + "pin set '" + name +
                                  "' needs a grid or lattice (pin meshes by position)");
  };
  // "top": cloth row j = 0; lattice layer j = ny-1 (front row k = 0 for corners / row).
  const int top_j = m.topology == Topology::lattice ? m.ny - 1 : 0;
  auto node = [&](int i, int j, int k) { return Grid::grid_node(i, j, k, m.nx, m.ny); };
  switch (set) {
    case PinSet::none: break;
    case PinSet::top_corners:
      needs_grid("top-corners");
      out.push_back(node(0, top_j, 0));
      if (m.nx > 1) out.push_back(node(m.nx - 1, top_j, 0));
      break;
    case PinSet::top_row:
      needs_grid("top-row");
      for (int i = 0; i < m.nx; ++i) out.push_back(node(i, top_j, 0));
      break;
    case PinSet::list:
      for (std::size_t k = 0; k < list.size(); ++k) try {
          for (int v : select_nodes(m, list[k])) out.push_back(v);
        } catch (const std::invalid_argument& e) {
          const std::string& key = list[k].where;
          throw std::invalid_argument((key.empty() ? "pins[" + std::to_string(k) + "]" : key) + ": " + e.what());
        }
      break;
  }
  return out;
}

void pin(Model& m, const std::vector<int>& nodes) {
  for (int v : nodes) m.inv_mass.at(v) = 0.f;
}

// From the offset, not the rounded positions: every spring of one offset shares one rest length.
float grid_rest_length(const Model& m, const GridOffset& o) {
  return float(double(m.spacing) * std::sqrt(double(o.di * o.di + o.dj * o.dj + o.dk * o.dk)));
}

Model explicit_springs(const Model& grid) {
  Model m = grid;
  m.topology = Topology::general;
  if (!grid.grid()) return m;
  const std::int64_t s = grid.spring_count();
  m.spring_i.reserve(s); m.spring_j.reserve(s); m.rest_length.reserve(s); m.kind.reserve(s);
  for_each_spring(grid, [&](const SpringRef& r) {
    m.spring_i.push_back(r.i);
    m.spring_j.push_back(r.j);
    m.rest_length.push_back(r.rest);
    m.kind.push_back(r.kind);
  });
  m.build_adjacency();
  return m;
}

}  // namespace deformlab
