#include "pipelines.hpp"

#include <stdexcept>

#include "cuda_pipeline.hpp"
#include "math_builds.hpp"

namespace deformlab {
namespace cuda {

const char* to_string(Variant v) {
  switch (v) {
    case Variant::naive: return "naive";
    case Variant::tiled: return "tiled";
    case Variant::scatter: return "scatter";
    case Variant::fused: return "fused";
    case Variant::temporal: return "temporal";
  }
  return "?";
}

Tile parse_tile(const std::string& s) {
  const auto x = s.find('x');
  const auto w = option_count(std::string_view(s).substr(0, x), 1024);
  const auto h = x == std::string::npos ? std::nullopt : option_count(std::string_view(s).substr(x + 1), 1024);
  if (!w || !h || *w * *h > 1024)
    throw std::invalid_argument("CUDA tile '" + s +
                                "' is not WxH with 1..1024 threads, in plain digits with no leading zero (e.g. 32x8)");
  return {int(*w), int(*h)};
}

std::string to_string(Tile t) { return std::to_string(t.x) + "x" + std::to_string(t.y); }

Tile tile_option(const PipelineOptions& o) {
  const auto it = o.find("tile");
  return it == o.end() ? Tile{} : parse_tile(it->second);
}

Tile default_tile(Variant v, Topology t) {
  if (v == Variant::fused && t == Topology::lattice) return {16, 16};
  return v == Variant::fused && t == Topology::cloth_grid ? Tile{32, 8} : Tile{16, 8};
}

Tile tile_for(const Options& o, const Model& m) {
  return o.tile.x > 0 ? o.tile : default_tile(o.variant, m.topology);
}

TemporalTile parse_temporal_tile(const std::string& s) {
  TemporalTile t;
  int* axes[] = {&t.x, &t.y, &t.z};
  std::size_t at = 0, n = 0;
  for (; n < 3 && at <= s.size(); ++n) {
    const std::size_t end = std::min(s.find('x', at), s.size());
    const auto v = option_count(std::string_view(s).substr(at, end - at), 4096);
    if (!v) break;
    *axes[n] = int(*v);
    at = end + 1;
  }
  if (n < 2 || at <= s.size())
    throw std::invalid_argument("cuda-temporal tile '" + s +
                                "' is not WxH or WxHxD nodes, in plain digits with no leading zero (e.g. 40x40)");
  return t;
}

int steps_per_launch_option(const PipelineOptions& o) {
  const auto it = o.find("steps_per_launch");
  if (it == o.end()) return 0;
  if (const auto k = option_count(it->second, 8)) return int(*k);
  throw std::invalid_argument("option steps_per_launch '" + it->second +
                              "' is not a count from 1 to 8 (plain digits, no leading zero)");
}

int steps_per_launch(const Options& o) { return o.steps_per_launch > 0 ? o.steps_per_launch : 2; }

std::unique_ptr<CudaPipeline> make_pipeline(const PipelineSetup& s, const Options& o) {
  Options with_tile = o;
  with_tile.tile = tile_for(o, s.model);
  return o.math == Math::fast ? fast::make_pipeline(s, with_tile) : exact::make_pipeline(s, with_tile);
}

std::unique_ptr<ForcePass> make_force_pass(const Model& m, const Params& p, Variant v, Tile tile, Math math) {
  Options o{v, tile, false, math};
  o.tile = tile_for(o, m);
  return math == Math::fast ? fast::make_force_pass(m, p, o) : exact::make_force_pass(m, p, o);
}

std::string unsupported(Integrator i, Variant v) {
  if (i == Integrator::backward_euler)
    return "backward-euler needs a linear solve per step, which the CUDA pipelines do not have (use cpu, omp or "
           "reference)";
  if (v == Variant::temporal && !make_schedule(i).single_pass())
    return std::string(info(i).name) + " evaluates forces more than once a step; cuda-temporal runs explicit-euler, "
           "semi-implicit-euler and verlet (use cuda-fused)";
  return {};
}

Options options_of(Variant v, const PipelineOptions& o) {
  Options out{v, {}, true, math_option(o)};
  if (v != Variant::temporal) {
    out.tile = tile_option(o);
    if (const auto it = o.find("tma"); v == Variant::fused && it != o.end()) {
      if (it->second != "on" && it->second != "off")
        throw std::invalid_argument("option tma '" + it->second + "' is not on or off");
      out.tma = it->second == "on";
    }
    return out;
  }
  out.steps_per_launch = steps_per_launch_option(o);
  if (const auto it = o.find("tile"); it != o.end()) out.temporal_tile = parse_temporal_tile(it->second);
  return out;
}

std::string idle_option(Variant v, const PipelineOptions& o, Topology t) {
  if (v == Variant::temporal && t == Topology::general) return {};  // it runs no mesh, which it says
  if (const auto it = o.find("tile"); it != o.end()) {
    if (v == Variant::temporal && t == Topology::cloth_grid && parse_temporal_tile(it->second).z > 0)
      return "option tile '" + it->second + "': a cloth's tile is WxH nodes (WxHxD is a lattice's)";
    if (v != Variant::tiled && t == Topology::general)
      return "option tile: on a mesh this pipeline runs one thread per node in blocks of its own (of the CUDA "
             "pipelines only cuda-tiled takes a tile there: its nodes per tile)";
  }
  if (v == Variant::fused && o.count("tma") && t != Topology::cloth_grid)
    return "option tma: the tensor memory accelerator's kernel is a cloth's";
  return {};
}

std::int64_t spring_bytes(const ModelSize& m, Variant v) {
  if (m.grid) return 0;
  // CSR: offsets and two 16-byte links per spring; scatter: 5 words per spring; tiles: the
  // CSR by tile cell, each cell's node (halos hold at most one cell per link) and tile bounds.
  if (v == Variant::scatter) return m.springs * 20;
  if (v == Variant::tiled) return (m.nodes + 2 * m.springs + 1) * 8 + 2 * m.springs * 16 + m.nodes * 8;
  return (m.nodes + 1) * 4 + 2 * m.springs * 16;
}

std::int64_t bytes_needed(const ModelSize& m, Integrator i, const Options& o) {
  const Schedule s = make_schedule(i);
  const std::int64_t n = m.nodes, f4 = 16;
  std::int64_t b = n * 4 * f4;  // two (x, v) buffers
  b += n * 2 * f4 * s.stage_states;
  const bool one_kernel = (o.variant == Variant::fused || o.variant == Variant::temporal) && s.single_pass();
  if (!one_kernel) b += n * f4 * s.accel_slots;
  b += (kStateSets + 1) * 4;  // the stop rule's largest displacement from each set, and its result
  return b + spring_bytes(m, o.variant);
}

double floor_bytes_per_node(const Model& m, Integrator i, const Options& o) {
  const Variant v = o.variant;
  const Schedule s = make_schedule(i);
  const double f4 = 16, springs_per_node = m.node_count() ? double(m.spring_count()) / m.node_count() : 0;
  const double links = m.topology == Topology::general ? 4 + 2 * springs_per_node * 16 : 0;
  // Force pass: gather reads (x, v) and writes a. Scatter: clears the sums, reads every
  // spring once and (x, v), adds into the sums, then reads them with (x, v) to write a.
  const double force = v == Variant::scatter ? f4 + springs_per_node * 16 + 2 * f4 + 2 * f4 + 3 * f4 + f4
                                             : 3 * f4 + links;
  if (s.single_pass()) {
    if (v == Variant::fused) return 4 * f4 + links;                         // (x, v) in, (x', v') out
    if (v == Variant::temporal) return 4 * f4 / steps_per_launch(o);        // per step, halo not counted
    return force + 3 * f4 + 2 * f4;                                         // update: x, v, a in, x', v' out
  }
  double b = 0;
  for (const Pass& p : s.passes) {
    if (p.op == Pass::Op::force) b += force;
    if (p.op != Pass::Op::combine) continue;
    int terms = 0;  // x0, v0 and the slopes (v_j, a_j) of non-zero weight in; x, v out
    for (double w : p.weights) terms += w != 0.0;
    b += 2 * f4 + terms * 2 * f4 + 2 * f4;
  }
  return b;
}

}  // namespace cuda

void add_cuda_pipelines(PipelineRegistry& r) {
  using cuda::Variant;
  const std::pair<const char*, Variant> variants[] = {{"cuda-naive", Variant::naive},
                                                      {"cuda-tiled", Variant::tiled},
                                                      {"cuda-scatter", Variant::scatter},
                                                      {"cuda-fused", Variant::fused},
                                                      {"cuda-temporal", Variant::temporal}};
  for (const auto& [name, v] : variants)
    r.add(described(
        name, [] { return cuda::unavailable(); }, [v](Integrator i) { return cuda::unsupported(i, v); },
        [v](const PipelineSetup& s) -> std::unique_ptr<Pipeline> { return cuda::make_pipeline(s, options_of(v, s.options)); },
        [v](const ModelSize& m, Integrator i, const PipelineOptions& o) {
          return Footprint{std::int64_t(kTransferChunkNodes) * 16, cuda::bytes_needed(m, i, cuda::options_of(v, o))};
        },
        [v](const PipelineOptions& o) { cuda::options_of(v, o); },
        [v](const PipelineOptions& o, Topology t) { return cuda::idle_option(v, o, t); }));
}

}  // namespace deformlab
