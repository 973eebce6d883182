// deformlab-bench: benchmarks, apart from the tests. Each backend adds a subcommand.
#pragma once
#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace deformlab::bench {

// Median and spread of a list of timings (ms).
struct Stats {
  double median = 0, min = 0, p90 = 0;
};
Stats stats(std::vector<double> ms);

void add_cpu_bench(CLI::App& app);
#if DEFORMLAB_HAVE_CUDA
void add_cuda_bench(CLI::App& app);
#endif
#if DEFORMLAB_HAVE_GL
void add_gl_bench(CLI::App& app);
#endif
#if DEFORMLAB_HAVE_INTEROP
void add_hybrid_bench(CLI::App& app);
#endif

}  // namespace deformlab::bench
