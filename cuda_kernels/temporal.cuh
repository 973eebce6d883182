// cuda-temporal: k steps of a grid in one launch. Each block copies its tile of the state and
// a halo of 2k nodes (flexion springs reach two nodes, so a step's result is wrong 2 nodes
// further in from a cut) into shared memory, advances the copy k times there, and writes back
// the tile's own nodes. Device memory sees a state read and written once per k steps; the
// halo's nodes are computed again by each block that overlaps them. Per node and step it does
// cuda-fused's arithmetic in the same order (the same gather, update and constraints).
#pragma once
#include "kernels.cuh"

namespace deformlab::cuda::DL_CUDA_MATH::dev {

constexpr int kMaxStepsPerLaunch = 8;
constexpr int kTemporalThreads = 1024;

// The drag targets of each step of a launch.
struct StepTargets {
  Targets step[kMaxStepsPerLaunch];
};

// A block's region: its tile of (tx, ty, tz) nodes at (i, j, k) = block index * tile, and
// `halo` nodes around it on each side (in k only on lattices).
struct Region {
  int3 first;  // grid coordinates of the region's first cell (may be negative)
  int3 cells;  // along each axis
  int halo;
  __device__ int count() const { return cells.x * cells.y * cells.z; }
  __device__ int3 at(int l) const { return {l % cells.x, (l / cells.x) % cells.y, l / (cells.x * cells.y)}; }
};

template <bool Volume>
__device__ __forceinline__ Region block_region(int3 tile, int halo) {
  const int hz = Volume ? halo : 0;
  return {{int(blockIdx.x) * tile.x - halo, int(blockIdx.y) * tile.y - halo, int(blockIdx.z) * tile.z - hz},
          {tile.x + 2 * halo, tile.y + 2 * halo, tile.z + 2 * hz},
          halo};
}

// Whether cell c lies in the grid and `depth` cells in from every side where the region was
// cut out of the grid: after step q its state is correct at depth 2 (q + 1).
template <bool Volume>
__device__ __forceinline__ bool cell_valid(const StepParams& s, const Region& r, int3 c, int depth) {
  auto axis = [](int at, int first, int cells, int n, int d) {
    const int g = first + at;
    return g >= 0 && g < n && (first <= 0 || at >= d) && (first + cells >= n || at < cells - d);
  };
  return axis(c.x, r.first.x, r.cells.x, s.nx, depth) && axis(c.y, r.first.y, r.cells.y, s.ny, depth) &&
         axis(c.z, r.first.z, r.cells.z, s.nz, Volume ? depth : 0);
}

// Whether cell c is one of the block's own nodes (its tile, within the grid).
template <bool Volume>
__device__ __forceinline__ bool cell_owned(const StepParams& s, const Region& r, int3 c) {
  const int hz = Volume ? r.halo : 0;
  auto own = [](int at, int first, int cells, int h, int n) { return at >= h && at < cells - h && first + at < n; };
  return own(c.x, r.first.x, r.cells.x, r.halo, s.nx) && own(c.y, r.first.y, r.cells.y, r.halo, s.ny) &&
         own(c.z, r.first.z, r.cells.z, hz, s.nz);
}

// Reads (x, v) and x_prev (Verlet), writes k = `steps` steps later (xo, vo) and, for Verlet,
// the positions one step before those (po). x_prev is not read when has_prev is false.
// Shared memory: two copies of (x, v) per region cell; Verlet's new positions overwrite the
// copy holding the previous ones, cell by cell, as in fused_grid.
template <int N, bool Damped, int Rule>
__global__ void __launch_bounds__(kTemporalThreads)
    temporal_grid(StepParams s, Stencil st, float weight, int steps, int3 tile, const float4* __restrict__ x,
                  const float4* __restrict__ v, const float4* __restrict__ x_prev, bool has_prev,
                  float4* __restrict__ xo, float4* __restrict__ vo, float4* __restrict__ po, StepTargets tg,
                  StopCheck check) {
  constexpr bool kVolume = N > 12, kVerlet = Rule == RULE_VERLET;
  extern __shared__ float4 sh[];
  const Region r = block_region<kVolume>(tile, 2 * steps);
  const int cells = r.count();
  float4* sx[2] = {sh, sh + cells};
  float4* sv[2] = {sh + 2 * cells, sh + 3 * cells};
  auto node_of = [&](int3 c) { return P::grid_node(r.first.x + c.x, r.first.y + c.y, r.first.z + c.z, s.nx, s.ny); };
  for (int l = threadIdx.x; l < cells; l += blockDim.x) {
    const int3 c = r.at(l);
    if (!cell_valid<kVolume>(s, r, c, 0)) continue;
    const int g = node_of(c);
    sx[0][l] = x[g];
    sv[0][l] = v[g];
    if (kVerlet && has_prev) sx[1][l] = x_prev[g];
  }
  __syncthreads();
  float d = 0.f;
  int cur = 0;
  for (int q = 0; q < steps; ++q) {
    const bool prev = has_prev || q > 0;
    for (int l = threadIdx.x; l < cells; l += blockDim.x) {
      const int3 c = r.at(l);
      if (!cell_valid<kVolume>(s, r, c, 2 * (q + 1))) continue;
      const int i = r.first.x + c.x, j = r.first.y + c.y, k = r.first.z + c.z, node = node_of(c);
      const float4 x4 = sx[cur][l], v4 = sv[cur][l];
      const Vec3f xi = xyz(x4), vi = xyz(v4);
      Vec3f acc{};
      if (!P::node_fixed(s, node, x4.w)) {
        const Window w{sx[cur], sv[cur], l, r.cells.x, r.cells.x * r.cells.y};
        acc = P::node_acceleration(s, node, x4.w, xi, vi, gather_grid<N, Damped>(s, st, i, j, k, xi, vi, w),
                                   tg.step[q].force);
      }
      const Vec3f xp = kVerlet && prev ? xyz(sx[1 - cur][l]) : Vec3f{};
      Vec3f xn, vn;
      P::one_pass_update(Rule, weight, xi, vi, acc, xp, prev, s.dt, xn, vn);
      P::constrain_node(s, node, x4.w, xi, tg.step[q].end, xn, vn);
      sx[1 - cur][l] = f4(xn, x4.w);
      sv[1 - cur][l] = f4(vn, 0.f);
      if (q == steps - 1 && cell_owned<kVolume>(s, r, c)) d = fmaxf(d, P::displacement(xn, xi, vn));
    }
    cur = 1 - cur;
    __syncthreads();
  }
  for (int l = threadIdx.x; l < cells; l += blockDim.x) {
    const int3 c = r.at(l);
    if (!cell_owned<kVolume>(s, r, c)) continue;
    const int g = node_of(c);
    xo[g] = sx[cur][l];
    vo[g] = sv[cur][l];
    if (kVerlet) po[g] = sx[1 - cur][l];
  }
  store_displacement(check, d);
}

}  // namespace deformlab::cuda::DL_CUDA_MATH::dev
