// Device helpers and kernels of the CUDA pipelines. Every formula comes from the shared
// per-node physics (core/node_physics.h, as Physics<float>); per node the kernels do the CPU
// pipeline's float arithmetic in the same order. Positions are float4 (xyz + inverse mass in
// w), velocities and accelerations float4 with w unused. Built once per math mode (DL_CUDA_MATH:
// exact or fast, cuda_kernels/CMakeLists.txt), each in its own namespace.
#pragma once
#include <cuda_runtime.h>

#include <cstdint>

#include "core/grid_stencil.hpp"
#include "core/integrator.hpp"
#include "core/physics.hpp"

namespace deformlab::cuda::DL_CUDA_MATH::dev {

using P = Physics<float>;
using StepParams = P::StepParams;

// A grid's spring constants and rest lengths per stencil entry (the offsets themselves are
// the compile-time grid_offset(volume, e)).
struct Stencil {
  P::StencilEntry e[kLatticeStencil];
};

// One CSR entry: the spring's other end and its constants. Aligned to its 16 bytes, so that a
// gather loads it with one vector load instead of four.
struct alignas(16) Link {
  int node;
  float rest, k, kd;
};

struct Spring {
  int i, j;
  float rest, k, kd;
};

// Drag targets of one pass: at the force evaluation's time and at the end of the step.
struct Targets {
  Vec3f force, end;
};

__device__ __forceinline__ Vec3f xyz(const float4& a) { return {a.x, a.y, a.z}; }
__device__ __forceinline__ float4 f4(const Vec3f& a, float w) { return make_float4(a.x, a.y, a.z, w); }
__device__ __forceinline__ std::int64_t thread_index() {
  return std::int64_t(blockIdx.x) * blockDim.x + threadIdx.x;
}

// A window on node data around one node: the whole array (global memory) or a shared tile.
struct Window {
  const float4* x;
  const float4* v;
  int base, stride_j, stride_k;
  __device__ __forceinline__ int at(int di, int dj, int dk) const { return base + di + dj * stride_j + dk * stride_k; }
};

// Damped neighbours loaded at a time (each brings x and v; undamped ones go four at a time).
// Fast math: one, which keeps the kernels within their 40-register cap without spilling (two
// spilled 40-52 bytes a thread) and took cuda-fused from 0.111-0.116 to 0.108 ms at 2048^2 and
// from 1.68-1.71 to 1.63 at 8192^2 (H100, paper scene, Euler; docs/speed.md). Exact math: two
// (one measured 4-5% slower).
#ifdef DL_CUDA_FAST_MATH
constexpr int kDampedGroup = 1;
#else
constexpr int kDampedGroup = 2;
#endif

// Sum of spring forces on grid node (i, j, k) from its N stencil neighbours (N: 12 cloth, 32
// lattice). Checked: some neighbours may lie outside the grid (nodes within 2 of a border).
// Undamped springs do not read the neighbours' velocities (kd = 0 makes the damping term 0
// either way). The neighbours are loaded a group at a time before their springs are
// computed, so that the loads are in flight together.
template <int N, bool Damped, bool Checked>
__device__ __forceinline__ Vec3f gather_stencil(const StepParams& s, const Stencil& st, int i, int j, int k,
                                                const Vec3f& xi, const Vec3f& vi, const Window& w) {
  constexpr int G = Damped ? kDampedGroup : 4;
  Vec3f f{};
#pragma unroll
  for (int g = 0; g < N; g += G) {
    float4 xn[G], vn[Damped ? G : 1];
    bool ok[G];
#pragma unroll
    for (int q = 0; q < G; ++q) {
      const GridOffset o = grid_offset(N == kLatticeStencil, g + q);
      ok[q] = !Checked || P::grid_neighbour(s, i, j, k, o.di, o.dj, o.dk) >= 0;
      if (ok[q]) {
        const int at = w.at(o.di, o.dj, o.dk);
        xn[q] = w.x[at];
        if (Damped) vn[q] = w.v[at];
      }
    }
#pragma unroll
    for (int q = 0; q < G; ++q) {
      if (!ok[q]) continue;
      const P::StencilEntry& e = st.e[g + q];
      const Vec3f vj = Damped ? xyz(vn[Damped ? q : 0]) : vi;
      f += P::spring_force(xi, xyz(xn[q]), vi, vj, e.k, e.kd, e.rest);
    }
  }
  return f;
}

// The gather with bounds checks only for nodes near a border (P::grid_interior).
template <int N, bool Damped>
__device__ __forceinline__ Vec3f gather_grid(const StepParams& s, const Stencil& st, int i, int j, int k,
                                             const Vec3f& xi, const Vec3f& vi, const Window& w) {
  if (P::grid_interior(s, i, j, k, N == kLatticeStencil))
    return gather_stencil<N, Damped, false>(s, st, i, j, k, xi, vi, w);
  return gather_stencil<N, Damped, true>(s, st, i, j, k, xi, vi, w);
}

// Sum of spring forces on node i from its CSR adjacency (general models). Undamped models
// do not read the neighbours' velocities (kd = 0 makes the damping term 0 either way).
template <bool Damped>
__device__ __forceinline__ Vec3f gather_csr(const int* __restrict__ offset, const Link* __restrict__ links,
                                            const float4* __restrict__ x, const float4* __restrict__ v, int i,
                                            const Vec3f& xi, const Vec3f& vi) {
  Vec3f f{};
  for (int e = offset[i]; e < offset[i + 1]; ++e) {
    const Link l = links[e];
    f += P::spring_force(xi, xyz(x[l.node]), vi, Damped ? xyz(v[l.node]) : vi, l.k, l.kd, l.rest);
  }
  return f;
}

// The one-pass update (rule RULE_*) and the constraints of node i, written to (xo, vo);
// half_step: Verlet's v is the half step's (State::half_step).
// Returns the node's term of the stop rule (P::displacement).
template <int Rule>
__device__ __forceinline__ float advance_node(const StepParams& s, float weight, int i, const float4& x4,
                                              const float4& v4, const Vec3f& a, bool half_step,
                                              const Vec3f& end_target, float4* xo, float4* vo) {
  const Vec3f x = xyz(x4);
  Vec3f xn, vn;
  P::one_pass_update(Rule, weight, x, xyz(v4), a, half_step, s.dt, xn, vn);
  P::constrain_node(s, i, x4.w, x, end_target, xn, vn);
  xo[i] = f4(xn, x4.w);
  vo[i] = f4(vn, 0.f);
  return P::displacement(xn, x, vn);
}

// The stop rule's reduction, in the launch that writes a step's result: the largest term
// (P::displacement: non-negative, +inf where the state is not finite) as float bits, which
// order as the floats do. Each block adds its own into `max` with one atomicMax. Block 0 also
// passes the maximum of the launch before (complete, by stream order) to the host, tagged with
// this launch's number, and clears its word, which the launch after this one adds into.
struct StopCheck {
  unsigned* max;       // 0 at the launch; null: no check in this kernel
  unsigned* last;      // the launch before's
  unsigned* launches;  // result launches so far
  unsigned long long* host;  // mapped host memory: launch number << 32 | the launch before's maximum
};
constexpr int kStopCheckShared = 32 * sizeof(unsigned);  // static shared memory of store_displacement

__device__ __forceinline__ unsigned thread_in_block() {
  return (threadIdx.z * blockDim.y + threadIdx.y) * blockDim.x + threadIdx.x;
}

// Called by every thread of the block, with its node's term (0 for a thread without a node).
// The kernels keep such threads to the end rather than return early: the lanes of a warp are
// then known without holding a mask through the kernel, and all reach the barrier.
__device__ __forceinline__ void store_displacement(const StopCheck& c, float d) {
  __shared__ unsigned warp_max[kStopCheckShared / sizeof(unsigned)];
  const unsigned threads = blockDim.x * blockDim.y * blockDim.z, t = thread_in_block();
  const unsigned in_warp = min(32u, threads - (t - t % 32));
  const unsigned bits = __reduce_max_sync(in_warp == 32 ? 0xffffffffu : (1u << in_warp) - 1u, __float_as_uint(d));
  if (t % 32 == 0) warp_max[t / 32] = bits;
  __syncthreads();
  if (t >= 32) return;
  const unsigned block_max = __reduce_max_sync(0xffffffffu, t < (threads + 31) / 32 ? warp_max[t] : 0u);
  if (t != 0) return;
  atomicMax(c.max, block_max);
  if (blockIdx.x != 0 || blockIdx.y != 0 || blockIdx.z != 0) return;
  const unsigned long long launch = ++*c.launches;
  *c.host = launch << 32 | atomicExch(c.last, 0u);
  __threadfence_system();
}

// ---- grid kernels: block (tile.x, tile.y) over (i, j), grid.z over layers k ----

// Register cap of the grid gather kernels: the compiler's choice (about 80) limits an SM to
// 3 blocks of 256 threads; the gather is issue-bound, and more resident warps hide its
// latencies better. Measured on the H100 (paper scene, 2048^2, fused): exact 48 (40: 11%
// slower, 64 and 80 slower too); fast 40 (48 11% slower, 36 8%; with the L2 prefetch and two
// damped neighbours at a time, 44 4% and 48 12% slower).
#ifdef DL_CUDA_FAST_MATH
constexpr int kGatherRegisters = 40;
#else
constexpr int kGatherRegisters = 48;
#endif

// Whether fused_grid asks L2 for the state of a node ahead of its own: in fast math only. With
// exact math the kernel is bound by its arithmetic, and the prefetch measured 1-2% slower there
// except for Verlet (H100, 2048^2 and 8192^2 cloths, a 256^3 lattice; docs/speed.md).
#ifdef DL_CUDA_FAST_MATH
constexpr bool kPrefetchAhead = true;
#else
constexpr bool kPrefetchAhead = false;
#endif

// Halo of the shared tile: flexion springs reach two nodes.
constexpr int kHalo = STENCIL_REACH;

// Loads the block's nodes and their halo (2 in i and j, and in k on lattices) into shared
// memory, coalesced along i. Cells outside the grid are left unset and never read.
template <bool Volume, bool Damped>
__device__ __forceinline__ Window load_tile(const StepParams& s, const float4* __restrict__ x, const float4* __restrict__ v,
                                            float4* sh) {
  const int tw = blockDim.x + 2 * kHalo, th = blockDim.y + 2 * kHalo, hz = Volume ? kHalo : 0;
  const int cells = tw * th * (2 * hz + 1);
  const int i0 = blockIdx.x * blockDim.x - kHalo, j0 = blockIdx.y * blockDim.y - kHalo, k0 = blockIdx.z - hz;
  for (int c = 0; c < 2 * hz + 1; ++c)  // loops rather than one index: no divisions
    for (int b = threadIdx.y; b < th; b += blockDim.y)
      for (int a = threadIdx.x; a < tw; a += blockDim.x) {
        const int gi = i0 + a, gj = j0 + b, gk = k0 + c, l = (c * th + b) * tw + a;
        if (gi < 0 || gi >= s.nx || gj < 0 || gj >= s.ny || gk < 0 || gk >= s.nz) continue;
        const std::int64_t g = (std::int64_t(gk) * s.ny + gj) * s.nx + gi;
        sh[l] = x[g];
        if (Damped) sh[cells + l] = v[g];
      }
  __syncthreads();
  const int base = (hz * th + threadIdx.y + kHalo) * tw + threadIdx.x + kHalo;
  return {sh, Damped ? sh + cells : nullptr, base, tw, tw * th};
}

// Grid node (i, j, k)'s acceleration, its neighbours read through w; pinned and hard-dragged
// nodes skip the gather.
template <int N, bool Damped>
__device__ __forceinline__ Vec3f grid_accel(const StepParams& s, const Stencil& st, int i, int j, int k, int node,
                                            const float4& x4, const float4& v4, const Window& w,
                                            const Vec3f& drag_target) {
  if (P::node_fixed(s, node, x4.w)) return {};
  const Vec3f xi = xyz(x4), vi = xyz(v4);
  return P::node_acceleration(s, node, x4.w, xi, vi, gather_grid<N, Damped>(s, st, i, j, k, xi, vi, w), drag_target);
}

// Force pass on a grid: acc = a(x, v). Tiled: neighbours from a shared tile.
template <int N, bool Damped, bool Tiled>
__global__ void __maxnreg__(kGatherRegisters) force_grid(StepParams s, Stencil st, const float4* __restrict__ x,
                                                         const float4* __restrict__ v, float4* __restrict__ acc,
                                                         Vec3f drag_target) {
  extern __shared__ float4 sh[];
  const int i = blockIdx.x * blockDim.x + threadIdx.x, j = blockIdx.y * blockDim.y + threadIdx.y, k = blockIdx.z;
  Window w{x, v, 0, s.nx, s.nx * s.ny};
  if constexpr (Tiled) w = load_tile<N == kLatticeStencil, Damped>(s, x, v, sh);
  if (i >= s.nx || j >= s.ny) return;
  const int node = P::grid_node(i, j, k, s.nx, s.ny);
  if constexpr (!Tiled) w.base = node;
  // Loaded here, whole: passed as x[node] and v[node], the loads split and ran 6% slower.
  const float4 x4 = x[node], v4 = v[node];
  acc[node] = f4(grid_accel<N, Damped>(s, st, i, j, k, node, x4, v4, w, drag_target), 0.f);
}

// Force, update and constraints in one kernel (one-force-pass schedules): reads (x, v), writes
// (xo, vo).
// With kPrefetchAhead each thread first asks L2 for the state of the node `prefetch` after its
// own, which a block launched later reads: its loads then wait on L2 rather than on DRAM (H100,
// paper scene: semi-implicit Euler 4% and Verlet 5% faster at 2048^2, Verlet 6% at 8192^2,
// explicit Euler within 1%; docs/speed.md).
template <int N, bool Damped, int Rule>
__global__ void __maxnreg__(kGatherRegisters) fused_grid(StepParams s, Stencil st, float weight,
                                                         const float4* __restrict__ x, const float4* __restrict__ v,
                                                         bool half_step, float4* xo,
                                                         float4* __restrict__ vo, Targets tg, StopCheck check,
                                                         int prefetch) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x, j = blockIdx.y * blockDim.y + threadIdx.y, k = blockIdx.z;
  float d = 0.f;
  if (i < s.nx && j < s.ny) {
    const int node = P::grid_node(i, j, k, s.nx, s.ny);
    if (kPrefetchAhead && node < s.node_count - prefetch) {
      asm volatile("prefetch.global.L2 [%0];" ::"l"(x + node + prefetch));
      asm volatile("prefetch.global.L2 [%0];" ::"l"(v + node + prefetch));
    }
    const float4 x4 = x[node], v4 = v[node];
    // grid_accel written out: through it this kernel measured about 1% slower on semi-implicit
    // Euler (fast math in two calls, exact in one; H200, 2048^2 paper scene; docs/speed.md).
    Vec3f a{};
    if (!P::node_fixed(s, node, x4.w)) {
      const Vec3f xi = xyz(x4), vi = xyz(v4);
      const Window w{x, v, node, s.nx, s.nx * s.ny};
      a = P::node_acceleration(s, node, x4.w, xi, vi, gather_grid<N, Damped>(s, st, i, j, k, xi, vi, w), tg.force);
    }
    d = advance_node<Rule>(s, weight, node, x4, v4, a, half_step, tg.end, xo, vo);
  }
  store_displacement(check, d);
}

