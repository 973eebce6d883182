// `deformlab-bench cpu`: the paper's Table 1 sizes, cpu vs omp, ms per step.
#include <iomanip>
#include <iostream>

#include "bench.hpp"
#include "core/cpu_backend.hpp"
#include "experiments/pipelines.hpp"

namespace deformlab::bench {

namespace {

void run_cpu(const StepOptions& o) {
  const Integrator integ = o.checked({"cpu", "omp"});
  const SceneKind kind = o.scene_kind();
  CsvFile csv = open_csv(o.csv, "grid,nodes,pipeline,median_ms,min_ms,p90_ms", kRunColumns);
  std::cout << title("cpu") << " ms per step (" << o.integrator << "), cloth grid, 12 springs per interior node\n"
            << describe(kind) << "\n"
            << "method: host steady_clock around each step, " << counted(o.warmup, "warm-up step") << ", median of "
            << o.reps << " timed steps; omp: " << pipelines().find("omp")->summary << "\n\n"
            << std::setw(8) << "grid" << std::setw(12) << "cpu ms" << std::setw(12) << "omp ms" << std::setw(10)
            << "speed-up" << std::setw(16) << "omp Mnodes/s" << "\n";
  for (int n : o.sizes) {
    const BenchScene scene(n, kind);
    const Model& m = scene.model;
    Stats st[2];
    for (int k = 0; k < 2; ++k) {
      auto pipe = make_cpu_pipeline(scene.setup(integ), Precision::f32, k == 1);
      const auto timer = pipe->step_timer();
      timed_steps(*pipe, *timer, o.warmup);
      st[k] = stats(timed_steps(*pipe, *timer, o.reps));
      if (csv) csv << n << "x" << n << "," << m.node_count() << "," << (k ? "omp" : "cpu") << "," << st[k].median
                   << "," << st[k].min << "," << st[k].p90 << run_columns(o) << "\n";
    }
    std::cout << std::setw(8) << (std::to_string(n) + "^2") << std::fixed << std::setprecision(3) << std::setw(12)
              << st[0].median << std::setw(12) << st[1].median << std::setw(10) << std::setprecision(2)
              << st[0].median / st[1].median << std::setw(16) << m.node_count() / (st[1].median * 1e3) << "\n";
  }
}

}  // namespace

void add_cpu_bench(CLI::App& app) {
  add_step_bench(app, "cpu",
                 "cpu vs omp ms/step at 64^2 to 512^2 (the paper's Table 1 sizes; the paper ran explicit Euler: "
                 "--integrator explicit-euler)",
                 {64, 128, 256, 512},
                 5, 30, "Timed steps", run_cpu, Device::cpu);
}

}  // namespace deformlab::bench
