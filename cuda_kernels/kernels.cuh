// Device helpers and kernels of the CUDA pipelines. Per node they do the CPU pipeline's
// float arithmetic in the same order (core/cpu_backend.cpp); the formulas themselves come
// from core/forces.hpp. Positions are float4 (xyz + inverse mass in w), velocities and
// accelerations float4 with w unused.
#pragma once
#include <cuda_runtime.h>

#include <cstdint>

#include "core/forces.hpp"
#include "core/integrator.hpp"

namespace deformlab::cuda::dev {

constexpr int kMaxStencil = 32;  // lattice: 6 structural + 20 shear + 6 flexion

// A grid's neighbour offsets in the order of the CPU's adjacency lists (incident springs by
// spring index), with one rest length per offset and the offset's spring constants (read
// straight from the kernel parameters).
struct Stencil {
  int count;  // entries in use (offsets that occur in the model)
  std::int8_t di[kMaxStencil], dj[kMaxStencil], dk[kMaxStencil];
  float rest[kMaxStencil], k[kMaxStencil], kd[kMaxStencil];
};

struct Link {  // one CSR entry: the spring's other end
  int node, kind;
  float rest;
  int unused;
};

struct Spring {
  int i, j, kind;
  float rest;
};

// Per-pipeline constants.
struct Scene {
  int n = 0, nx = 1, ny = 1, nz = 1;
  float k[3] = {}, kd[3] = {};
  Vec3f gravity, wind;
  float c = 0.f, dt = 0.f;
  int drag_node = -1;      // -1: no drag handle
  bool drag_hard = false;  // kinematic node (else a spring of drag_k pulls it)
  float drag_k = 0.f;
  bool has_ground = false;
  float ground = 0.f;
  int sphere_count = 0;
  const float4* spheres = nullptr;  // centre xyz, radius w
};

// Drag targets of one pass: at the force evaluation's time and at the end of the step.
struct Targets {
  Vec3f force, end;
};

__device__ __forceinline__ Vec3f xyz(const float4& a) { return {a.x, a.y, a.z}; }
__device__ __forceinline__ float4 f4(const Vec3f& a, float w) { return make_float4(a.x, a.y, a.z, w); }
// Per-kind constant without dynamic indexing into parameter space.
__device__ __forceinline__ float pick(const float (&a)[3], int kind) {
  return kind == 0 ? a[0] : (kind == 1 ? a[1] : a[2]);
}
__device__ __forceinline__ std::int64_t thread_index() {
  return std::int64_t(blockIdx.x) * blockDim.x + threadIdx.x;
}

// Pinned and hard-dragged nodes have no acceleration.
__device__ __forceinline__ bool fixed(const Scene& s, int i, float w) {
  return w == 0.f || (s.drag_hard && i == s.drag_node);
}

// Spring sum -> acceleration, with the drag spring's pull on a spring-dragged node.
__device__ __forceinline__ Vec3f node_accel(const Scene& s, int i, float w, const Vec3f& xi, const Vec3f& vi,
                                            Vec3f f, const Vec3f& drag_target) {
  if (fixed(s, i, w)) return {};
  if (i == s.drag_node) f += (drag_target - xi) * s.drag_k;
  return acceleration(f, vi, w, s.c, s.wind, s.gravity);
}

// A window on node data around one node: the whole array (global memory) or a shared tile.
struct Window {
  const float4* x;
  const float4* v;
  int base, stride_j, stride_k;
  __device__ __forceinline__ int at(int di, int dj, int dk) const { return base + di + dj * stride_j + dk * stride_k; }
};

struct Offset {
  int di, dj, dk;
};

// The stencil order of grids at least 4 nodes wide (5 for lattices) is always the same; with
// it as compile-time constants the index arithmetic and the bounds checks fold away.
// Cloth: the 6 springs from lower-numbered nodes, then the node's own 6.
__host__ __device__ constexpr Offset canonical_offset(int n, int e) {
  constexpr Offset cloth[12] = {{0, -2, 0}, {-1, -1, 0}, {0, -1, 0}, {1, -1, 0}, {-2, 0, 0}, {-1, 0, 0},
                                {1, 0, 0},  {-1, 1, 0},  {0, 1, 0},  {1, 1, 0},  {2, 0, 0},  {0, 2, 0}};
  constexpr Offset lattice[32] = {
      {0, 0, -2},  {-1, -1, -1}, {0, -1, -1}, {1, -1, -1}, {-1, 0, -1}, {0, 0, -1}, {1, 0, -1},  {-1, 1, -1},
      {0, 1, -1},  {1, 1, -1},   {0, -2, 0},  {-1, -1, 0}, {0, -1, 0},  {1, -1, 0}, {-2, 0, 0},  {-1, 0, 0},
      {1, 0, 0},   {-1, 1, 0},   {0, 1, 0},   {1, 1, 0},   {-1, -1, 1}, {0, -1, 1}, {1, -1, 1},  {-1, 0, 1},
      {0, 0, 1},   {1, 0, 1},    {-1, 1, 1},  {0, 1, 1},   {1, 1, 1},   {2, 0, 0},  {0, 2, 0},   {0, 0, 2}};
  return n == 12 ? cloth[e] : lattice[e];
}

// Sum of spring forces on grid node (i, j, k) from its N stencil neighbours. Canonical: the
// offsets are canonical_offset(N, .). Checked: some neighbours may lie outside the grid
// (nodes within 2 of a border). Undamped springs do not read the neighbours' velocities
// (kd = 0 makes the damping term 0 either way). The neighbours are loaded a group at a time
// before their springs are computed, so that the loads are in flight together.
template <int N, bool Damped, bool Canonical, bool Checked>
__device__ __forceinline__ Vec3f gather_stencil(const Scene& s, const Stencil& st, int i, int j, int k,
                                                const Vec3f& xi, const Vec3f& vi, const Window& w) {
  constexpr int G = N <= 12 ? 6 : 8;  // group size: bounded register use
  Vec3f f{};
#pragma unroll
  for (int g = 0; g < N; g += G) {
    float4 xn[G], vn[Damped ? G : 1];
    bool ok[G];
#pragma unroll
    for (int q = 0; q < G; ++q) {
      const int e = g + q;
      const Offset o = Canonical ? canonical_offset(N, e) : Offset{st.di[e], st.dj[e], st.dk[e]};
      ok[q] = Canonical || e < st.count;
      if (Checked) {
        const int a = i + o.di, b = j + o.dj, c = k + o.dk;
        ok[q] = ok[q] && a >= 0 && a < s.nx && b >= 0 && b < s.ny && c >= 0 && c < s.nz;
      }
      if (ok[q]) {
        const int at = w.at(o.di, o.dj, o.dk);
        xn[q] = w.x[at];
        if (Damped) vn[q] = w.v[at];
      }
    }
#pragma unroll
    for (int q = 0; q < G; ++q) {
      if (!ok[q]) continue;
      const int e = g + q;
      const Vec3f vj = Damped ? xyz(vn[Damped ? q : 0]) : vi;
      f += spring_force(xi, xyz(xn[q]), vi, vj, st.k[e], st.kd[e], st.rest[e]);
    }
  }
  return f;
}

// The gather with bounds checks only for nodes within 2 of a border.
template <int N, bool Damped, bool Canonical>
__device__ __forceinline__ Vec3f gather_grid(const Scene& s, const Stencil& st, int i, int j, int k,
                                             const Vec3f& xi, const Vec3f& vi, const Window& w) {
  const bool inside = i >= 2 && i < s.nx - 2 && j >= 2 && j < s.ny - 2 && (N == 12 || (k >= 2 && k < s.nz - 2));
  if (Canonical && inside) return gather_stencil<N, Damped, true, false>(s, st, i, j, k, xi, vi, w);
  return gather_stencil<N, Damped, Canonical, true>(s, st, i, j, k, xi, vi, w);
}

// Sum of spring forces on node i from its CSR adjacency (general models).
__device__ __forceinline__ Vec3f gather_csr(const Scene& s, const int* __restrict__ offset,
                                            const Link* __restrict__ links, const float4* __restrict__ x,
                                            const float4* __restrict__ v, int i, const Vec3f& xi, const Vec3f& vi) {
  Vec3f f{};
  for (int e = offset[i]; e < offset[i + 1]; ++e) {
    const Link l = links[e];
    f += spring_force(xi, xyz(x[l.node]), vi, xyz(v[l.node]), pick(s.k, l.kind), pick(s.kd, l.kind), l.rest);
  }
  return f;
}

// The one-force-pass updates (cpu_backend.cpp, fused()).
template <Integrator I>
__device__ __forceinline__ void integrate(const Vec3f& x, const Vec3f& v, const Vec3f& a, const Vec3f& x_prev,
                                          bool has_prev, float dt, Vec3f& xo, Vec3f& vo) {
  if constexpr (I == Integrator::explicit_euler) {
    xo = x + v * dt;
    vo = v + a * dt;
  } else if constexpr (I == Integrator::semi_implicit_euler) {
    vo = v + a * dt;
    xo = x + vo * dt;
  } else {
    static_assert(I == Integrator::verlet, "one-pass update for a multi-pass integrator");
    const Vec3f step = has_prev ? (x - x_prev) + a * (dt * dt) : v * dt + a * (0.5f * dt * dt);
    xo = x + step;
    vo = step * (1.f / dt);
  }
}

// Constraints after an update (cpu_backend.cpp, constrain_and_commit()).
__device__ __forceinline__ void constrain(const Scene& s, int i, float w, const Vec3f& x_old, const Vec3f& end_target,
                                          Vec3f& x, Vec3f& v) {
  if (w == 0.f) {
    x = x_old;
    v = Vec3f{};
  } else if (s.drag_hard && i == s.drag_node) {
    x = end_target;
    v = (x - x_old) * (1.f / s.dt);
  } else {
    if (s.has_ground) ground_constraint(x, v, s.ground);
    for (int q = 0; q < s.sphere_count; ++q) {
      const float4 sp = s.spheres[q];
      sphere_constraint(x, v, xyz(sp), sp.w);
    }
  }
}

// One-pass update and constraints of node i, written to (xo, vo). x_prev may alias xo
// (Verlet writes the new positions over the previous ones, node by node).
template <Integrator I>
__device__ __forceinline__ void advance_node(const Scene& s, int i, const float4& x4, const float4& v4, const Vec3f& a,
                                             const float4* x_prev, bool has_prev, const Vec3f& end_target, float4* xo,
                                             float4* vo) {
  const Vec3f x = xyz(x4);
  const Vec3f xp = (I == Integrator::verlet && has_prev) ? xyz(x_prev[i]) : Vec3f{};
  Vec3f xn, vn;
  integrate<I>(x, xyz(v4), a, xp, has_prev, s.dt, xn, vn);
  constrain(s, i, x4.w, x, end_target, xn, vn);
  xo[i] = f4(xn, x4.w);
  vo[i] = f4(vn, 0.f);
}

// ---- grid kernels: block (tile.x, tile.y) over (i, j), grid.z over layers k ----

// Register cap of the grid gather kernels: the compiler's choice (about 80) limits an SM to
// 3 blocks of 256 threads; the gather is issue-bound, and more resident warps hide its
// latencies better (measured on the H100: 48 beats 64 and 80).
constexpr int kGatherRegisters = 48;

// Halo of the shared tile: flexion springs reach two nodes.
constexpr int kHalo = 2;

// Loads the block's nodes and their halo (2 in i and j, and in k on lattices) into shared
// memory, coalesced along i. Cells outside the grid are left unset and never read.
template <bool Volume, bool Damped>
__device__ __forceinline__ Window load_tile(const Scene& s, const float4* __restrict__ x, const float4* __restrict__ v,
                                            float4* sh) {
  const int tw = blockDim.x + 2 * kHalo, th = blockDim.y + 2 * kHalo, hz = Volume ? kHalo : 0;
  const int cells = tw * th * (2 * hz + 1);
  const int i0 = blockIdx.x * blockDim.x - kHalo, j0 = blockIdx.y * blockDim.y - kHalo, k0 = blockIdx.z - hz;
  for (int l = threadIdx.y * blockDim.x + threadIdx.x; l < cells; l += blockDim.x * blockDim.y) {
    const int a = i0 + l % tw, b = j0 + (l / tw) % th, c = k0 + l / (tw * th);
    if (a < 0 || a >= s.nx || b < 0 || b >= s.ny || c < 0 || c >= s.nz) continue;
    const std::int64_t g = (std::int64_t(c) * s.ny + b) * s.nx + a;
    sh[l] = x[g];
    if (Damped) sh[cells + l] = v[g];
  }
  __syncthreads();
  const int base = (hz * th + threadIdx.y + kHalo) * tw + threadIdx.x + kHalo;
  return {sh, Damped ? sh + cells : nullptr, base, tw, tw * th};
}

// Force pass on a grid: acc = a(x, v). Tiled: neighbours from a shared tile.
template <int N, bool Damped, bool Canonical, bool Tiled>
__global__ void __maxnreg__(kGatherRegisters) force_grid(Scene s, Stencil st, const float4* __restrict__ x, const float4* __restrict__ v,
                           float4* __restrict__ acc, Vec3f drag_target) {
  extern __shared__ float4 sh[];
  const int i = blockIdx.x * blockDim.x + threadIdx.x, j = blockIdx.y * blockDim.y + threadIdx.y, k = blockIdx.z;
  Window w{x, v, 0, s.nx, s.nx * s.ny};
  if constexpr (Tiled) w = load_tile<(N > 12), Damped>(s, x, v, sh);
  if (i >= s.nx || j >= s.ny) return;
  const int node = (k * s.ny + j) * s.nx + i;
  if constexpr (!Tiled) w.base = node;
  const float4 x4 = x[node], v4 = v[node];
  Vec3f a{};
  if (!fixed(s, node, x4.w)) {
    const Vec3f xi = xyz(x4), vi = xyz(v4);
    a = node_accel(s, node, x4.w, xi, vi, gather_grid<N, Damped, Canonical>(s, st, i, j, k, xi, vi, w), drag_target);
  }
  acc[node] = f4(a, 0.f);
}

// Force, update and constraints in one kernel (one-force-pass integrators): reads (x, v)
// and x_prev (Verlet), writes (xo, vo). x_prev may alias xo.
template <int N, bool Damped, bool Canonical, Integrator I>
__global__ void __maxnreg__(kGatherRegisters) fused_grid(Scene s, Stencil st, const float4* __restrict__ x, const float4* __restrict__ v,
                           const float4* x_prev, bool has_prev, float4* xo, float4* __restrict__ vo, Targets tg) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x, j = blockIdx.y * blockDim.y + threadIdx.y, k = blockIdx.z;
  if (i >= s.nx || j >= s.ny) return;
  const int node = (k * s.ny + j) * s.nx + i;
  const float4 x4 = x[node], v4 = v[node];
  Vec3f a{};
  if (!fixed(s, node, x4.w)) {
    const Vec3f xi = xyz(x4), vi = xyz(v4);
    const Window w{x, v, node, s.nx, s.nx * s.ny};
    a = node_accel(s, node, x4.w, xi, vi, gather_grid<N, Damped, Canonical>(s, st, i, j, k, xi, vi, w), tg.force);
  }
  advance_node<I>(s, node, x4, v4, a, x_prev, has_prev, tg.end, xo, vo);
}

