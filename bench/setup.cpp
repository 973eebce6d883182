// The benches' shared scene, flags, statistics and CSV files (bench.hpp).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "app/command_line.hpp"
#include "bench.hpp"
#include "core/profiler.hpp"
#include "experiments/experiment.hpp"
#include "experiments/output.hpp"
#include "experiments/pipelines.hpp"
#include "mesh/scene_model.hpp"

namespace deformlab::bench {

const char* to_string(SceneKind k) { return k == SceneKind::paper ? "paper" : "idealised"; }

std::string describe(SceneKind k) {
  if (k == SceneKind::paper)
    return "paper scene: the table2 experiment's (spring damping, ground, a sphere, the centre node dragged on its "
           "path, dt 50 us), from rest";
  return "idealised scene: 1 m, top corners pinned, undamped springs, no contact, no drag, dt 1 ms, from rest";
}

std::string title(const char* name) {
  return std::string("deformlab-bench ") + name + " (build " + build_info()["git"].get<std::string>() + "):";
}

namespace {
Scene scene_of(int n, SceneKind k) {
  Scene s;
  if (k == SceneKind::paper) {
    s = load_experiment_by_name("table2").scene;
  } else {
    s.model.material = Material{};
    s.params.dt = 0.001f;
  }
  s.model.nx = s.model.ny = n;
  return s;
}
}  // namespace

BenchScene::BenchScene(int n, SceneKind k) : BenchScene(scene_of(n, k)) {}

BenchScene::BenchScene(const Scene& s) : model(build_model(s)), params(resolve_params(s, model)) {}

namespace {

// Throws unless the scene's model and a state fit beside what the host has left, with the
// largest host footprint of the pipelines named (an allocation of another pipeline's that fails
// is reported as out of memory).
void require_fits(const Scene& s, const std::vector<std::string>& names, Integrator integ) {
  const ModelSize size = model_size(s.model);
  const std::int64_t need = model_host_bytes(size) + state_host_bytes(size.nodes);
  if (const auto limit = host_memory_limit(); limit && need > limit->bytes)
    throw std::invalid_argument("a " + std::to_string(s.model.nx) + " x " + std::to_string(s.model.ny) + " cloth needs " +
                                gib(need) + " of host memory for its model and state; " + limit->name + " leaves " +
                                gib(limit->bytes));
  for (const std::string& name : names)
    if (const std::string why = host_memory_shortfall(size, *pipelines().find(name), integ, {}); !why.empty())
      throw std::invalid_argument(why);
}

}  // namespace

void check_sizes(const std::string& flag, const std::vector<int>& sizes, SceneKind k,
                 const std::vector<std::string>& pipelines, Integrator integ) {
  for (auto n = sizes.begin(); n != sizes.end(); ++n) {
    const std::string at = flag + ": size " + std::to_string(*n);
    if (*n < 2) throw std::invalid_argument(at + ": expected 2 or more");
    if (std::find(sizes.begin(), n, *n) != n) throw std::invalid_argument(at + " is named twice");
    try {
      check_node_count(double(*n) * *n);
      require_fits(scene_of(*n, k), pipelines, integ);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(at + ": " + e.what());
    }
  }
}

Stats stats(std::vector<double> ms) {
  if (ms.empty()) return {};
  std::sort(ms.begin(), ms.end());
  return {median(ms), ms.front(), ms[std::min(ms.size() - 1, ms.size() * 9 / 10)]};
}

Stats stats(const TimedWork& w) {
  Stats s = stats(w.ms);
  s.clock = w.clock;
  return s;
}

std::string clock_columns(const ClockSummary& c) {
  return c.watched() ? std::to_string(c.sm_mhz_median) + "," + std::to_string(c.slowed) : ",";
}

void print_clocks(std::ostream& os, const ClockTally& clocks, const std::string& timed) {
  os << "\n[clock] ";
  if (clocks.empty())
    os << "the GPU's clock was not read (no NVIDIA driver's NVML here)\n";
  else
    os << "SM clock over each case's " << timed << " (NVML, sampled every " << ClockWatch::kPeriodMs
       << " ms): " << clocks.describe("case", true) << "\n";
}

std::string fixed(double v, int prec) {
  if (std::isnan(v)) return "-";
  std::ostringstream s;
  s << std::fixed << std::setprecision(prec) << v;
  return s.str();
}

Integrator BenchOptions::integ() const {
  const auto i = parse_integrator(integrator);
  if (!i) throw std::invalid_argument("unknown integrator '" + integrator + "' (valid: " + integrator_names() + ")");
  return *i;
}

Integrator BenchOptions::checked(const std::vector<std::string>& names) const {
  const Integrator i = integ();
  for (const std::string& name : names)
    if (const std::string why = pipelines().find(name)->unsupported(i); !why.empty())
      throw std::invalid_argument(name + ": " + why);
  check_sizes("--sizes", sizes, scene_kind(), names, i);
  return i;
}

void add_bench_options(CLI::App& c, BenchOptions& o) {
  c.add_option("--sizes", o.sizes, "Grid sizes n (n x n nodes), 2 and up")
      ->check(deformlab::app::whole_in(2, 1 << 17));
  c.add_flag("--idealised", o.idealised,
             "Time the idealised scene (undamped, no contact, no drag) in place of the paper's (table2's)");
  c.add_option("--warmup", o.warmup, "Warm-up steps (0: none)")->check(deformlab::app::whole_in(0, std::numeric_limits<int>::max()));
  c.add_option("--integrator", o.integrator, "Integrator")->transform([](std::string name) {
    const auto i = parse_integrator(name);  // the paper's aliases by their names
    return i ? std::string(info(*i).name) : name;
  });
  c.add_option("--csv", o.csv, "Also write the results to this CSV file (replacing an earlier CSV of this bench only)")
      ->check([](const std::string& file) { return file.empty() ? std::string("an empty file name") : std::string(); });
}

void add_warmup_ms(CLI::App& c, BenchOptions& o) {
  c.add_option("--warmup-ms", o.warmup_ms, "Untimed steps from rest before each case for this long, ms (0: none)")
      ->check(deformlab::app::real_in(0.0, 3.6e6));
}

std::string warm_up_words(const BenchOptions& o) {
  return o.warmup_ms > 0 ? fixed(o.warmup_ms, 0) + " ms of untimed steps from rest (host clock), then " : "";
}

std::string build_column() { return "," + build_info()["git"].get<std::string>(); }

std::string run_columns(const BenchOptions& o) {
  return std::string(",") + to_string(o.scene_kind()) + "," + o.integrator + build_column();
}

namespace {

// The rows of each CSV file a bench has written, kept until finish_csv_files.
std::vector<std::pair<std::string, std::string>>& finished_csv_files() {
  static std::vector<std::pair<std::string, std::string>> files;  // file, rows
  return files;
}

}  // namespace

CsvFile::~CsvFile() {
  if (!file_.empty()) finished_csv_files().emplace_back(file_, str());
}

CsvFile open_csv(const std::string& path, const char* header, const char* tail) {
  if (path.empty()) return {};
  require_file_target(path, "--csv");  // before anything is measured
  const std::string first_line = std::string(header) + tail;
  // Replaces an earlier CSV of this bench, or an empty file, and nothing else.
  std::error_code ec;
  if (std::filesystem::is_regular_file(path, ec) && std::filesystem::file_size(path, ec) > 0) {
    std::ifstream in(path);
    std::string first;
    std::getline(in, first);
    if (first != first_line)
      throw std::invalid_argument("--csv '" + path + "' holds a file whose first line is not this bench's header (" +
                                  first_line + "): move it or give another file");
  }
  CsvFile csv(path);
  csv << first_line << "\n";
  return csv;
}

void finish_csv_files() {
  for (const auto& [file, rows] : std::exchange(finished_csv_files(), {})) write_atomically(file, rows);
}

void add_step_bench(CLI::App& app, const char* name, const char* description, std::vector<int> sizes, int warmup,
                    int reps, const char* reps_help, void (*run)(const StepOptions&), Device device) {
  auto o = std::make_shared<StepOptions>();
  o->sizes = std::move(sizes);
  o->warmup = warmup;
  o->reps = reps;
  auto* c = app.add_subcommand(name, description);
  add_bench_options(*c, *o);
  // Each timed step's time is kept (8 bytes): 10^7 of them take 80 MB.
  c->add_option("--reps", o->reps, reps_help)->check(deformlab::app::whole_in(1, 10'000'000));
  if (device == Device::gpu) add_warmup_ms(*c, *o);
  c->callback([o, run] { run(*o); });
}

}  // namespace deformlab::bench
