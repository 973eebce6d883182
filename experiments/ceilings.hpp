// This device's ceilings, from `deformlab calibrate`'s JSON, and the least time each stage
// of a GPU pipeline could take on it, so that reports show measured times as fractions of
// their own ceilings and hand-offs against the floor.
//
// Per force evaluation and node, the least a pass must do on what runs it (the pipeline's
// traits, core/pipeline.hpp):
//   CUDA and compute-shader passes move their state once at the calibrated copy bandwidth
//   (CUDA: device-to-device copy; GL compute: compute-shader copy): a force pass reads x, v
//   and writes a (48 B), an update reads x, v, a and writes x, v (80 B), a fused
//   force+update pass reads and writes x, v (64 B). Neighbour reads are left out (caches
//   serve them), so these bounds are optimistic.
//   Transform feedback passes emit one vertex per node at the pass-through vertex rate.
//   A pipeline whose passes run on two APIs hands off twice per force evaluation, each at
//   least the floor.
#pragma once
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "core/integrator.hpp"
#include "core/pipeline.hpp"

namespace deformlab {

struct Ceilings {
  double copy_gb_s = 0;          // CUDA device-to-device copy, GB/s read + written
  double compute_copy_gb_s = 0;  // GL compute-shader copy, GB/s read + written
  double tf_vertices_s = 0;      // pass-through transform feedback, vertices/s
  double floor_us = 0;           // GL <-> CUDA semaphore ping-pong with no work, µs per hand-off
  std::string device = "?";      // the device the calibration measured, by its name
  bool any() const { return copy_gb_s > 0 || compute_copy_gb_s > 0 || tf_vertices_s > 0 || floor_us > 0; }
};

// Missing or non-positive entries stay 0 (no ceiling of that kind).
Ceilings ceilings_of(const nlohmann::json& calibration);
// Reads a calibration file; throws std::invalid_argument naming the file and the problem
// when it is not JSON or has none of the ceilings above.
nlohmann::json read_calibration(const std::filesystem::path& file);

// The least time in ms per step of `stage` (a span name; span::step for the whole step) of
// a pipeline with `traits` on `nodes` nodes, and what bounds it; nullopt where none
// applies (CPU pipelines, stages without a ceiling, an uncalibrated ceiling).
struct Bound {
  double ms;
  std::string what;
};
// `adjacency_b`: bytes per node a gather reads of a general model's adjacency beyond the
// state (mesh_adjacency_bytes; grids: 0, their stencil is arithmetic), added to force passes.
std::optional<Bound> stage_ceiling(const Ceilings& c, const PipelineTraits& traits, const std::string& stage,
                                   std::int64_t nodes, Integrator integrator, double adjacency_b = 0);

// A mesh (CSR) gather's adjacency bytes per node: the offsets (4 B) and a 16-byte link per
// incident spring end (2 s / n of them); neighbours' x and v are taken as served by a perfect
// cache once. A fused mesh step then moves 64 + mesh_adjacency_bytes per node and evaluation.
double mesh_adjacency_bytes(std::int64_t nodes, std::int64_t springs);

}  // namespace deformlab
