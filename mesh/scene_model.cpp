#include "scene_model.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include "core/memory.hpp"
#include "generate.hpp"
#include "load.hpp"

namespace deformlab {

namespace {

// Scales and transforms a mesh's vertices, refusing one that is not finite as read (before the
// transform spreads a NaN to its other coordinates) or one with a coordinate, once placed, past
// ±kFarthest, where a spring's squared length can overflow float.
constexpr float kFarthest = 1e15f;  // m
void place(Mesh& m, const MeshSpec& s) {
  const auto& t = s.transform;
  auto far = [](const Vec3f& p) { return std::abs(p.x) > kFarthest || std::abs(p.y) > kFarthest || std::abs(p.z) > kFarthest; };
  for (auto& p : m.position) {
    if (!finite_vertex(p)) throw std::invalid_argument(non_finite_vertex(p));
    const Vec3f from = p, q{p.x * s.scale.x, p.y * s.scale.y, p.z * s.scale.z};
    for (int r = 0; r < 3; ++r) p[r] = t[r * 4] * q.x + t[r * 4 + 1] * q.y + t[r * 4 + 2] * q.z + t[r * 4 + 3];
    if (finite_vertex(p) && !far(p)) continue;
    std::ostringstream os;
    os << (far(from) ? "the vertex (" : "its scale and transform take the vertex (") << from.x << ", " << from.y << ", "
       << from.z << (far(from) ? ") lies" : ")") << " more than 1e15 m from the origin along an axis, where squared "
       << "lengths overflow float";
    throw std::invalid_argument(os.str());
  }
}

// Refuses a mesh whose model would not fit beside what the host has left.
void check_memory(std::int64_t nodes, std::int64_t springs, std::int64_t elements) {
  const auto limit = host_memory_limit();
  if (!limit) return;
  const std::int64_t need = model_host_bytes({nodes, springs, false}) + elements * 64;  // sorting the elements' sides
  if (need > limit->bytes)
    throw DoesNotFit("its model needs up to " + gib(need) + " of host memory; " + limit->name + " leaves " +
                     gib(limit->bytes));
}
void check_memory(const Mesh& mesh) {
  check_memory(std::int64_t(mesh.position.size()), mesh_spring_bound(mesh),
               std::int64_t(mesh.triangle.size() + mesh.tetrahedron.size()));
}

std::string generated_name(MeshShape::Kind k) { return "generated " + std::string(to_string(k)); }

// `e` again, of its kind (DoesNotFit or not), with `what` before its message.
[[noreturn]] void rethrow_naming(const std::string& what, const std::invalid_argument& e) {
  if (dynamic_cast<const DoesNotFit*>(&e)) throw DoesNotFit(what + ": " + e.what());
  throw std::invalid_argument(what + ": " + e.what());
}

// f(), with `what` before the message of its std::invalid_argument (a WriteError names its own
// file).
template <class F>
auto naming(const std::string& what, F&& f) {
  try {
    return f();
  } catch (const WriteError&) {
    throw;
  } catch (const std::invalid_argument& e) {
    rethrow_naming(what, e);
  }
}

// Refuses a model whose nodes reach `far` m from the origin along an axis, where float positions
// are more than a hundredth of its shortest spring (`shortest` m long; `which` names it) apart:
// its strains and small moves would be lost to rounding (a 16 x 16 cloth at 1e5 m never moved,
// and its run stopped as converged; at 1e4 m it jittered to max_steps). A 16384^2 cloth 1 m wide
// at 1 m, the paper's largest, has floats 0.2% of a spring apart.
void require_float_resolution(float far, float shortest, const std::string& which) {
  const float step = std::nextafter(far, INFINITY) - far;
  if (step <= 1e-2f * shortest) return;
  std::ostringstream os;
  os << std::setprecision(3) << "it lies up to " << far << " m from the origin, where floats are " << step
     << " m apart: more than a hundredth of its shortest spring (" << shortest << " m" << which
     << "), so rounding would swallow its strains and small moves: place it nearer the origin, or make that spring "
        "longer";
  throw std::invalid_argument(os.str());
}

// Refuses a generated shape placed where require_float_resolution would refuse it once meshed,
// before Gmsh meshes it: its farthest corner once scaled and transformed, and as its shortest
// spring a bound, twice its cell size stretched by the scale and transform's linear part
// (Frobenius norm: at least its largest stretch; Gmsh's edges stay well within that).
void require_generated_resolution(const MeshSpec& ms) {
  const MeshShape& g = *ms.generate;
  const auto& t = ms.transform;
  const bool box = g.kind == MeshShape::Kind::box;  // a box stands on y = 0, a sheet lies in it
  float far = 0.f;
  for (int c = 0; c < 8; ++c) {
    const Vec3f p{(c & 1 ? 0.5f : -0.5f) * g.size.x * ms.scale.x, (box && (c & 2) ? g.size.y : 0.f) * ms.scale.y,
                  (c & 4 ? 0.5f : -0.5f) * g.size.z * ms.scale.z};
    for (int r = 0; r < 3; ++r)
      far = std::max(far, std::abs(t[r * 4] * p.x + t[r * 4 + 1] * p.y + t[r * 4 + 2] * p.z + t[r * 4 + 3]));
  }
  if (!(far <= kFarthest)) return;  // place() refuses it, saying why
  double stretch = 0;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) stretch += std::pow(double(t[r * 4 + c]) * ms.scale[c], 2);
  require_float_resolution(far, float(2 * g.cell_size * std::sqrt(stretch)),
                           " or less: twice its cell_size, scaled and transformed, bounds it");
}

// The mesh the spec names: read from its file or generated; what names it in errors.
Mesh source_mesh(const MeshSpec& ms, std::string& what, std::vector<std::string>& notes) {
  if (ms.generate) {
    what = generated_name(ms.generate->kind);
    naming(what, [&] { require_generated_resolution(ms); });
    return generated_mesh(*ms.generate);
  }
  if (ms.file.empty())
    throw std::invalid_argument((ms.where.empty() ? "" : ms.where + ": ") +
                                "a mesh model needs a file (\"file\") or a shape (\"generate\")");
  what = "mesh file '" + ms.file + "'";
  return load_mesh(ms.file, notes);
}

// Refuses a fill whose tetrahedra of `cell_size` would make more than 2^30 nodes, or a model
// that would not fit, estimated from the volume the surface encloses (before meshing): by the
// divergence theorem over each connected part's triangles, its magnitude, so that parts wound
// the other way add rather than cancel (a cavity's volume is added, not taken away: an upper
// bound).
void check_fill_size(const Mesh& surface, float cell_size) {
  std::vector<std::int32_t> root(surface.position.size());
  std::iota(root.begin(), root.end(), 0);
  auto find = [&](std::int32_t v) {
    while (root[v] != v) v = root[v] = root[root[v]];
    return v;
  };
  for (const auto& t : surface.triangle) {
    const std::int32_t r = find(t[0]);
    root[find(t[1])] = r;
    root[find(t[2])] = r;
  }
  std::unordered_map<std::int32_t, double> part;  // a part's root -> its signed volume
  for (const auto& t : surface.triangle) {
    auto at = [&](std::int32_t v) {
      const Vec3f& p = surface.position[v];
      return Vec3d{p.x, p.y, p.z};
    };
    const Vec3d a = at(t[0]), b = at(t[1]), c = at(t[2]);
    part[find(t[0])] += dot(a, cross(b, c)) / 6.0;
  }
  double volume = 0;
  for (const auto& [r, v] : part) volume += std::abs(v);
  const double n = estimated_filled_nodes(volume, cell_size);
  std::ostringstream about;
  about << "filling with tetrahedra of cell_size " << cell_size << " m would make " << about_nodes(n);
  if (n > double(std::int64_t(1) << 30)) throw std::invalid_argument(about.str() + ", over the limit of 2^30");
  try {
    check_memory(std::int64_t(n), std::int64_t(n * 16), std::int64_t(n * 6.6));
  } catch (const std::invalid_argument& e) {
    rethrow_naming(about.str(), e);
  }
}

// The mesh a spec names, read or generated, placed by its scale and transform and repaired;
// with "fill", checked to be a surface whose filling fits, not yet filled. `what` names it in
// errors.
Mesh prepared_mesh(const MeshSpec& ms, std::vector<std::string>& notes, std::string& what) {
  Mesh mesh = source_mesh(ms, what, notes);
  return naming(what, [&] {
    place(mesh, ms);
    for (auto& line : repair(mesh)) notes.push_back(std::move(line));
    if (ms.fill && mesh.volume()) throw std::invalid_argument("it is a volume already: leave out \"fill\"");
    if (ms.fill && ms.cell_size > 0) check_fill_size(mesh, ms.cell_size);
    return std::move(mesh);
  });
}

// The mesh a spec's model is made of: prepared_mesh, with "fill" filled with tetrahedra (the
// filled mesh also written to `fill_to` when given).
Mesh model_mesh(const MeshSpec& ms, std::vector<std::string>& notes, std::string& what,
                const std::string& fill_to = {}) {
  Mesh mesh = prepared_mesh(ms, notes, what);
  if (!ms.fill) return mesh;
  return naming(what, [&] {
    Mesh filled = fill_tetrahedra(mesh, ms.cell_size, fill_to);
    for (auto& line : repair(filled)) notes.push_back("after filling: " + line);
    return filled;
  });
}

Model mesh_model_of(const ModelSpec& spec) {
  std::vector<std::string> notes;
  std::string what;
  const Mesh mesh = model_mesh(spec.mesh, notes, what);
  return naming(what, [&] {
    check_memory(mesh);
    Model m = mesh_model(mesh, spec.material, spec.mesh.density);
    const auto shortest = std::min_element(m.rest_length.begin(), m.rest_length.end());
    if (shortest != m.rest_length.end()) {
      const auto s = shortest - m.rest_length.begin();
      const std::string nodes = "between nodes " + std::to_string(m.file_index(m.spring_i[s])) + " and " +
                                std::to_string(m.file_index(m.spring_j[s]));
      if (*shortest < float(kShortestLength)) {
        std::ostringstream os;
        os << "the spring " << nodes << " is " << std::setprecision(3) << *shortest
           << " m long, shorter than the 1e-6 m a model's lengths take (a mesh in other units: its \"scale\")";
        throw std::invalid_argument(os.str());
      }
      float far = 0.f;
      for (const Vec3f& p : m.rest_position) far = std::max({far, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
      require_float_resolution(far, *shortest, ", " + nodes);
    }
    m.repairs = std::move(notes);
    return m;
  });
}


}  // namespace

// Refused first when the model of the estimated size would not fit: springs and elements a node
// as measured on Gmsh's meshes, sheets 6.0 and 2.0, boxes 14.8 and 6.0, with a margin.
Mesh generated_mesh(const MeshShape& shape, const std::string& save_to) {
  const bool sheet = shape.kind == MeshShape::Kind::sheet;
  const double n = estimated_nodes(shape);
  try {
    check_memory(std::int64_t(n), std::int64_t(n * (sheet ? 6.5 : 16)), std::int64_t(n * (sheet ? 2.2 : 6.6)));
  } catch (const std::invalid_argument& e) {
    rethrow_naming(generated_name(shape.kind) + " of " + about_nodes(n), e);
  }
  return generate_shape(shape, save_to);
}

void check_mesh_file(const Scene& s) {
  const MeshSpec& ms = s.model.mesh;
  if (s.model.topology != Topology::general) return;
  if (ms.generate) return naming(generated_name(ms.generate->kind), [&] {
    require_generated_resolution(ms);
  });
  if (ms.file.empty()) return;
  if (ms.fill) {
    std::vector<std::string> notes;
    std::string what;
    prepared_mesh(ms, notes, what);
  } else {
    resolve_params(s, build_model_in_file_order(s));  // its springs (a non-manifold edge), pins and drag node
  }
}

Mesh filled_mesh(const MeshSpec& ms, const std::string& save_to) {
  if (!ms.fill) throw std::logic_error("filled_mesh of a model without \"fill\"");
  std::vector<std::string> notes;
  std::string what;
  return model_mesh(ms, notes, what, save_to);
}

float grid_spacing(const ModelSpec& m) {
  if (m.nx < 1 || m.ny < 1 || m.nz < 1) throw std::invalid_argument("model size must be positive in every dimension");
  // `width` spans the first axis with more than one node: x, unless the grid is one node wide.
  const int across = m.nx > 1 ? m.nx : m.ny > 1 ? m.ny : m.nz;
  const float h = m.spacing != 0.f ? m.spacing : across > 1 ? m.width / float(across - 1) : m.width;
  if (h < float(kShortestLength)) {
    std::ostringstream os;
    os << "its width, " << m.width << " m across " << across << " nodes, spaces them " << std::setprecision(3) << h
       << " m apart: under the 1e-6 m a model's lengths take";
    throw std::invalid_argument(os.str());
  }
  // The farthest coordinate as cloth_grid and lattice place the nodes (centred in x and z, from
  // `height` up in y), by the same float expressions; the shortest spring is the structural one, h.
  const int along_z = m.topology == Topology::lattice ? m.nz : m.ny;
  const float cx = 0.5f * float(m.nx - 1) * h, cz = 0.5f * float(along_z - 1) * h;
  const float top = m.topology == Topology::lattice ? m.height + float(m.ny - 1) * h : m.height;
  require_float_resolution(std::max({cx, cz, std::abs(m.height), std::abs(top)}), h, "");
  return h;
}

Model build_model_in_file_order(const Scene& s) {
  const ModelSpec& m = s.model;
  Model model;
  if (m.topology == Topology::general) {
    model = mesh_model_of(m);
  } else {
    const float h = grid_spacing(m);
    model = m.topology == Topology::lattice ? lattice(m.nx, m.ny, m.nz, h, m.height, m.material)
                                            : cloth_grid(m.nx, m.ny, h, m.height, m.material);
  }
  pin(model, pin_nodes(model, m.pins, m.pin_list, m.pins_where));  // before reordering: indices are the file's
  return model;
}

void apply_node_order(Model& model, const ModelSpec& m) {
  if (m.topology == Topology::general && m.mesh.order != NodeOrder::file)
    reorder(model, node_order(model, m.mesh.order, m.mesh.seed));
}

Model build_model(const Scene& s) {
  Model model = build_model_in_file_order(s);
  apply_node_order(model, s.model);
  return model;
}

}  // namespace deformlab