// ---- general models: one thread per node over the CSR adjacency ----

// Node i's acceleration; pinned and hard-dragged nodes skip the gather.
template <bool Damped>
__device__ __forceinline__ Vec3f csr_accel(const StepParams& s, const int* __restrict__ offset,
                                           const Link* __restrict__ links, const float4* __restrict__ x,
                                           const float4* __restrict__ v, int i, const float4& x4, const float4& v4,
                                           const Vec3f& drag_target) {
  if (P::node_fixed(s, i, x4.w)) return {};
  const Vec3f xi = xyz(x4), vi = xyz(v4);
  return P::node_acceleration(s, i, x4.w, xi, vi, gather_csr<Damped>(offset, links, x, v, i, xi, vi), drag_target);
}

template <bool Damped>
__global__ void force_csr(StepParams s, const int* __restrict__ offset, const Link* __restrict__ links,
                          const float4* __restrict__ x, const float4* __restrict__ v, float4* __restrict__ acc,
                          Vec3f drag_target) {
  const std::int64_t t = thread_index();
  if (t >= s.node_count) return;
  const int i = int(t);
  acc[i] = f4(csr_accel<Damped>(s, offset, links, x, v, i, x[i], v[i], drag_target), 0.f);
}

template <int Rule, bool Damped>
__global__ void fused_csr(StepParams s, float weight, const int* __restrict__ offset, const Link* __restrict__ links,
                          const float4* __restrict__ x, const float4* __restrict__ v, bool half_step, float4* xo,
                          float4* __restrict__ vo, Targets tg, StopCheck check) {
  const std::int64_t t = thread_index();
  float d = 0.f;
  if (t < s.node_count) {
    const int i = int(t);
    const float4 x4 = x[i], v4 = v[i];
    const Vec3f a = csr_accel<Damped>(s, offset, links, x, v, i, x4, v4, tg.force);
    d = advance_node<Rule>(s, weight, i, x4, v4, a, half_step, tg.end, xo, vo);
  }
  store_displacement(check, d);
}

