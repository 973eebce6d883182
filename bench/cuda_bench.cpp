// `deformlab-bench cuda`: ms per step of the CUDA pipelines on cloth grids, against the
// device's own copy bandwidth; launch overhead with and without step graphs; tile shapes;
// cuda-fused in exact and fast math against its bare gather; cuda-temporal's steps per launch.
#include <algorithm>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <utility>

#include "app/command_line.hpp"
#include "bench.hpp"
#include "cuda_kernels/cuda_pipeline.hpp"

namespace deformlab::bench {

namespace {

// BenchOptions (the main table's sizes and integrator, also the sweeps') and the sweeps'.
struct CudaOptions : BenchOptions {
  std::vector<std::string> variants{"naive", "tiled", "scatter", "fused"};
  std::vector<std::string> tiles{"8x8", "16x8", "16x16", "32x4", "32x8", "32x16", "64x4", "128x2", "256x1"};
  int tile_size = 2048;
  std::vector<int> graph_sizes{64, 128, 256, 512};
  int copy_mib = 1024;
  std::optional<double> reference_ms;  // another kernel's ms per step at tile_size, the user's own figure
  std::vector<int> temporal_sizes{2048, 8192};
  std::vector<int> steps_per_launch{1, 2, 4, 8};
  std::vector<std::string> temporal_tiles{"default"};
};

cuda::Variant parse_variant(const std::string& s) {
  for (cuda::Variant v : {cuda::Variant::naive, cuda::Variant::tiled, cuda::Variant::scatter, cuda::Variant::fused,
                          cuda::Variant::temporal})
    if (s == cuda::to_string(v)) return v;
  throw std::invalid_argument("unknown CUDA variant '" + s + "' (naive, tiled, scatter, fused, temporal)");
}

// cuda-fused's default block on the bench's cloths, "WxH".
std::string fused_block() { return cuda::to_string(cuda::default_tile(cuda::Variant::fused, Topology::cloth_grid)); }

struct Row {
  std::string table, scene, grid, variant, integrator, tile, math;
  bool graphs;
  std::int64_t nodes;
  double ms, floor_bytes, gbs, of_copy;
  ClockSummary clock;  // over the timed steps or launches
};

class Report {
 public:
  // `csv`: open_csv_of's, opened before anything is measured.
  Report(double copy_gbs, std::string bus, CsvFile csv)
      : copy_gbs_(copy_gbs), bus_(std::move(bus)), csv_(std::move(csv)) {}
  static CsvFile open_csv_of(const CudaOptions& o) {
    return open_csv(o.csv, "table,scene,grid,nodes,variant,integrator,tile,math,steps_per_launch,graphs,median_ms,"
                           "floor_bytes_per_node,effective_GBps,fraction_of_copy,sm_mhz_median,slowed_fraction",
                    kBuildColumn);
  }
  Row measure(const std::string& table, SceneKind kind, const BenchScene& scene, Integrator integ,
              const cuda::Options& opt, const CudaOptions& o) {
    const Model& m = scene.model;
    auto p = cuda::make_pipeline(scene.setup(integ), opt);
    // Timed as `deformlab run` times its steps; a multiple of 8, so that cuda-temporal's launches are whole.
    const Stats st = stats(time_steps(*p, m, o.warmup_ms, o.warmup, 8, bus_, 8));
    Row r;
    r.table = table;
    r.scene = to_string(kind);
    r.grid = std::to_string(m.nx) + "^2";
    r.variant = cuda::to_string(opt.variant);
    r.integrator = std::string(info(integ).name);
    r.tile = cuda::to_string(cuda::tile_for(opt, m));
    r.math = to_string(opt.math);
    const int k = opt.variant == cuda::Variant::temporal ? cuda::steps_per_launch(opt) : 1;
    r.graphs = opt.graphs;
    r.nodes = m.node_count();
    r.ms = st.median;
    r.floor_bytes = cuda::floor_bytes_per_node(m, integ, opt);
    r.clock = st.clock;
    clocks_.add(r.table + " " + r.grid + " " + r.variant + (k > 1 ? " k=" + std::to_string(k) : "") + " " +
                    r.integrator + " " + r.math + " " + r.tile + (r.graphs ? "" : " no graphs"),
                st.clock);
    return record(r, k);
  }

