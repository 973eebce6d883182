#include <iostream>
#include <new>
#include <stdexcept>

#include "app/command_line.hpp"
#include "bench.hpp"
#include "core/one_line.hpp"

int main(int argc, char** argv) {
  CLI::App cli{"deformlab-bench: timings of deformlab's pipelines (not tests)", "deformlab-bench"};
  cli.require_subcommand(1);
  cli.option_defaults()->always_capture_default();  // --help shows each option's default
  deformlab::bench::add_cpu_bench(cli);
#if DEFORMLAB_HAVE_CUDA
  deformlab::bench::add_cuda_bench(cli);
#endif
#if DEFORMLAB_HAVE_GL
  deformlab::bench::add_gl_bench(cli);
#endif
#if DEFORMLAB_HAVE_INTEROP
  deformlab::bench::add_hybrid_bench(cli);
  deformlab::bench::add_draw_bench(cli);
#endif
  deformlab::app::decimal_numbers_only(cli);
  try {
    deformlab::app::cap_openmp_threads("deformlab-bench");  // before parsing: the benches run in its callbacks
    // The benches run in the parser's callbacks and print their results as they go.
    if (const int code = deformlab::app::parse_command_line(cli, argc, argv); code >= 0)
      return deformlab::app::flush_output("deformlab-bench", code);
    deformlab::bench::finish_csv_files();
  } catch (const std::invalid_argument& e) {  // bad input
    std::cerr << "deformlab-bench: error: " << deformlab::one_line(e.what()) << "\n";
    return 2;
  } catch (const std::bad_alloc&) {  // a pipeline's allocation: the check before the model counts only it
    std::cerr << "deformlab-bench: error: out of memory (host or device): the model or its pipeline does not fit this machine\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "deformlab-bench: error: " << deformlab::one_line(e.what()) << "\n";
    return 1;
  }
  return deformlab::app::flush_output("deformlab-bench", 0);
}