// ---- general models, tiled (cuda-tiled): one thread block per tile of core/partition.hpp ----

// A Tiling on the device; links[e].node is a cell of the member's own tile.
struct TiledCsr {
  const int* __restrict__ tile_offset;
  const int* __restrict__ tile_node;
  const int* __restrict__ members;
  const int* __restrict__ link_offset;
  const Link* __restrict__ links;
};

// Force pass: the block stages its tile's positions (and velocities, if damped) in shared
// memory, then each member gathers its springs from there (gather_csr over the tile's cells).
template <bool Damped>
__global__ void force_tiled_csr(StepParams s, TiledCsr t, const float4* __restrict__ x, const float4* __restrict__ v,
                                float4* __restrict__ acc, Vec3f drag_target) {
  extern __shared__ float4 sh[];
  const int c0 = t.tile_offset[blockIdx.x], cells = t.tile_offset[blockIdx.x + 1] - c0;
  float4* sv = sh + cells;
  for (int c = threadIdx.x; c < cells; c += blockDim.x) {
    const int g = t.tile_node[c0 + c];
    sh[c] = x[g];
    if (Damped) sv[c] = v[g];
  }
  __syncthreads();
  if (int(threadIdx.x) >= t.members[blockIdx.x]) return;
  const int p = c0 + threadIdx.x, i = t.tile_node[p];
  const float4 x4 = sh[threadIdx.x], v4 = Damped ? sv[threadIdx.x] : v[i];
  Vec3f a{};
  if (!P::node_fixed(s, i, x4.w)) {
    const Vec3f xi = xyz(x4), vi = xyz(v4);
    a = P::node_acceleration(s, i, x4.w, xi, vi, gather_csr<Damped>(t.link_offset, t.links, sh, sv, p, xi, vi),
                             drag_target);
  }
  acc[i] = f4(a, 0.f);
}

