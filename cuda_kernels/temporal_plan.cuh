// cuda-temporal's launch shape: its steps a launch and its tile, checked against the device's
// shared memory, and the blocks that cover a grid.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "check.cuh"
#include "core/model.hpp"
#include "cuda_pipeline.hpp"
#include "temporal.cuh"

namespace deformlab::cuda::DL_CUDA_MATH {

struct TemporalPlan {
  int k = 1;               // steps a launch
  int3 tile{};             // the nodes a block writes
  std::size_t shared = 0;  // a block's shared memory: its tile and a halo of 2k nodes, two copies of x and v a cell
  int shared_limit = 0;    // the device's a block, less the kernel's static shared memory
  dim3 blocks(int nx, int ny, int nz) const {
    return dim3(unsigned((nx + tile.x - 1) / tile.x), unsigned((ny + tile.y - 1) / tile.y),
                unsigned((nz + tile.z - 1) / tile.z));
  }
};

// The plan for grid model m under options o: the tile o names, else the largest that the
// device's shared memory holds with its halo. Throws std::invalid_argument where none fits.
inline TemporalPlan plan_temporal(const Model& m, const Options& o) {
  TemporalPlan plan;
  plan.k = cuda::steps_per_launch(o);
  const int halo = dev::kHalo * plan.k;
  const bool volume = m.volume();
  const std::size_t cell = 4 * sizeof(float4);
  int device = 0, limit = 0, per_sm = 0, reserved = 0;
  check(cudaGetDevice(&device), "finding the device");
  check(cudaDeviceGetAttribute(&limit, cudaDevAttrMaxSharedMemoryPerBlockOptin, device),
        "reading the shared-memory limit");
  check(cudaDeviceGetAttribute(&per_sm, cudaDevAttrMaxSharedMemoryPerMultiprocessor, device),
        "reading the shared memory of a multiprocessor");
  check(cudaDeviceGetAttribute(&reserved, cudaDevAttrReservedSharedMemoryPerBlock, device),
        "reading the shared memory reserved a block");
  limit -= dev::kStopCheckShared;  // the kernel's own, beside the tile
  plan.shared_limit = limit;
  TemporalTile t = o.temporal_tile;
  if (t.x == 0) {
    // The largest square that leaves room for kTemporalBlocksPerSM blocks an SM; on lattices,
    // whose halo grows in three axes, the largest cube that fits one.
    const int blocks = volume ? 1 : dev::kTemporalBlocksPerSM;
    const int share = std::min(limit, per_sm / blocks - reserved - dev::kStopCheckShared);
    const int side = int(std::pow(double(std::size_t(share) / cell), volume ? 1.0 / 3.0 : 0.5) + 1e-9) - 2 * halo;
    t = {side, side, volume ? side : 1};
  }
  if (!volume) t.z = 1;
  if (t.z == 0) t.z = t.y;
  const std::string need = "cuda-temporal: " + std::to_string(plan.k) + " steps a launch need a halo of " +
                           std::to_string(halo) + " nodes around each tile; ";
  if (t.x < 1)
    throw std::invalid_argument(need + "no tile with it fits in the " + std::to_string(limit) +
                                " bytes of shared memory this device allows a block (choose fewer steps_per_launch)");
  const std::int64_t cells = std::int64_t(t.x + 2 * halo) * (t.y + 2 * halo) * (volume ? t.z + 2 * halo : 1);
  plan.shared = std::size_t(cells) * cell;
  if (plan.shared > std::size_t(limit))
    throw std::invalid_argument(need + "a tile of " + std::to_string(t.x) + "x" + std::to_string(t.y) +
                                (volume ? "x" + std::to_string(t.z) : "") + " nodes with it needs " +
                                std::to_string(plan.shared) + " bytes of shared memory, where this device allows " +
                                std::to_string(limit) + " a block (choose fewer steps_per_launch or a smaller tile)");
  plan.tile = int3{t.x, t.y, t.z};
  const dim3 b = plan.blocks(m.nx, m.ny, m.nz);
  if (b.y > 65535 || b.z > 65535)
    throw std::invalid_argument("cuda-temporal: the grid exceeds the CUDA launch limits with this tile");
  return plan;
}

}  // namespace deformlab::cuda::DL_CUDA_MATH
