// cuda-fused's cloth step with each block's nodes and their halo copied into shared memory by
// the tensor memory accelerator (TMA, compute capability 9.0 and up): one cp.async.bulk.tensor
// a state array and block, issued by one thread, instead of a load a neighbour and thread. It
// runs on 32 x 8 blocks, by default in exact math, where it measured 2.0-5.9% faster than
// dev::fused_grid on the 16 x 8 blocks exact math ran before; in fast math it was 24-30% slower
// than fused_grid (H200, paper scene; docs/speed.md), so fast math takes it only when the
// pipeline option tma=on asks. Same arithmetic in the same order as fused_grid: the same bits.
#pragma once
#include <cuda.h>
#include <cudaTypedefs.h>

#include <stdexcept>
#include <string>

#include "cuda_pipeline.hpp"
#include "kernels.cuh"

namespace deformlab::cuda::DL_CUDA_MATH::dev {

constexpr int kTmaW = 32, kTmaH = 8;  // the block's nodes
// Whether cuda-fused can run it (on a device of compute capability 9.0 or more): builds whose
// every architecture has the accelerator (cuda_kernels/CMakeLists.txt).
#ifdef DL_CUDA_TMA
constexpr bool kTmaBuilt = true;
#else
constexpr bool kTmaBuilt = false;
#endif
constexpr int kTmaBoxW = kTmaW + 2 * kHalo, kTmaBoxH = kTmaH + 2 * kHalo;

__device__ __forceinline__ unsigned shared_address(const void* p) { return unsigned(__cvta_generic_to_shared(p)); }

// The box of `map` whose first node is (i0, j0) into `to`, completing on barrier `bar`. Nodes
// outside the array arrive as zeros (never read: the gather checks its neighbours near borders).
__device__ __forceinline__ void copy_box(const CUtensorMap& map, void* to, int i0, int j0, unsigned bar) {
#if __CUDA_ARCH__ >= 900
  asm volatile(
      "cp.async.bulk.tensor.3d.shared::cluster.global.tile.mbarrier::complete_tx::bytes [%0], [%1, {%2, %3, %4}], "
      "[%5];" ::"r"(shared_address(to)), "l"(&map), "r"(0), "r"(i0), "r"(j0), "r"(bar)
      : "memory");
#endif
}

// Reads x through the tensor map tx, v through tv where springs are damped (else from v),
// writes (xo, vo): fused_grid on a cloth, its neighbours from the block's box in shared memory.
template <bool Damped, int Rule>
__global__ void __maxnreg__(kGatherRegisters)
    fused_cloth_tma(StepParams s, Stencil st, float weight, const __grid_constant__ CUtensorMap tx,
                    const __grid_constant__ CUtensorMap tv, const float4* __restrict__ v, bool half_step,
                    float4* xo, float4* __restrict__ vo, Targets tg, StopCheck check) {
#if __CUDA_ARCH__ >= 900
  __shared__ __align__(128) float4 box[2][kTmaBoxH * kTmaBoxW];
  __shared__ __align__(8) unsigned long long arrived;
  const unsigned bar = shared_address(&arrived);
  if (threadIdx.x == 0 && threadIdx.y == 0) {
    const unsigned bytes = (Damped ? 2 : 1) * sizeof(box[0]);
    asm volatile("mbarrier.init.shared::cta.b64 [%0], 1;" ::"r"(bar));
    asm volatile("fence.proxy.async.shared::cta;");
    asm volatile("mbarrier.arrive.expect_tx.shared::cta.b64 _, [%0], %1;" ::"r"(bar), "r"(bytes));
    const int i0 = blockIdx.x * kTmaW - kHalo, j0 = blockIdx.y * kTmaH - kHalo;
    copy_box(tx, box[0], i0, j0, bar);
    if (Damped) copy_box(tv, box[1], i0, j0, bar);
  }
  __syncthreads();  // the barrier is initialised
  for (unsigned done = 0; !done;)
    asm volatile("{ .reg .pred p; mbarrier.try_wait.parity.shared::cta.b64 p, [%1], 0; selp.u32 %0, 1, 0, p; }"
                 : "=r"(done)
                 : "r"(bar)
                 : "memory");
  const int i = blockIdx.x * kTmaW + threadIdx.x, j = blockIdx.y * kTmaH + threadIdx.y;
  float d = 0.f;
  if (i < s.nx && j < s.ny) {
    const int node = P::grid_node(i, j, 0, s.nx, s.ny), at = (threadIdx.y + kHalo) * kTmaBoxW + threadIdx.x + kHalo;
    const float4 x4 = box[0][at], v4 = Damped ? box[1][at] : v[node];
    const Vec3f a = grid_accel<kClothStencil, Damped>(s, st, i, j, 0, node, x4, v4, {box[0], box[1], at, kTmaBoxW, 0},
                                                      tg.force);
    d = advance_node<Rule>(s, weight, node, x4, v4, a, half_step, tg.end, xo, vo);
  }
  store_displacement(check, d);
#endif
}

}  // namespace deformlab::cuda::DL_CUDA_MATH::dev

