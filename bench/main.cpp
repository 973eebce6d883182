#include <algorithm>
#include <memory>
#include <iostream>

#include "bench.hpp"

namespace deformlab::bench {

Stats stats(std::vector<double> ms) {
  if (ms.empty()) return {};
  std::sort(ms.begin(), ms.end());
  return {ms[ms.size() / 2], ms.front(), ms[std::min(ms.size() - 1, ms.size() * 9 / 10)]};
}

void add_step_bench(CLI::App& app, const char* name, const char* description, const StepOptions& defaults,
                    void (*run)(const StepOptions&)) {
  auto o = std::make_shared<StepOptions>(defaults);
  auto* c = app.add_subcommand(name, description);
  c->add_option("--sizes", o->sizes, "Grid sizes (n for n x n)");
  c->add_option("--warmup", o->warmup, "Warm-up steps")->check(CLI::PositiveNumber);
  c->add_option("--reps", o->reps, "Timed steps")->check(CLI::PositiveNumber);
  c->add_option("--integrator", o->integrator, "Integrator");
  c->add_option("--csv", o->csv, "Also write the results to this CSV file");
  c->callback([o, run] { run(*o); });
}

}  // namespace deformlab::bench

int main(int argc, char** argv) {
  CLI::App cli{"deformlab-bench: timings of deformlab's pipelines (not tests)"};
  cli.require_subcommand(1);
  deformlab::bench::add_cpu_bench(cli);
#if DEFORMLAB_HAVE_CUDA
  deformlab::bench::add_cuda_bench(cli);
#endif
#if DEFORMLAB_HAVE_GL
  deformlab::bench::add_gl_bench(cli);
#endif
#if DEFORMLAB_HAVE_INTEROP
  deformlab::bench::add_hybrid_bench(cli);
#endif
  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return cli.exit(e) == 0 ? 0 : 2;
  } catch (const std::exception& e) {
    std::cerr << "deformlab-bench: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
