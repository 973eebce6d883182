// The model and scene on the device and the force pass of the CUDA gather and scatter variants
// (ForceKernels), shared by the CUDA pipeline and the hybrids' CUDA force stage. Part of
// cuda_pipeline.cu's translation unit: compiled once per math mode, into DL_CUDA_MATH.
#pragma once
#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "check.cuh"
#include "core/partition.hpp"
#include "core/step_params.hpp"
#include "cuda_pipeline.hpp"
#include "kernels.cuh"

namespace deformlab::cuda::DL_CUDA_MATH {

using dev::Link;
using dev::P;
using dev::Spring;
using dev::Stencil;
using dev::Targets;

constexpr int kBlock = 256;  // threads per block of the one-dimensional kernels

inline unsigned blocks_for(std::int64_t n) { return unsigned((n + kBlock - 1) / kBlock); }

// Throws std::invalid_argument when the tile is not a block shape or the grid exceeds the
// launch limits with it.
inline void check_tile(const Model& m, const Tile& t) {
  if (t.x < 1 || t.y < 1 || t.x * t.y > 1024)
    throw std::invalid_argument("CUDA tile " + to_string(t) +
                                " is not a valid block shape (1..1024 threads)");
  if (m.topology == Topology::general) return;
  if ((m.ny + t.y - 1) / t.y > 65535 || m.nz > 65535)
    throw std::invalid_argument("grid of " + std::to_string(m.ny) + " rows / " + std::to_string(m.nz) +
                                " layers exceeds the CUDA launch limits for tile height " + std::to_string(t.y));
}

// The model and scene on the device as the kernels see them (scene, stencil or adjacency,
// springs, spheres) and the force pass of the gather and scatter variants: the base of the
// CUDA pipeline and, on its own, the force stage of the hybrid pipelines.
class ForceKernels {
 public:
  ForceKernels(const Model& m, const Params& p, const Options& o)
      : model_(m), o_(o), sp_(step_params<float>(m, p)) {
    if (m.grid()) {
      const auto entries = stencil_entries<float>(m);
      std::copy(entries.begin(), entries.end(), stencil_.e);
    } else if (o_.variant == Variant::tiled) {
      upload_tiling();
    } else if (o_.variant != Variant::scatter) {
      upload(offset_, m.adj_offset, "uploading the adjacency offsets");
      upload(links_, links_of(m.adj_node, m.adj_spring), "uploading the adjacency");
    }
    if (o_.variant == Variant::scatter && !m.grid()) upload_springs();
  }

  // acc = a(x, v) for every node, queued on `stream`.
  void launch_forces(const float4* x, const float4* v, float4* acc, Vec3f target, cudaStream_t stream) const {
    if (o_.variant == Variant::scatter) {
      check(cudaMemsetAsync(acc, 0, std::size_t(sp_.node_count) * sizeof(float4), stream), "clearing the force sums");
      const std::int64_t s = std::int64_t(springs_.size());
      if (model_.grid()) {
        with_grid_flags([&](auto n, auto) {
          const std::int64_t threads = std::int64_t(sp_.node_count) * (n() / 2);
          dev::scatter_grid<n()><<<blocks_for(threads), kBlock, 0, stream>>>(sp_, stencil_, x, v, acc);
        });
        check_launch("launching the grid scatter kernel");
      } else if (s > 0) {
        dev::scatter_springs<<<blocks_for(s), kBlock, 0, stream>>>(springs_.get(), s, x, v, acc);
        check_launch("launching the scatter kernel");
      }
      dev::scatter_finish<<<blocks_for(sp_.node_count), kBlock, 0, stream>>>(sp_, x, v, acc, target);
      check_launch("launching the scatter finishing kernel");
      return;
    }
    if (!model_.grid() && o_.variant == Variant::tiled) {
      const dev::TiledCsr t{tile_offset_.get(), tile_node_.get(), members_.get(), offset_.get(), links_.get()};
      if (damped_) dev::force_tiled_csr<true><<<tiles_, tile_threads_, tile_shared_, stream>>>(sp_, t, x, v, acc, target);
      else dev::force_tiled_csr<false><<<tiles_, tile_threads_, tile_shared_, stream>>>(sp_, t, x, v, acc, target);
      check_launch("launching the tiled mesh force kernel");
      return;
    }
    if (!model_.grid()) {
      const auto kernel = damped_ ? dev::force_csr<true> : dev::force_csr<false>;
      kernel<<<blocks_for(sp_.node_count), kBlock, 0, stream>>>(sp_, offset_.get(), links_.get(), x, v, acc, target);
      check_launch("launching the CSR gather force kernel");
      return;
    }
    const bool tiled = o_.variant == Variant::tiled;
    with_grid_flags([&](auto n, auto damped) {
      if (tiled) launch_force_grid<n(), damped(), true>(x, v, acc, target, stream);
      else launch_force_grid<n(), damped(), false>(x, v, acc, target, stream);
    });
  }