namespace deformlab::cuda::DL_CUDA_MATH {

// Why dev::fused_cloth_tma cannot take the steps of `integrator` on model m with options o (o.tile
// set), whatever the device; empty where it can, on a device of compute capability 9.0 or more.
inline std::string tma_misfit(const Options& o, const Model& m, Integrator integrator) {
  if (!dev::kTmaBuilt) return "this build includes CUDA architectures below 90";
  if (o.variant != Variant::fused || !make_schedule(integrator).single_pass())
    return "it takes cuda-fused's one-kernel steps (explicit-euler, semi-implicit-euler, verlet)";
  if (m.topology != Topology::cloth_grid) return "it runs grid cloths";
  if (o.tile.x != dev::kTmaW || o.tile.y != dev::kTmaH) return "it runs blocks of 32x8 nodes";
  return {};
}

// A tensor map over a cloth's nx x ny float4 array (dimensions: the 4 floats, i, j) in boxes
// of the block and its halo, for dev::fused_cloth_tma. The driver's encoder is reached through
// the runtime, so that nothing links the driver library.
inline CUtensorMap cloth_tensor_map(const float4* a, int nx, int ny) {
  static const auto encode = [] {
    void* f = nullptr;
    cudaDriverEntryPointQueryResult found{};
    if (cudaGetDriverEntryPointByVersion("cuTensorMapEncodeTiled", &f, 12000, cudaEnableDefault, &found) !=
            cudaSuccess ||
        found != cudaDriverEntryPointSuccess)
      throw std::runtime_error("the CUDA driver has no cuTensorMapEncodeTiled");
    return reinterpret_cast<PFN_cuTensorMapEncodeTiled_v12000>(f);
  }();
  CUtensorMap m{};
  const cuuint64_t size[3] = {4, cuuint64_t(nx), cuuint64_t(ny)};
  const cuuint64_t stride[2] = {sizeof(float4), cuuint64_t(nx) * sizeof(float4)};
  const cuuint32_t box[3] = {4, dev::kTmaBoxW, dev::kTmaBoxH}, step[3] = {1, 1, 1};
  if (encode(&m, CU_TENSOR_MAP_DATA_TYPE_FLOAT32, 3, const_cast<float4*>(a), size, stride, box, step,
             CU_TENSOR_MAP_INTERLEAVE_NONE, CU_TENSOR_MAP_SWIZZLE_NONE, CU_TENSOR_MAP_L2_PROMOTION_L2_256B,
             CU_TENSOR_MAP_FLOAT_OOB_FILL_NONE) != CUDA_SUCCESS)
    throw std::runtime_error("encoding a tensor map over " + std::to_string(nx) + " x " + std::to_string(ny) +
                             " nodes");
  return m;
}

}  // namespace deformlab::cuda::DL_CUDA_MATH