// ---- scatter: one thread per spring, atomics; then per node force sum -> acceleration ----

__global__ void scatter_springs(const Spring* __restrict__ springs, std::int64_t count, const float4* __restrict__ x,
                                const float4* __restrict__ v, float4* force) {
  const std::int64_t t = thread_index();
  if (t >= count) return;
  const Spring sp = springs[t];
  const Vec3f f = P::spring_force(xyz(x[sp.i]), xyz(x[sp.j]), xyz(v[sp.i]), xyz(v[sp.j]), sp.k, sp.kd, sp.rest);
  atomicAdd(&force[sp.i].x, f.x);
  atomicAdd(&force[sp.i].y, f.y);
  atomicAdd(&force[sp.i].z, f.z);
  atomicAdd(&force[sp.j].x, -f.x);
  atomicAdd(&force[sp.j].y, -f.y);
  atomicAdd(&force[sp.j].z, -f.z);
}

// Grids: one thread per node and own stencil entry (the second half: one per spring), the
// spring to that neighbour scattered as above. No spring list: the stencil is the model.
template <int N>
__global__ void scatter_grid(StepParams s, Stencil st, const float4* __restrict__ x, const float4* __restrict__ v,
                             float4* force) {
  const std::int64_t t = thread_index();
  if (t >= std::int64_t(s.node_count) * (N / 2)) return;
  const int u = int(t / (N / 2)), e = N / 2 + int(t % (N / 2));
  const int i = P::grid_axis(u, 1, s.nx), j = P::grid_axis(u, s.nx, s.ny), k = P::grid_axis(u, s.nx * s.ny, s.nz);
  const P::StencilEntry& o = st.e[e];
  const int w = P::grid_neighbour(s, i, j, k, o.di, o.dj, o.dk);
  if (w < 0) return;
  const Vec3f f = P::spring_force(xyz(x[u]), xyz(x[w]), xyz(v[u]), xyz(v[w]), o.k, o.kd, o.rest);
  atomicAdd(&force[u].x, f.x);
  atomicAdd(&force[u].y, f.y);
  atomicAdd(&force[u].z, f.z);
  atomicAdd(&force[w].x, -f.x);
  atomicAdd(&force[w].y, -f.y);
  atomicAdd(&force[w].z, -f.z);
}

