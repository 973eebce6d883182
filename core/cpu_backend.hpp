// The CPU backend: every integrator's schedule run pass by pass over host arrays.
// `cpu` is single-threaded (the paper's "unoptimised"), `omp` splits every pass over
// nodes with OpenMP (its "optimised"); both do the same float arithmetic in the same
// order per node, so their states are bitwise equal. The double instantiation is the
// reference that tests and `--compare` measure the other pipelines against.
#pragma once
#include <memory>

#include "pipeline.hpp"

namespace deformlab {

enum class Precision { f32, f64 };

// The OpenMP pipelines' threads: at least this many nodes each, so that small models do not
// pay for more barriers than they have work (a thread more changes no result).
inline constexpr int kNodesPerThread = 1024;

std::unique_ptr<Pipeline> make_cpu_pipeline(const PipelineSetup& s, Precision p, bool parallel);

// Adds `cpu`, `omp` and `reference` (double, OpenMP) to the registry.
void add_cpu_pipelines(PipelineRegistry& r);

}  // namespace deformlab