  ClockTally& clocks() { return clocks_; }

  // The bare gather (cuda::time_bare_gather) of the scene's springs (their neighbours' velocities
  // read where any kind is damped, as cuda-fused reads them) for the one-step integrators (64 B a
  // node), on cuda-fused's block, with its per-thread loads of fast math.
  Row bare_gather(SceneKind kind, const BenchScene& scene, const CudaOptions& o) {
    const Model& m = scene.model;
    const bool damped = m.damped();
    const int n = m.nx;
    const cuda::Tile tile = cuda::default_tile(cuda::Variant::fused, m.topology);
    Row r;
    r.table = "bare-gather";
    r.scene = to_string(kind);
    r.grid = std::to_string(n) + "^2";
    r.variant = "bare-gather";
    r.integrator = "one-step";
    r.tile = cuda::to_string(tile);
    r.math = "none";
    r.graphs = false;
    r.nodes = std::int64_t(n) * n;
    const TimedWork w = cuda::time_bare_gather(n, tile, damped, o.warmup_ms);
    r.ms = w.median_ms();
    r.clock = w.clock;
    r.floor_bytes = 64;
    clocks_.add("bare gather " + r.grid + " " + r.scene + " " + r.integrator, w.clock);
    return record(r, 1);
  }

 private:
  Row record(Row& r, int steps_per_launch) {
    r.gbs = r.floor_bytes * double(r.nodes) / (r.ms * 1e-3) / 1e9;
    r.of_copy = r.gbs / copy_gbs_;
    if (csv_)
      csv_ << r.table << "," << r.scene << "," << r.grid << "," << r.nodes << "," << r.variant << "," << r.integrator
           << "," << r.tile << "," << r.math << "," << steps_per_launch << "," << r.graphs << "," << r.ms << ","
           << r.floor_bytes << "," << r.gbs << "," << r.of_copy << ","
           << clock_columns(r.clock) << build_column() << "\n";
    return r;
  }

