// The CUDA pipelines behind the registry names, with the knobs that tests and benchmarks
// turn. Plain C++: includable without nvcc or CUDA headers.
#pragma once
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "availability.hpp"
#include "core/pipeline.hpp"

struct float4;
struct CUstream_st;

namespace deformlab {
struct TimedWork;  // core/timed_work.hpp
}

namespace deformlab::cuda {

enum class Variant {
  naive,    // one thread per node gathering its springs from global memory
  tiled,    // the same gather from a shared-memory tile: a grid block with a 2-node halo, or a
            // mesh tile of core/partition.hpp (tile.x * tile.y nodes along the Z-order, and its halo)
  scatter,  // one thread per spring, +f / -f added with atomics (not bitwise deterministic)
  fused,    // gather + update + constraints in one kernel for one-force-pass integrators
  temporal, // fused's step k times per launch on a shared-memory tile with a 2k-node halo
            // (grids; explicit Euler, semi-implicit Euler, Verlet)
};
const char* to_string(Variant v);

// Thread-block shape over a grid's (i, j) plane for the gather kernels (one node per
// thread); cuda-tiled stages the block's nodes plus a 2-node halo in shared memory.
// 0 x 0: none chosen, the variant's default for the model (tile_for).
struct Tile {
  int x = 0, y = 0;
};
// "WxH" -> Tile; throws std::invalid_argument on anything else.
Tile parse_tile(const std::string& s);
// Tile -> "WxH".
std::string to_string(Tile t);
// The tile named by the pipeline option "tile" ("WxH"), else none (0 x 0).
Tile tile_option(const PipelineOptions& o);

// cuda-temporal's tile: the nodes each thread block writes (z: layers, on lattices). Zero: the
// largest square (cube) whose region with its halo fits the device's shared memory.
struct TemporalTile {
  int x = 0, y = 0, z = 0;
};
// The option "tile" of cuda-temporal, "WxH" or (lattices) "WxHxD"; throws std::invalid_argument.
TemporalTile parse_temporal_tile(const std::string& s);
// The option "steps_per_launch" (1..8), else 0 (the default: steps_per_launch below); throws std::invalid_argument.
int steps_per_launch_option(const PipelineOptions& o);

struct Options {
  Variant variant = Variant::fused;
  Tile tile;
  // Replay each step as a captured CUDA graph when the step's kernel arguments do not
  // change from step to step (no drag handle moving). Measured on the H100 at 64^2-512^2:
  // 6-13% off a two-kernel step, nothing off the one-kernel fused step.
  bool graphs = true;
  Math math = Math::exact;  // the kernels' arithmetic (the build of cuda_pipeline.cu that runs)
  int steps_per_launch = 0;  // cuda-temporal: steps per launch (k); 0: the default
  TemporalTile temporal_tile;
  // cuda-fused on cloths: the blocks' nodes through the tensor memory accelerator (option tma);
  // none given: in exact math where the device has it (cuda_kernels/tma_tile.cuh).
  std::optional<bool> tma;
};

class CudaPipeline : public Pipeline {
 public:
  // Queues on `stream`, after the steps queued so far, a device copy of the current positions
  // (a float4 per node, w: inverse mass) to `dst`, device memory of the pipeline's device.
  virtual void copy_positions(float4* dst, CUstream_st* stream) = 0;
  std::string timing_method() const override { return "CUDA events"; }
};

// The registry's options (tile, steps_per_launch, tma, math) as variant v reads them; throws
// std::invalid_argument on a bad value.
Options options_of(Variant v, const PipelineOptions& o);
// Why an option of `o` would do nothing for variant v on a model of topology t, else empty.
std::string idle_option(Variant v, const PipelineOptions& o, Topology t);
// Variant v's tile on a model of topology t when none is chosen: 16 x 8, except for
// cuda-fused: 32 x 8 on cloths (H100, paper scene, explicit Euler, one call, fast math: 0.1056
// against 0.1076 ms at 2048^2 and 1.540 against 1.633 at 8192^2; exact math within 1% across
// shapes, and on 32 x 8 it takes the tensor memory accelerator's copies: tma_tile.cuh) and 16 x 16
// on lattices (semi-implicit Euler on six lattices from 96^3 to 48x48x1536: 2-5% faster in exact
// math, up to 3% in fast math, never more than 0.6% slower; docs/speed.md).
Tile default_tile(Variant v, Topology t);
// The tile the pipeline of options o runs model m on: o.tile, else default_tile.
Tile tile_for(const Options& o, const Model& m);

// cuda-temporal's steps per launch: the option, else 2 (on the H100 at 2048^2 and 8192^2 the
// fastest on cloths; on lattices, whose halo grows in three axes, 4 fits no tile).
int steps_per_launch(const Options& o);

// Empty when variant v runs this integrator, else the reason.
std::string unsupported(Integrator i, Variant v);

// Device bytes of a general model's springs as variant v reads them (the CSR adjacency, or
// the scatter's spring list); 0 for grids, whose springs are the stencil.
std::int64_t spring_bytes(const ModelSize& m, Variant v);
// The (x, v) state sets a pipeline cycles through: a launch reads one and writes the other.
inline constexpr int kStateSets = 2;
// Device memory a pipeline needs, bytes (state, stage slots, model arrays).
std::int64_t bytes_needed(const ModelSize& m, Integrator i, const Options& o);
// Device memory the pipelines' buffers hold now, bytes: what bytes_needed is tested against.
std::int64_t buffer_bytes();
// Throws std::invalid_argument naming `what`, the bytes needed and the bytes free when the
// device does not have `bytes` free.
void require_device_memory(std::int64_t bytes, const std::string& what);

// Throws std::invalid_argument for an unsupported integrator, a size that does not fit,
// a bad tile; std::runtime_error for a CUDA failure.
std::unique_ptr<CudaPipeline> make_pipeline(const PipelineSetup& s, const Options& o);

// For benchmarks.
struct DeviceInfo {
  std::string name;
  int sm_count = 0;
  double memory_gib = 0;
  int cc_major = 0, cc_minor = 0;
  int driver_version = 0, runtime_version = 0;
  std::string pci_bus_id;  // e.g. "0000:1B:00.0": which GPU a ClockWatch reads
};
DeviceInfo device_info(int device = -1);  // -1: the current device
// The benchmarks' references, timed as the steps are (time_back_to_back: calls back to back for
// about kGpuTimedMs, each ended by a CUDA event) after calls for `warm_ms` (warm_up) and
// kReferenceWarmUp more, with the device's clock over them.
inline constexpr int kReferenceWarmUp = 10;
// A device-to-device cudaMemcpy of `bytes`, `min_reps` at the least.
TimedWork time_copy(std::int64_t bytes, int min_reps, double warm_ms);
// The bare gather: cuda-fused's loads and stores on an n x n cloth without its arithmetic
// (a node's x and v and its 12 neighbours' x, and v with `velocities` (damped springs)), on
// blocks of `tile`: the fastest of three load
// schedules (1, 2 or 4 neighbours' loads at a time) by median. A reference for the gather's
// memory traffic, not a bound: cuda-fused's L2 prefetch, which it lacks, can beat it.
TimedWork time_bare_gather(int n, Tile tile, bool velocities, double warm_ms);
// Compulsory DRAM traffic of one step, bytes per node: every array a kernel touches read or
// written once per kernel, neighbours served by caches.
double floor_bytes_per_node(const Model& m, Integrator i, const Options& o);

}  // namespace deformlab::cuda