// ---- general models: one thread per node over the CSR adjacency ----

// Node i's acceleration; pinned and hard-dragged nodes skip the gather.
__device__ __forceinline__ Vec3f csr_accel(const Scene& s, const int* __restrict__ offset,
                                           const Link* __restrict__ links, const float4* __restrict__ x,
                                           const float4* __restrict__ v, int i, const float4& x4, const float4& v4,
                                           const Vec3f& drag_target) {
  if (fixed(s, i, x4.w)) return {};
  const Vec3f xi = xyz(x4), vi = xyz(v4);
  return node_accel(s, i, x4.w, xi, vi, gather_csr(s, offset, links, x, v, i, xi, vi), drag_target);
}

__global__ void force_csr(Scene s, const int* __restrict__ offset, const Link* __restrict__ links,
                          const float4* __restrict__ x, const float4* __restrict__ v, float4* __restrict__ acc,
                          Vec3f drag_target) {
  const std::int64_t t = thread_index();
  if (t >= s.n) return;
  const int i = int(t);
  acc[i] = f4(csr_accel(s, offset, links, x, v, i, x[i], v[i], drag_target), 0.f);
}

template <Integrator I>
__global__ void fused_csr(Scene s, const int* __restrict__ offset, const Link* __restrict__ links,
                          const float4* __restrict__ x, const float4* __restrict__ v, const float4* x_prev,
                          bool has_prev, float4* xo, float4* __restrict__ vo, Targets tg) {
  const std::int64_t t = thread_index();
  if (t >= s.n) return;
  const int i = int(t);
  const float4 x4 = x[i], v4 = v[i];
  const Vec3f a = csr_accel(s, offset, links, x, v, i, x4, v4, tg.force);
  advance_node<I>(s, i, x4, v4, a, x_prev, has_prev, tg.end, xo, vo);
}