__global__ void scatter_finish(StepParams s, const float4* __restrict__ x, const float4* __restrict__ v, float4* acc,
                               Vec3f drag_target) {
  const std::int64_t t = thread_index();
  if (t >= s.node_count) return;
  const int i = int(t);
  const float4 x4 = x[i];
  acc[i] = f4(P::node_acceleration(s, i, x4.w, xyz(x4), xyz(v[i]), xyz(acc[i]), drag_target), 0.f);
}

// ---- updates ----

// One-pass update from acceleration slot 0 (the variants that run forces on their own).
template <int Rule>
__global__ void update(StepParams s, float weight, const float4* __restrict__ x, const float4* __restrict__ v,
                       const float4* __restrict__ acc, bool half_step, float4* xo,
                       float4* __restrict__ vo, Vec3f end_target, StopCheck check) {
  const std::int64_t t = thread_index();
  float d = 0.f;
  if (t < s.node_count) {
    const int i = int(t);
    d = advance_node<Rule>(s, weight, i, x[i], v[i], xyz(acc[i]), half_step, end_target, xo, vo);
  }
  store_displacement(check, d);
}

// The slopes of a Runge-Kutta combination with a non-zero weight, in stage order.
struct Terms {
  const float4* v[kMaxStages];
  const float4* a[kMaxStages];
  float weight[kMaxStages];
  int count;
};

