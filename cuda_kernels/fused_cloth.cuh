// cuda-fused on cloths: each spring evaluated once. The gather evaluates every spring twice,
// once from each end; here a block evaluates the own springs (the stencil's second half) of
// its tile's nodes, and those of halo nodes reaching into the tile, into shared memory, and
// each node sums its twelve terms in the stencil's order, an incoming one as the negated force
// of its owner. That is the gather's sum bit for bit: spring_force(xj, xi, vj, vi) is
// exactly -spring_force(xi, xj, vi, vj), as negating d, u and the velocity difference rounds
// nothing. (Lattices, with 16 own springs a node, keep fused_grid.)
#pragma once
#include "kernels.cuh"

namespace deformlab::cuda::DL_CUDA_MATH::dev {

constexpr int kOwnSprings = kClothStencil / 2;  // stencil entries 6..11

// Own entry e (0..5, stencil entry 6 + e) of the owner of incoming stencil entry q (0..5):
// the entry whose offset is q's negated.
__device__ __forceinline__ constexpr int owner_entry(int q) {
  constexpr int own[kOwnSprings] = {5, 3, 2, 1, 4, 0};
  return own[q];
}

// Force cells: (tile.x + 3) x (tile.y + 2) from (-2, -2) in tile coordinates, one per node
// whose own springs a node of the tile can have (the halo's reach into the tile: two nodes
// before it in i and j, one after it in i).
struct ForceCells {
  float4* f;  // kOwnSprings arrays of `count`
  int width, count;
  __device__ __forceinline__ float4& at(int e, int a, int b) const { return f[e * count + (b + 2) * width + a + 2]; }
};

// The halo's springs into a tile, as a list made once on the host (halo_springs in
// cuda_pipeline.cu): own entry e of halo cell (a, b) packed as e | (a + 2) << 3 | (b + 2) << 15.
struct HaloSprings {
  const int* __restrict__ packed;
  int count;
};

template <bool Damped, int Rule>
__global__ void __maxnreg__(kGatherRegisters) fused_cloth(StepParams s, Stencil st, float weight,
                                                          HaloSprings halo, const float4* __restrict__ x,
                                                          const float4* __restrict__ v,
                                                          const float4* x_prev, bool has_prev, float4* xo,
                                                          float4* __restrict__ vo, Targets tg, StopCheck check) {
  extern __shared__ float4 sh[];
  const int tx = blockDim.x, ty = blockDim.y, i0 = blockIdx.x * tx, j0 = blockIdx.y * ty;
  const Window w = load_tile<false, Damped>(s, x, v, sh);  // also: __syncthreads()
  const int cells = (tx + 2 * kHalo) * (ty + 2 * kHalo);
  const ForceCells fc{sh + cells * (Damped ? 2 : 1), tx + 3, (tx + 3) * (ty + 2)};
  auto in_grid = [&](int a, int b) { return i0 + a >= 0 && i0 + a < s.nx && j0 + b >= 0 && j0 + b < s.ny; };
  // Own spring e of tile cell (a, b), at state cell `at`, where both ends lie in the grid.
  auto own_spring = [&](int e, int a, int b, int at, const Vec3f& xi, const Vec3f& vi) {
    const P::StencilEntry& c = st.e[kOwnSprings + e];
    if (!in_grid(a + c.di, b + c.dj)) return;
    const int far = at + c.di + c.dj * w.stride_j;
    const Vec3f vj = Damped ? xyz(w.v[far]) : vi;
    fc.at(e, a, b) = f4(P::spring_force(xi, xyz(w.x[far]), vi, vj, c.k, c.kd, c.rest), 0.f);
  };
  const int a = threadIdx.x, b = threadIdx.y;
  if (in_grid(a, b)) {
    const Vec3f xi = xyz(w.x[w.base]), vi = Damped ? xyz(w.v[w.base]) : Vec3f{};
#pragma unroll
    for (int e = 0; e < kOwnSprings; ++e) own_spring(e, a, b, w.base, xi, vi);
  }
  for (int h = b * tx + a; h < halo.count; h += tx * ty) {
    const int p = halo.packed[h], e = p & 7, ha = ((p >> 3) & 0xfff) - 2, hb = (p >> 15) - 2;
    if (!in_grid(ha, hb)) continue;
    const int at = (hb + kHalo) * w.stride_j + ha + kHalo;
    own_spring(e, ha, hb, at, xyz(w.x[at]), Damped ? xyz(w.v[at]) : Vec3f{});
  }
  __syncthreads();

  float d = 0.f;
  const int i = i0 + a, j = j0 + b;
  if (i < s.nx && j < s.ny) {
    const int node = P::grid_node(i, j, 0, s.nx, s.ny);
    const float4 x4 = w.x[w.base], v4 = Damped ? w.v[w.base] : v[node];
    Vec3f acc{};
    if (!P::node_fixed(s, node, x4.w)) {
      const bool inside = i >= 2 && i < s.nx - 2 && j >= 2 && j < s.ny - 2;
      Vec3f f{};
#pragma unroll
      for (int e = 0; e < kClothStencil; ++e) {
        const GridOffset o = grid_offset(false, e);
        if (!inside && P::grid_neighbour(s, i, j, 0, o.di, o.dj, 0) < 0) continue;
        if (e < kOwnSprings) f -= xyz(fc.at(owner_entry(e), a + o.di, b + o.dj));
        else f += xyz(fc.at(e - kOwnSprings, a, b));
      }
      acc = P::node_acceleration(s, node, x4.w, xyz(x4), xyz(v4), f, tg.force);
    }
    d = advance_node<Rule>(s, weight, node, x4, v4, acc, x_prev, has_prev, tg.end, xo, vo);
  }
  store_displacement(check, d);
}

}  // namespace deformlab::cuda::DL_CUDA_MATH::dev
