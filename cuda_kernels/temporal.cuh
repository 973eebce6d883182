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
// Threads a block, and the blocks an SM holds at once with the default tile: two, so that one
// block's loads and stores overlap the other's steps.
constexpr int kTemporalThreads = 512;
constexpr int kTemporalBlocksPerSM = 2;

// The drag targets of each step of a launch.
struct StepTargets {
  Targets step[kMaxStepsPerLaunch];
};

// A box of region cells: `size` cells from `lo` along each axis.
struct Box {
  int3 lo, size;
};

// a / b (rounded down) for 0 <= a < 2^21 and b >= 1, given rb = __frcp_rn(b): (a + 0.5) / b
// lies at least 0.5 / b from an integer, and the two correctly rounded operations move it by
// at most (a + 0.5) / b * 2^-23, less than that. A few instructions where an integer division
// takes twenty.
__device__ __forceinline__ int small_quotient(int a, float rb) {
  return __float2int_rz(__fmul_rn(__fadd_rn(float(a), 0.5f), rb));
}

// Calls f(c) for each cell c of the box, the block's threads taking consecutive cells (along i
// first: coalesced).
template <bool Volume, class F>
__device__ __forceinline__ void for_each_cell(const Box& b, F&& f) {
  const int count = b.size.x * b.size.y * b.size.z;
  const float rx = __frcp_rn(float(b.size.x)), ry = __frcp_rn(float(b.size.y));
  for (int t = threadIdx.x; t < count; t += blockDim.x) {
    const int row = small_quotient(t, rx);
    int3 c{t - row * b.size.x, row, 0};
    if (Volume) {
      c.z = small_quotient(row, ry);
      c.y = row - c.z * b.size.y;
    }
    f(int3{b.lo.x + c.x, b.lo.y + c.y, b.lo.z + c.z});
  }
}

// A block's region: its tile of (tx, ty, tz) nodes at (i, j, k) = block index * tile, and
// `halo` nodes around it on each side (in k only on lattices).
template <bool Volume>
struct Region {
  int3 first;  // grid coordinates of the region's first cell (may be negative)
  int3 cells;  // along each axis
  int halo;

  __device__ Region(int3 tile, int h)
      : first{int(blockIdx.x) * tile.x - h, int(blockIdx.y) * tile.y - h, int(blockIdx.z) * tile.z - (Volume ? h : 0)},
        cells{tile.x + 2 * h, tile.y + 2 * h, tile.z + (Volume ? 2 * h : 0)},
        halo(h) {}
  __device__ int count() const { return cells.x * cells.y * cells.z; }
  __device__ int index(int3 c) const { return (c.z * cells.y + c.y) * cells.x + c.x; }
  __device__ int node(const StepParams& s, int3 c) const {
    return P::grid_node(first.x + c.x, first.y + c.y, first.z + c.z, s.nx, s.ny);
  }
  // The cells in the grid and `depth` cells in from every side where the region was cut out
  // of the grid: after step q their state is correct at depth 2 (q + 1).
  __device__ Box valid(const StepParams& s, int depth) const {
    return per_axis(s, [depth](int first, int cells, int n) {
      const int lo = first <= 0 ? -first : depth;
      return int2{lo, max(0, (first + cells >= n ? n - first : cells - depth) - lo)};
    });
  }
  // The block's own nodes: its tile, within the grid.
  __device__ Box owned(const StepParams& s) const {
    return per_axis(s, [h = halo](int first, int cells, int n) { return int2{h, max(0, min(cells - h, n - first) - h)}; });
  }

 private:
  // The box whose extent along each axis is axis(first, cells, grid size) = (lo, size); one cell
  // along k on cloths.
  template <class Axis>
  __device__ Box per_axis(const StepParams& s, Axis axis) const {
    const int2 x = axis(first.x, cells.x, s.nx), y = axis(first.y, cells.y, s.ny);
    const int2 z = Volume ? axis(first.z, cells.z, s.nz) : int2{0, 1};
    return {{x.x, y.x, z.x}, {x.y, y.y, z.y}};
  }
};

// Reads (x, v), writes k = `steps` steps later (xo, vo); half_step: Verlet's v is the half
// step's (State::half_step) at the first step. Shared memory: two copies of (x, v) per region
// cell, a step reading one and writing the other.
template <int N, bool Damped, int Rule>
__global__ void __launch_bounds__(kTemporalThreads, kTemporalBlocksPerSM)
    temporal_grid(StepParams s, Stencil st, float weight, int steps, int3 tile, const float4* __restrict__ x,
                  const float4* __restrict__ v, bool half_step, float4* __restrict__ xo,
                  float4* __restrict__ vo, StepTargets tg, StopCheck check) {
  constexpr bool kVolume = N == kLatticeStencil;
  extern __shared__ float4 sh[];
  const Region<kVolume> r(tile, kHalo * steps);
  const int cells = r.count();
  // Copy c of the positions and of the velocities (offsets, not an array of pointers: one
  // indexed by the step's parity would live in local memory).
  auto sx = [&](int c) { return sh + c * cells; };
  auto sv = [&](int c) { return sh + (2 + c) * cells; };
  for_each_cell<kVolume>(r.valid(s, 0), [&](int3 c) {
    const int l = r.index(c), g = r.node(s, c);
    sx(0)[l] = x[g];
    sv(0)[l] = v[g];
  });
  __syncthreads();
  int cur = 0;
  for (int q = 0; q < steps; ++q) {
    const bool half = half_step || q > 0;
    for_each_cell<kVolume>(r.valid(s, kHalo * (q + 1)), [&](int3 c) {
      const int i = r.first.x + c.x, j = r.first.y + c.y, k = r.first.z + c.z, l = r.index(c);
      const int node = P::grid_node(i, j, k, s.nx, s.ny);
      const float4 x4 = sx(cur)[l], v4 = sv(cur)[l];
      const Vec3f xi = xyz(x4), vi = xyz(v4);
      const Window w{sx(cur), sv(cur), l, r.cells.x, r.cells.x * r.cells.y};
      const Vec3f acc = grid_accel<N, Damped>(s, st, i, j, k, node, x4, v4, w, tg.step[q].force);
      Vec3f xn, vn;
      P::one_pass_update(Rule, weight, xi, vi, acc, half, s.dt, xn, vn);
      P::constrain_node(s, node, x4.w, xi, tg.step[q].end, xn, vn);
      sx(1 - cur)[l] = f4(xn, x4.w);
      sv(1 - cur)[l] = f4(vn, 0.f);
    });
    cur = 1 - cur;
    __syncthreads();
  }
  // The last step's result is in copy cur, its start in the other.
  float d = 0.f;
  for_each_cell<kVolume>(r.owned(s), [&](int3 c) {
    const int l = r.index(c), g = r.node(s, c);
    const float4 xn = sx(cur)[l], vn = sv(cur)[l], xs = sx(1 - cur)[l];
    xo[g] = xn;
    vo[g] = vn;
    d = fmaxf(d, P::displacement(xyz(xn), xyz(xs), xyz(vn)));
  });
  store_displacement(check, d);
}

}  // namespace deformlab::cuda::DL_CUDA_MATH::dev