  double copy_gbs_;
  std::string bus_;
  ClockTally clocks_;
  CsvFile csv_;
};

void run_cuda(const CudaOptions& o) {
  std::vector<cuda::Variant> variants;
  std::vector<std::string> names;
  for (const auto& v : o.variants) {
    variants.push_back(parse_variant(v));
    names.push_back(std::string("cuda-") + cuda::to_string(variants.back()));
  }
  const Integrator integ = o.checked(names);
  const SceneKind kind = o.scene_kind();
  check_sizes("--graph-sizes", o.graph_sizes, SceneKind::idealised, {}, integ);
  check_sizes("--temporal-sizes", o.temporal_sizes, kind, {}, integ);
  if (o.tile_size > 0) check_sizes("--tile-size", {o.tile_size}, kind, {}, integ);
  for (const auto& t : o.tiles) cuda::parse_tile(t);  // bad tiles refused before anything runs
  for (const auto& t : o.temporal_tiles)
    if (t != "default") cuda::parse_temporal_tile(t);
  // Asked of a machine without CUDA: refused like deformlab's CUDA pipelines there (exit 2).
  if (const std::string why = cuda::unavailable(); !why.empty()) throw std::invalid_argument(why);

  CsvFile csv = Report::open_csv_of(o);
  const cuda::DeviceInfo dev = cuda::device_info();
  const std::int64_t copy_bytes = std::int64_t(o.copy_mib) << 20;
  const TimedWork copy_work = cuda::time_copy(copy_bytes, 20, o.warmup_ms);
  const double copy = copy_work.median_ms();
  const double copy_gbs = 2.0 * double(copy_bytes) / (copy * 1e-3) / 1e9;
  std::cout << title("cuda") << " " << dev.name << " (sm_" << dev.cc_major << dev.cc_minor << ", " << dev.sm_count
            << " SMs, " << fixed(dev.memory_gib, 1) << " GiB), driver " << dev.driver_version << ", runtime "
            << dev.runtime_version << "\n"
            << "method: a CUDA event at each step's end (the pipeline's step clock) after " << warm_up_words(o)
            << counted(o.warmup, "warm-up step") << "; the median of steps timed back to back for about "
            << fixed(kGpuTimedMs, 0) << " ms (at least 8), in ms per step.\n"
            << "cloth grid n x n, 12 springs per interior node. " << describe(kind) << ";\n"
            << describe(SceneKind::idealised) << " (graphs; the [fused] summary's second rows).\n"
            << "floor: compulsory DRAM bytes per node per step (each array a kernel touches read or written\n"
            << "once, neighbours from cache); effective GB/s = floor x nodes / time; copy = cudaMemcpy device to\n"
            << "device of " << o.copy_mib << " MiB, timed as the steps are"
            << (o.warmup_ms > 0 ? " (after " + fixed(o.warmup_ms, 0) + " ms of copies)" : "") << ", "
            << fixed(copy, 3) << " ms = " << fixed(copy_gbs, 0)
            << " GB/s counting read + write (the memory ceiling of this run).\n";

  Report rep(copy_gbs, dev.pci_bus_id, std::move(csv));
  rep.clocks().add("copy " + std::to_string(o.copy_mib) + " MiB", copy_work.clock);
  std::cout << "\n[steps] " << to_string(kind) << " scene, " << o.integrator << ", exact math, default tiles, step "
               "graphs on\n"
            << std::setw(8) << "grid" << std::setw(10) << "variant" << std::setw(12) << "ms/step" << std::setw(10)
            << "B/node" << std::setw(10) << "GB/s" << std::setw(10) << "of copy" << "\n";
  for (int n : o.sizes) {
    const BenchScene scene(n, kind);
    for (cuda::Variant v : variants) {
      const Row r = rep.measure("steps", kind, scene, integ, {v, {}, true}, o);
      std::cout << std::setw(8) << r.grid << std::setw(10) << r.variant << std::setw(12) << fixed(r.ms, 4)
                << std::setw(10) << fixed(r.floor_bytes, 0) << std::setw(10) << fixed(r.gbs, 0) << std::setw(9)
                << fixed(100 * r.of_copy, 1) << "%\n";
    }
  }

  if (!o.graph_sizes.empty()) std::cout << "\n[graphs] launch overhead: ms/step with and without the step captured as a CUDA graph ("
            << o.integrator << ", idealised scene: a moving drag handle changes the step's arguments, so the paper "
            "scene is not replayed)\n"
            << std::setw(8) << "grid" << std::setw(10) << "variant" << std::setw(12) << "graph" << std::setw(12)
            << "launches" << std::setw(10) << "gain" << "\n";
  for (int n : o.graph_sizes) {
    const BenchScene scene(n, SceneKind::idealised);
    for (cuda::Variant v : {cuda::Variant::fused, cuda::Variant::naive}) {
      const Row g = rep.measure("graphs", SceneKind::idealised, scene, integ, {v, {}, true}, o);
      const Row l = rep.measure("graphs", SceneKind::idealised, scene, integ, {v, {}, false}, o);
      std::cout << std::setw(8) << g.grid << std::setw(10) << g.variant << std::setw(12) << fixed(g.ms, 4)
                << std::setw(12) << fixed(l.ms, 4) << std::setw(9) << fixed(l.ms / g.ms, 2) << "x\n";
    }
  }

  if (o.tile_size > 0 && !o.tiles.empty()) {
    std::cout << "\n[tiles] block shape sweep at " << o.tile_size << "^2 (" << to_string(kind) << " scene, " << o.integrator
              << "): ms/step, exact math and cuda-fused in fast math too; tiled stages the block + 2-node halo in "
                 "shared memory\n"
              << std::setw(8) << "tile" << std::setw(12) << "tiled" << std::setw(12) << "naive" << std::setw(12)
              << "fused" << std::setw(12) << "fused fast" << "\n";
    const BenchScene scene(o.tile_size, kind);
    for (const auto& t : o.tiles) {
      const cuda::Tile tile = cuda::parse_tile(t);
      std::cout << std::setw(8) << t;
      for (cuda::Variant v : {cuda::Variant::tiled, cuda::Variant::naive, cuda::Variant::fused})
        std::cout << std::setw(12)
                  << fixed(rep.measure("tiles", kind, scene, integ, {v, tile, true}, o).ms, 4);
      const cuda::Options fast{cuda::Variant::fused, tile, true, Math::fast};
      std::cout << std::setw(12) << fixed(rep.measure("tiles", kind, scene, integ, fast, o).ms, 4) << "\n";
    }
  }

  if (o.tile_size > 0) {
    std::cout << "\n[bare gather] fast-math cuda-fused's loads and stores at " << o.tile_size
              << "^2 without its arithmetic (block " << fused_block() << ", cuda-fused's; in exact math it loads "
              << "cloths through the tensor memory accelerator instead): "
              << "each node's x and v and its 12 "
              << "neighbours' x, and their v where springs are damped (the paper scene); "
              << "the fastest of 1, 2 or 4 neighbours' loads at a time, each timed as the steps are (after "
              << (o.warmup_ms > 0 ? fixed(o.warmup_ms, 0) + " ms of launches and " : "") << cuda::kReferenceWarmUp
              << " warm-up launches); a reference, not a bound "
              << "(cuda-fused's L2 prefetch can beat it)\n"
              << std::setw(12) << "scene" << std::setw(22) << "integrator" << std::setw(12) << "ms/step"
              << std::setw(10) << "B/node" << std::setw(10) << "of copy" << "\n";
    std::map<SceneKind, double> bare_ms;
    for (SceneKind k : {SceneKind::paper, SceneKind::idealised}) {
      const Row r = rep.bare_gather(k, BenchScene(o.tile_size, k), o);
      bare_ms[k] = r.ms;
      std::cout << std::setw(12) << r.scene << std::setw(22) << r.integrator << std::setw(12) << fixed(r.ms, 4)
                << std::setw(10) << fixed(r.floor_bytes, 0) << std::setw(9) << fixed(100 * r.of_copy, 1) << "%\n";
    }

    std::cout << "\n[fused] one-pass integrators at " << o.tile_size << "^2 in exact and fast math against the copy "
              << "ceiling and the bare gather"
              << (o.reference_ms ? " and --reference-ms (" + fixed(*o.reference_ms, 4) + " ms per step, as given)" : "")
              << ", on cuda-fused's default block (" << fused_block() << ")\n"
              << std::setw(12) << "scene" << std::setw(22) << "integrator" << std::setw(7) << "math" << std::setw(12)
              << "ms/step" << std::setw(10) << "B/node" << std::setw(10) << "of copy" << std::setw(10) << "of bare"
              << (o.reference_ms ? "  vs reference" : "") << "\n";
    for (SceneKind k : {SceneKind::paper, SceneKind::idealised})
      for (Integrator i : {Integrator::explicit_euler, Integrator::semi_implicit_euler, Integrator::verlet})
        for (Math math : {Math::exact, Math::fast}) {
          const BenchScene scene(o.tile_size, k);
          const Row r = rep.measure("fused", k, scene, i, {cuda::Variant::fused, {}, true, math}, o);
          const double bare = bare_ms.at(k);
          std::cout << std::setw(12) << r.scene << std::setw(22) << r.integrator << std::setw(7) << r.math
                    << std::setw(12) << fixed(r.ms, 4) << std::setw(10) << fixed(r.floor_bytes, 0) << std::setw(9)
                    << fixed(100 * r.of_copy, 1) << "%" << std::setw(9) << fixed(100 * bare / r.ms, 1) << "%";
          if (o.reference_ms) std::cout << std::setw(13) << fixed(*o.reference_ms / r.ms, 2) << "x";
          std::cout << "\n";
        }
  }

  if (!o.temporal_sizes.empty()) {
    std::cout << "\n[temporal] cuda-temporal on the " << to_string(kind) << " scene, steps per launch k and tile "
              << "(default: the largest square whose region, with its 2k-node halo, leaves shared memory for two "
              << "blocks an SM), against cuda-fused of the same math and the one-step roofline (64 B per node and "
              << "step at the copy bandwidth)\n"
              << std::setw(8) << "grid" << std::setw(22) << "integrator" << std::setw(7) << "math" << std::setw(4)
              << "k" << std::setw(9) << "tile" << std::setw(12) << "ms/step" << std::setw(12) << "fused"
              << std::setw(12) << "roofline" << std::setw(14) << "vs roofline" << "\n";
    for (int n : o.temporal_sizes) {
      const BenchScene scene(n, kind);
      const double roofline = 64.0 * double(scene.model.node_count()) / (copy_gbs * 1e9) * 1e3;
      for (Integrator i : {Integrator::explicit_euler, Integrator::semi_implicit_euler, Integrator::verlet})
        for (Math math : {Math::exact, Math::fast}) {
          const double fused = rep.measure("temporal", kind, scene, i, {cuda::Variant::fused, {}, true, math}, o).ms;
          for (int k : o.steps_per_launch)
            for (const std::string& tile : o.temporal_tiles) {
              cuda::Options t{cuda::Variant::temporal, {}, true, math};
              t.steps_per_launch = k;
              if (tile != "default") t.temporal_tile = cuda::parse_temporal_tile(tile);
              const Row r = rep.measure("temporal", kind, scene, i, t, o);
              std::cout << std::setw(8) << r.grid << std::setw(22) << r.integrator << std::setw(7) << r.math
                        << std::setw(4) << k << std::setw(9) << tile << std::setw(12) << fixed(r.ms, 4)
                        << std::setw(12) << fixed(fused, 4) << std::setw(12) << fixed(roofline, 4) << std::setw(13)
                        << fixed(roofline / r.ms, 2) << "x\n";
            }
        }
    }
  }
  print_clocks(std::cout, rep.clocks(), "timed steps, copies or launches");
}

}  // namespace

void add_cuda_bench(CLI::App& app) {
  auto o = std::make_shared<CudaOptions>();
  o->sizes = {64, 128, 256, 512, 1024, 2048, 4096, 8192};
  o->integrator = "verlet";
  o->warmup = 10;
  auto* c = app.add_subcommand("cuda", "CUDA variants: ms/step at 64^2 to 8192^2 against the copy bandwidth, "
                                       "step graphs, tile sweep");
  add_bench_options(*c, *o);
  add_warmup_ms(*c, *o);
  c->add_option("--variants", o->variants, "Variants: naive, tiled, scatter, fused, temporal");
  c->add_option("--tiles", o->tiles, "Tile shapes WxH for the sweep");
  c->add_option("--tile-size", o->tile_size, "Grid size of the tile sweep and the fused summary (0: skip)");
  c->add_option("--graph-sizes", o->graph_sizes, "Grid sizes of the graph comparison");
  c->add_option("--copy-mib", o->copy_mib, "Size of the reference device-to-device copy, MiB")
      ->check(deformlab::app::whole_in(1, std::numeric_limits<int>::max()));
  c->add_option("--reference-ms", o->reference_ms,
                 "Another kernel's ms per step at --tile-size (your own measurement), to set cuda-fused against")
      ->check(deformlab::app::real_in(1e-9, 3.6e6));
  c->add_option("--temporal-sizes", o->temporal_sizes, "Grid sizes of the cuda-temporal table (none or 0: skip)")
      ->expected(0, CLI::detail::expected_max_vector_size)
      ->check(deformlab::app::whole_in(0, 1 << 16));
  c->add_option("--steps-per-launch", o->steps_per_launch, "cuda-temporal's steps per launch to compare")
      ->check(deformlab::app::whole_in(1, 8));
  c->add_option("--temporal-tiles", o->temporal_tiles, "cuda-temporal's tiles WxH to compare (default: its own)");
  c->callback([o, c] {
    std::erase(o->temporal_sizes, 0);  // "--temporal-sizes" alone gives {0}
    // A table's own flags where the table is skipped would do nothing.
    for (const char* flag : {"--tiles", "--reference-ms"})
      if (o->tile_size == 0 && c->count(flag) > 0)
        throw std::invalid_argument(std::string(flag) + ": --tile-size 0 skips the tile sweep and the fused summary");
    for (const char* flag : {"--steps-per-launch", "--temporal-tiles"})
      if (o->temporal_sizes.empty() && c->count(flag) > 0)
        throw std::invalid_argument(std::string(flag) + ": --temporal-sizes none or 0 skips the cuda-temporal table");
    run_cuda(*o);
  });
}

}  // namespace deformlab::bench
