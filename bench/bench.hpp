// deformlab-bench: benchmarks, apart from the tests. Each backend adds a subcommand; all
// run the same scene (BenchScene) and take the same basic flags (BenchOptions).
#pragma once
#include <CLI/CLI.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/clock_watch.hpp"
#include "core/pipeline.hpp"
#include "core/number_text.hpp"
#include "core/scene.hpp"
#include "core/timed_work.hpp"

namespace deformlab::bench {

// The benches' scenes, n x n cloths from rest. `paper`, every bench's main row: the table2
// experiment's scene (spring damping, ground, sphere, the centre node dragged, dt 50 us).
// `idealised`: 1 m, top corners pinned, undamped springs, no contact, no drag, dt 1 ms.
enum class SceneKind { paper, idealised };
const char* to_string(SceneKind k);
std::string describe(SceneKind k);

// The scene of size n (a size check_sizes took, before the bench began).
struct BenchScene {
  BenchScene(int n, SceneKind k);
  Model model;
  Params params;
  PipelineSetup setup(Integrator i) const { return {model, params, i}; }

 private:
  explicit BenchScene(const Scene& s);
};

// Median and spread of a list of timings (ms), and the GPU's clock while they were taken.
struct Stats {
  double median = 0, min = 0, p90 = 0;
  ClockSummary clock;  // not watched on the CPU
};
Stats stats(std::vector<double> ms);
Stats stats(const TimedWork& w);  // with w's clock

// A CSV row's last two columns: the median SM clock (MHz) and the share of samples slowed; empty
// where the clock was not watched.
std::string clock_columns(const ClockSummary& c);

// A bench's last line: the GPU's clock over its cases' `timed` ("timed steps", ...).
void print_clocks(std::ostream& os, const ClockTally& clocks, const std::string& timed);


// A bench's first words: "deformlab-bench NAME (build GIT):", the build that measures.
std::string title(const char* name);

// `v` with `prec` decimals; "-" for NaN (not measured).
std::string fixed(double v, int prec);

// The flags every bench takes: grid sizes, scene, warm-up steps, integrator, CSV file; the GPU
// benches' untimed work before each case (add_warmup_ms).
struct BenchOptions {
  std::vector<int> sizes;
  bool idealised = false;  // --idealised: that scene in place of the paper's
  int warmup = 5;
  double warmup_ms = kGpuWarmUpMs;
  std::string integrator = "semi-implicit-euler";
  std::string csv;  // also write the rows here when set
  // `integrator` parsed; throws std::invalid_argument naming it when unknown.
  Integrator integ() const;
  // integ(), checked before a bench prints or measures anything: each of `pipelines` runs it,
  // and check_sizes(sizes, ...) holds. Throws std::invalid_argument at the first that does not.
  Integrator checked(const std::vector<std::string>& pipelines) const;
  SceneKind scene_kind() const { return idealised ? SceneKind::idealised : SceneKind::paper; }
};
void add_bench_options(CLI::App& c, BenchOptions& o);
// Throws std::invalid_argument, naming `flag`, where a size is named twice, or its scene's model and a state do
// not fit the host beside the largest host footprint of `pipelines`.
void check_sizes(const std::string& flag, const std::vector<int>& sizes, SceneKind k,
                 const std::vector<std::string>& pipelines, Integrator integ);
void add_warmup_ms(CLI::App& c, BenchOptions& o);

// A GPU bench case starts with warm_up_from_rest(p, m, o.warmup_ms): the device's clock up after
// the host's setup, as `deformlab run` does.
// The method line's words for it: "1000 ms of untimed steps from rest (host clock), then " (none
// for 0).
std::string warm_up_words(const BenchOptions& o);

// The CSV file at `path` with its header line written; not open when `path` is empty.
// Throws std::invalid_argument when it cannot be written.
// The columns each CSV row of a bench ends with, so that a file says what it measured: the
// build, and where the bench runs one scene and integrator, those first. Their names end the
// header (`tail`: kRunColumns or kBuildColumn); the rows' values are run_columns / build_column.
inline constexpr const char* kRunColumns = ",scene,integrator,build";
inline constexpr const char* kBuildColumn = ",build";
std::string run_columns(const BenchOptions& o);
std::string build_column();
// The rows of a CSV file (none: no file), kept in memory: the file is written whole by
// finish_csv_files once the bench has ended well, so that bad input found partway, a failure or
// a kill leave the file as it was.
class CsvFile : public std::ostringstream {
 public:
  CsvFile() = default;
  explicit CsvFile(std::string file) : file_(std::move(file)) {}
  CsvFile(CsvFile&& o) noexcept : std::ostringstream(std::move(o)), file_(std::exchange(o.file_, {})) {}
  ~CsvFile() override;  // hands the rows on to finish_csv_files
  explicit operator bool() const { return !file_.empty(); }  // whether rows are wanted

 private:
  std::string file_;
};
// The file, which must be writable where it is named (else std::invalid_argument), with its header.
CsvFile open_csv(const std::string& path, const char* header, const char* tail);
// Writes each file whose CsvFile is gone; throws where one cannot be written.
void finish_csv_files();

// What the per-step benches (cpu, gl) take: BenchOptions and the number of timed steps.
struct StepOptions : BenchOptions {
  int reps = 0;
};
// Adds `name` with StepOptions' flags (default sizes, warm-up and timed steps as given, --reps
// described by `reps_help`; on a GPU also --warmup-ms); `run` runs it.
enum class Device { cpu, gpu };
void add_step_bench(CLI::App& app, const char* name, const char* description, std::vector<int> sizes, int warmup,
                    int reps, const char* reps_help, void (*run)(const StepOptions&), Device device);

void add_cpu_bench(CLI::App& app);
#if DEFORMLAB_HAVE_CUDA
void add_cuda_bench(CLI::App& app);
#endif
#if DEFORMLAB_HAVE_GL
void add_gl_bench(CLI::App& app);
#endif
#if DEFORMLAB_HAVE_INTEROP
void add_hybrid_bench(CLI::App& app);
void add_draw_bench(CLI::App& app);
#endif

}  // namespace deformlab::bench