// ---- scatter: one thread per spring, atomics; then per node force sum -> acceleration ----

__global__ void scatter_springs(const Scene s, const Spring* __restrict__ springs, std::int64_t count,
                                const float4* __restrict__ x, const float4* __restrict__ v, float4* force) {
  const std::int64_t t = thread_index();
  if (t >= count) return;
  const Spring sp = springs[t];
  const Vec3f f = spring_force(xyz(x[sp.i]), xyz(x[sp.j]), xyz(v[sp.i]), xyz(v[sp.j]), pick(s.k, sp.kind),
                               pick(s.kd, sp.kind), sp.rest);
  atomicAdd(&force[sp.i].x, f.x);
  atomicAdd(&force[sp.i].y, f.y);
  atomicAdd(&force[sp.i].z, f.z);
  atomicAdd(&force[sp.j].x, -f.x);
  atomicAdd(&force[sp.j].y, -f.y);
  atomicAdd(&force[sp.j].z, -f.z);
}

__global__ void scatter_finish(Scene s, const float4* __restrict__ x, const float4* __restrict__ v, float4* acc,
                               Vec3f drag_target) {
  const std::int64_t t = thread_index();
  if (t >= s.n) return;
  const int i = int(t);
  const float4 x4 = x[i];
  acc[i] = f4(node_accel(s, i, x4.w, xyz(x4), xyz(v[i]), xyz(acc[i]), drag_target), 0.f);
}