 protected:
  // Synchronous: done before any work is queued (or, for the springs, before they are read).
  template <class T>
  void upload(Buffer<T>& b, const std::vector<T>& h, const char* what) {
    b.allocate(h.size(), what);
    if (!h.empty()) check(cudaMemcpy(b.get(), h.data(), h.size() * sizeof(T), cudaMemcpyHostToDevice), what);
  }
  // One link per CSR entry: `node` (another node, or a cell of a tile) and spring's constants.
  std::vector<Link> links_of(const std::vector<std::int32_t>& node, const std::vector<std::int32_t>& spring) const {
    std::vector<Link> links(node.size());
    for (std::size_t e = 0; e < links.size(); ++e)
      links[e] = {node[e], model_.rest_length[spring[e]], model_.spring_k(spring[e]), model_.spring_kd(spring[e])};
    return links;
  }
  // cuda-tiled on a general model: one thread block per tile of tile.x * tile.y nodes
  // (core/partition.hpp), the tile's positions (and velocities) in shared memory.
  void upload_tiling() {
    const Tiling t = tile_model(model_, o_.tile.x * o_.tile.y);
    const std::vector<Link> links = links_of(t.link_cell, t.link_spring);
    tiles_ = unsigned(t.blocks());
    tile_threads_ = unsigned(o_.tile.x * o_.tile.y);
    tile_shared_ = std::size_t(t.largest_tile()) * sizeof(float4) * (damped_ ? 2 : 1);
    int device = 0, limit = 0;
    check(cudaGetDevice(&device), "finding the device");
    check(cudaDeviceGetAttribute(&limit, cudaDevAttrMaxSharedMemoryPerBlockOptin, device), "reading the shared-memory limit");
    if (tile_shared_ > std::size_t(limit))
      throw std::invalid_argument("cuda-tiled: the largest tile of " + std::to_string(t.largest_tile()) + " nodes needs " +
                                  std::to_string(tile_shared_) + " bytes of shared memory; this device allows " +
                                  std::to_string(limit) + " (choose a smaller tile)");
    for (const auto kernel : {dev::force_tiled_csr<true>, dev::force_tiled_csr<false>})
      check(cudaFuncSetAttribute(kernel, cudaFuncAttributeMaxDynamicSharedMemorySize, int(tile_shared_)),
            "raising the tiled kernel's shared-memory limit");
    upload(tile_offset_, t.tile_offset, "uploading the tiles");
    upload(tile_node_, t.tile_node, "uploading the tiles' nodes");
    upload(members_, t.members, "uploading the tiles' member counts");
    upload(offset_, t.link_offset, "uploading the tiles' adjacency offsets");
    upload(links_, links, "uploading the tiles' adjacency");
  }
  void upload_springs() {
    const Model& m = model_;  // general models (grids have no spring list)
    std::vector<Spring> sp(m.spring_count());
    for (std::size_t e = 0; e < sp.size(); ++e)
      sp[e] = {m.spring_i[e], m.spring_j[e], m.rest_length[e], m.spring_k(int(e)), m.spring_kd(int(e))};
    require_device_memory(std::int64_t(sp.size() * sizeof(Spring)), "the spring list");
    upload(springs_, sp, "uploading the spring list");
  }
  dim3 grid_blocks() const {
    return dim3(unsigned((sp_.nx + o_.tile.x - 1) / o_.tile.x), unsigned((sp_.ny + o_.tile.y - 1) / o_.tile.y),
                unsigned(sp_.nz));
  }
  dim3 grid_threads() const { return dim3(unsigned(o_.tile.x), unsigned(o_.tile.y), 1); }

  // Calls f(N, Damped) with the grid kernels' compile-time flags for this model.
  template <class F>
  void with_grid_flags(F&& f) const {
    using std::bool_constant;
    using std::integral_constant;
    auto damp = [&](auto n) {
      if (damped_) f(n, bool_constant<true>{});
      else f(n, bool_constant<false>{});
    };
    if (model_.volume()) damp(integral_constant<int, kLatticeStencil>{});
    else damp(integral_constant<int, kClothStencil>{});
  }

  template <int N, bool Damped, bool Tiled>
  void launch_force_grid(const float4* x, const float4* v, float4* acc, Vec3f target, cudaStream_t stream) const {
    const auto kernel = dev::force_grid<N, Damped, Tiled>;
    std::size_t shared = 0;
    if (Tiled) {
      const std::size_t cells = std::size_t(o_.tile.x + 2 * dev::kHalo) * (o_.tile.y + 2 * dev::kHalo) *
                                (N == kLatticeStencil ? 2 * dev::kHalo + 1 : 1);
      shared = cells * sizeof(float4) * (Damped ? 2 : 1);
      if (shared > 48 * 1024)
        check(cudaFuncSetAttribute(kernel, cudaFuncAttributeMaxDynamicSharedMemorySize, int(shared)),
              "raising the tiled kernel's shared-memory limit");
    }
    kernel<<<grid_blocks(), grid_threads(), shared, stream>>>(sp_, stencil_, x, v, acc, target);
    check_launch(Tiled ? "launching the tiled force kernel" : "launching the gather force kernel");
  }

  const Model& model_;
  Options o_;
  const bool damped_ = model_.damped();
  dev::StepParams sp_;
  Stencil stencil_{};
  Buffer<int> offset_;  // CSR offsets: per node, or per tile cell (cuda-tiled)
  Buffer<Link> links_;
  Buffer<int> tile_offset_, tile_node_, members_;  // cuda-tiled on general models
  unsigned tiles_ = 0, tile_threads_ = 0;
  std::size_t tile_shared_ = 0;
  Buffer<Spring> springs_;
};

}  // namespace deformlab::cuda::DL_CUDA_MATH
