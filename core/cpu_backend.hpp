// The CPU backend: every integrator's schedule run pass by pass over host arrays.
// `cpu` is single-threaded (the paper's "unoptimised"), `omp` splits every pass over
// nodes with OpenMP (its "optimised"); both do the same float arithmetic in the same
// order per node, so their states are bitwise equal. The double instantiation is the
// reference that tests and `--compare` measure the other pipelines against.
#pragma once
#include <memory>
#include <vector>

#include "pipeline.hpp"

namespace deformlab {

enum class Precision { f32, f64 };

// The OpenMP pipelines' threads: at least this many nodes each, so that small models do not
// pay for more barriers than they have work (a thread more changes no result).
inline constexpr int kNodesPerThread = 1024;

std::unique_ptr<Pipeline> make_cpu_pipeline(const PipelineSetup& s, Precision p, bool parallel);

// The float CPU pipeline's force pass on its own: the acceleration of every node in state s at
// time t (the drag target read then), in the pipeline's arithmetic and order. The tests of GPU
// update passes feed them where a CUDA force pass would.
std::vector<Vec3f> cpu_accelerations(const PipelineSetup& setup, const State& s, double t);

// Adds `cpu`, `omp` and `reference` (double, OpenMP) to the registry.
void add_cpu_pipelines(PipelineRegistry& r);

}  // namespace deformlab
