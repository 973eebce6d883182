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

// What the per-step benches (cpu, gl) take: sizes, warm-up and timed steps, integrator, CSV.
struct StepOptions {
  std::vector<int> sizes;
  int warmup = 5, reps = 30;
  std::string integrator = "semi-implicit-euler";
  std::string csv;  // also write the rows here when set
};
// Adds `name` with StepOptions' flags (defaults from `defaults`); `run` runs it.
void add_step_bench(CLI::App& app, const char* name, const char* description, const StepOptions& defaults,
                    void (*run)(const StepOptions&));

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