// A stage state, or (result: the check's slots set) the step's result, its constraints and
// the stop rule's reduction: s0 + dt sum_j w_j k_j.
__global__ void combine(StepParams s, const float4* __restrict__ x, const float4* __restrict__ v, Terms terms,
                        float4* __restrict__ xo, float4* __restrict__ vo, Vec3f end_target, StopCheck check) {
  const bool result = check.max != nullptr;
  const std::int64_t t = thread_index();
  float d = 0.f;
  if (t < s.node_count) {
    const int i = int(t);
    Vec3f dx{}, dv{};
#pragma unroll
    for (int q = 0; q < kMaxStages; ++q) {
      if (q >= terms.count) break;
      P::add_slope(dx, dv, terms.weight[q], xyz(terms.v[q][i]), xyz(terms.a[q][i]));
    }
    const float4 x4 = x[i];
    const Vec3f x_old = xyz(x4);
    Vec3f xn, vn;
    P::rk_state(x_old, xyz(v[i]), dx, dv, s.dt, xn, vn);
    if (result) P::constrain_node(s, i, x4.w, x_old, end_target, xn, vn);
    xo[i] = f4(xn, x4.w);
    vo[i] = f4(vn, 0.f);
    if (result) d = P::displacement(xn, x_old, vn);
  }
  if (result) store_displacement(check, d);
}

}  // namespace deformlab::cuda::DL_CUDA_MATH::dev