// ---- updates ----

// One-pass update from an acceleration slot (the non-fused variants).
template <Integrator I>
__global__ void update(Scene s, const float4* __restrict__ x, const float4* __restrict__ v,
                       const float4* __restrict__ acc, const float4* x_prev, bool has_prev, float4* xo,
                       float4* __restrict__ vo, Vec3f end_target) {
  const std::int64_t t = thread_index();
  if (t >= s.n) return;
  const int i = int(t);
  advance_node<I>(s, i, x[i], v[i], xyz(acc[i]), x_prev, has_prev, end_target, xo, vo);
}

// Stage state: dst = s0 + h (v of src, acc of src).
__global__ void stage(int n, float h, const float4* __restrict__ x0, const float4* __restrict__ v0,
                      const float4* __restrict__ v_src, const float4* __restrict__ acc, float4* __restrict__ x_dst,
                      float4* __restrict__ v_dst) {
  const std::int64_t t = thread_index();
  if (t >= n) return;
  const float4 x4 = x0[t];
  x_dst[t] = f4(xyz(x4) + xyz(v_src[t]) * h, x4.w);
  v_dst[t] = f4(xyz(v0[t]) + xyz(acc[t]) * h, 0.f);
}

// Final combination of the stages (the terms with a non-zero weight, in stage order).
struct Terms {
  const float4* v[4];
  const float4* a[4];
  float weight[4];
  int count;
};

__global__ void combine(Scene s, const float4* __restrict__ x, const float4* __restrict__ v, Terms terms,
                        float4* __restrict__ xo, float4* __restrict__ vo, Vec3f end_target) {
  const std::int64_t t = thread_index();
  if (t >= s.n) return;
  const int i = int(t);
  Vec3f dx{}, dv{};
#pragma unroll
  for (int q = 0; q < 4; ++q) {
    if (q >= terms.count) break;
    dx += xyz(terms.v[q][i]) * terms.weight[q];
    dv += xyz(terms.a[q][i]) * terms.weight[q];
  }
  const float4 x4 = x[i];
  const Vec3f x_old = xyz(x4);
  Vec3f xn = x_old + dx * s.dt, vn = xyz(v[i]) + dv * s.dt;
  constrain(s, i, x4.w, x_old, end_target, xn, vn);
  xo[i] = f4(xn, x4.w);
  vo[i] = f4(vn, 0.f);
}

}  // namespace deformlab::cuda::dev
