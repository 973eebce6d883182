// The energies of a CUDA pipeline's state (physics checks), reduced on the device in double
// precision: kinetic and field energy a node, spring energy a spring (on grids, each node's own
// half of the stencil).
#pragma once
#include <thrust/execution_policy.h>
#include <thrust/functional.h>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/transform_reduce.h>

#include "check.cuh"
#include "core/energy.hpp"
#include "core/model.hpp"
#include "kernels.cuh"

namespace deformlab::cuda::DL_CUDA_MATH {

using PD = Physics<double>;
inline __host__ __device__ Vec3d widen(const Vec3f& a) { return {a.x, a.y, a.z}; }

struct NodeEnergy {
  double kinetic, field;
};
struct NodeEnergyOp {
  const float4* x;
  const float4* v;
  PD::StepParams sp;
  __device__ NodeEnergy operator()(int i) const {
    const float4 x4 = x[i];
    return {PD::kinetic_energy(x4.w, widen(dev::xyz(v[i]))), PD::field_energy(sp, x4.w, widen(dev::xyz(x4)))};
  }
};
struct AddNodeEnergy {
  __device__ NodeEnergy operator()(const NodeEnergy& a, const NodeEnergy& b) const {
    return {a.kinetic + b.kinetic, a.field + b.field};
  }
};
struct SpringEnergyOp {
  const dev::Spring* springs;
  const float4* x;
  __device__ double operator()(std::int64_t e) const {
    const dev::Spring s = springs[e];
    return PD::spring_energy(widen(dev::xyz(x[s.i])), widen(dev::xyz(x[s.j])), s.k, s.rest);
  }
};
// Grids: node u's own springs (the second half of its stencil).
struct GridSpringEnergyOp {
  dev::StepParams sp;
  dev::Stencil st;
  const float4* x;
  __device__ double operator()(int u) const {
    const int i = u % sp.nx, j = (u / sp.nx) % sp.ny, k = u / (sp.nx * sp.ny), n = sp.stencil_count;
    double e = 0.0;
    for (int q = n / 2; q < n; ++q) {
      const dev::P::StencilEntry& o = st.e[q];
      const int w = dev::P::grid_neighbour(sp, i, j, k, o.di, o.dj, o.dk);
      if (w >= 0) e += PD::spring_energy(widen(dev::xyz(x[u])), widen(dev::xyz(x[w])), o.k, o.rest);
    }
    return e;
  }
};

// The energies of state (x, v) of model m (springs: its spring list on the device, for a model
// that is not a grid), reduced on `stream`, which it waits for.
inline Energy model_energy(cudaStream_t stream, const Model& m, const PD::StepParams& spd, const dev::StepParams& sp,
                           const dev::Stencil& stencil, const dev::Spring* springs, const float4* x, const float4* v) {
  const int n = m.node_count();
  const auto policy = thrust::cuda::par.on(stream);
  const NodeEnergy ne =
      thrust::transform_reduce(policy, thrust::counting_iterator<int>(0), thrust::counting_iterator<int>(n),
                               NodeEnergyOp{x, v, spd}, NodeEnergy{0.0, 0.0}, AddNodeEnergy{});
  const double se =
      m.grid() ? thrust::transform_reduce(policy, thrust::counting_iterator<int>(0), thrust::counting_iterator<int>(n),
                                          GridSpringEnergyOp{sp, stencil, x}, 0.0, thrust::plus<double>())
      : m.spring_count() == 0
          ? 0.0
          : thrust::transform_reduce(policy, thrust::counting_iterator<std::int64_t>(0),
                                     thrust::counting_iterator<std::int64_t>(m.spring_count()),
                                     SpringEnergyOp{springs, x}, 0.0, thrust::plus<double>());
  check(cudaStreamSynchronize(stream), "reducing the energies");
  Energy e;
  e.kinetic = ne.kinetic;
  e.field = ne.field;
  e.spring = se;
  return e;
}

}  // namespace deformlab::cuda::DL_CUDA_MATH
