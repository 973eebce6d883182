#include "run_input.hpp"

#include <linux/magic.h>
#include <sys/statvfs.h>
#include <sys/vfs.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>
#include <sstream>
#include <utility>

#include "core/memory.hpp"
#include "core/number_text.hpp"
#include "core/run.hpp"
#include "experiments/output.hpp"
#include "experiments/pipelines.hpp"
#include "experiments/sweep.hpp"
#include "mesh/scene_model.hpp"
#if DEFORMLAB_GL_RENDER
#include "gl/context.hpp"
#endif

namespace deformlab::app {
namespace {

struct BadInput : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// The GL flags, then the experiment (or the default one) with --scene, --pipeline and
// --integrator applied.
Experiment read_experiment(const RunArgs& a) {
#if DEFORMLAB_GL_RENDER
  if (a.gl_device) gl::configure({.device = *a.gl_device});
  if (a.frames && *a.frames < 1) throw BadInput("--frames must be at least 1");
#else
  if (a.frames || a.gl_device) throw BadInput("--frames and --gl-device need a build with OpenGL");
#endif
  Experiment x = a.experiment ? load_experiment_by_name(*a.experiment) : default_experiment();
  if (a.experiment) parse_sweep(x.raw, *a.experiment);  // a run leaves the sweep out, but not unread
  if (a.scene) x.scene = load_scene(*a.scene);
  if (a.pipeline) x.pipeline = *a.pipeline;
  if (a.integrator) x.integrator = *a.integrator;
  return x;
}

// The experiment's integrator.
Integrator integrator_of(const Experiment& x) {
  const auto i = parse_integrator(x.integrator);
  if (!i) throw BadInput("unknown integrator '" + x.integrator + "' (valid: " + integrator_names() + ")");
  return *i;
}

// The experiment's pipeline ("best": the best here for `integ`).
const PipelineEntry* find_pipeline(const Experiment& x, Integrator integ) {
  const PipelineEntry* entry = x.pipeline == "best" ? &best_pipeline(integ) : pipelines().find(x.pipeline);
  if (!entry) throw BadInput("unknown pipeline '" + x.pipeline + "' (valid: best, " + pipelines().names() + ")");
  return entry;
}

// Throws unless `entry` runs `integ`.
void require_supports(const PipelineEntry* entry, const Experiment& x, Integrator integ) {
  if (const auto why = entry->unsupported(integ); !why.empty())
    throw BadInput("integrator '" + x.integrator + "' is not available on " + entry->name + ": " + why);
}

// Throws unless `entry` is available here and runs `integ`.
void require_runs(const PipelineEntry* entry, const Experiment& x, Integrator integ) {
  if (const auto why = entry->unavailable(); !why.empty())
    throw BadInput("pipeline '" + entry->name + "' is not available: " + why);
  require_supports(entry, x, integ);
}

// Throws unless a pipeline of this build that reads every option of `o` accepts their values:
// what can be checked of options before a pipeline is chosen. Pipelines with no GL pass that
// are unavailable here (CUDA's without a device or in a build without CUDA) are passed over,
// and named where no other pipeline has the options. Those with a GL pass are asked only for
// values, where this build has them (read_options): whether they run here is known only once
// the window has made its context. With no pipeline left to ask, it passes.
void require_some_reader(const PipelineOptions& o) {
  std::string names, first, unavailable;
  for (const auto& [name, value] : o) names += (names.empty() ? "" : ", ") + name;
  bool any = false;
  for (const PipelineEntry& e : pipelines().all()) {
    if (!std::all_of(o.begin(), o.end(), [&](const auto& kv) { return reads_option(e, kv.first); })) continue;
    if (!is_gl(e.traits.force) && !is_gl(e.traits.update))
      if (const std::string why = e.unavailable(); !why.empty()) {
        if (unavailable.empty()) unavailable = e.name + ": " + why;
        continue;
      }
    any = true;
    if (!e.read_options) continue;
    try {
      check_options(e, o);
      return;
    } catch (const std::invalid_argument& x) {
      if (first.empty()) first = x.what();
    }
  }
  if (!any && !unavailable.empty())
    throw BadInput("--option: no pipeline available here has all of the options " + names + " (" + unavailable + ")");
  if (!any) throw BadInput("--option: no pipeline has all of the options " + names);
  if (!first.empty()) throw BadInput("--option: no pipeline reads these values (" + first + ")");
}

// --option NAME=VALUE flags, each an option the pipeline reads, with a value it can read; with no
// pipeline chosen yet (`view`'s best, before its window), options some pipeline reads with their
// values.
PipelineOptions parse_options(const std::vector<std::string>& flags, const PipelineEntry* entry) {
  PipelineOptions options;
  for (const auto& o : flags) {
    const auto eq = o.find('=');
    if (eq == std::string::npos || eq == 0) throw BadInput("--option '" + o + "': expected NAME=VALUE");
    const std::string name = o.substr(0, eq);
    if (!options.emplace(name, o.substr(eq + 1)).second)
      throw BadInput("--option '" + o + "': option '" + name + "' is given twice");
    const auto& all = pipelines().all();
    if (!entry && std::none_of(all.begin(), all.end(), [&](const PipelineEntry& e) { return reads_option(e, name); }))
      throw BadInput("--option '" + o + "': no pipeline has an option '" + name + "'");
  }
  if (!entry) {
    if (!options.empty()) require_some_reader(options);
    return options;
  }
  try {
    check_options(*entry, options);
  } catch (const std::invalid_argument& e) {
    throw BadInput(e.what());
  }
  return options;
}

void apply_model_flags(const RunArgs& a, ModelSpec& ms) {
  if ((a.grid || a.lattice) && ms.topology == Topology::general)
    std::cerr << "deformlab: note: " << (a.grid ? "--grid " + *a.grid + " replaces the scene's mesh model with a cloth"
                                                : "--lattice " + *a.lattice + " replaces the scene's mesh model with a lattice")
              << "\n";
  if (a.grid) {
    const auto d = parse_size(*a.grid, 2, "--grid");
    ms.topology = Topology::cloth_grid;
    ms.nx = d[0]; ms.ny = d[1]; ms.nz = 1;
  }
  if (a.lattice) {
    const auto d = parse_size(*a.lattice, 3, "--lattice");
    ms.topology = Topology::lattice;
    ms.nx = d[0]; ms.ny = d[1]; ms.nz = d[2];
  }
}

void apply_param_flags(const RunArgs& a, Params& p) {
  if (a.dt) p.dt = float(*a.dt);
  // Read as floats: a dt under float's normal range is 0 or a subnormal whose inverse overflows.
  if (a.dt && !(*a.dt >= std::numeric_limits<float>::min() && *a.dt <= 3e38))
    throw BadInput("--dt must be a positive number of seconds from 1.18e-38 (the smallest normal float) to 3e38");
  if (a.threshold && !(*a.threshold >= std::numeric_limits<float>::min() && *a.threshold <= 3e38))
    throw BadInput("--threshold must be a positive number of metres from 1.18e-38 (the smallest normal float) to 3e38");
  if (a.threshold) p.threshold = float(*a.threshold);
  if (a.check_every && *a.check_every < 1) throw BadInput("--check-every must be at least 1");
  if (a.check_every) p.check_every = *a.check_every;
  if (a.steps) p.max_steps = *a.steps;
  if (a.steps && *a.steps < 1) throw BadInput("--steps must be at least 1");
  if (a.warmup_ms && !(*a.warmup_ms >= 0.0 && *a.warmup_ms <= 3.6e6))
    throw BadInput("--warmup-ms must be between 0 and 3600000 (an hour)");
}

}  // namespace

void check_run_flags(const RunArgs& a) {
  Scene scratch;
  apply_model_flags(a, scratch.model);
  apply_param_flags(a, scratch.params);
}

namespace {

// Refuses a run whose host memory does not fit before anything is allocated.
// With no pipeline chosen yet (`best` in `view`, before its window), the model and its state.
void check_fits(const RunInput& in, bool compare, const ModelSize& size) {
  const PipelineEntry* reference = compare ? pipelines().find("reference") : nullptr;
  const std::string why = in.entry ? host_memory_shortfall(size, *in.entry, in.integ, in.options, reference)
                                   : model_memory_shortfall(size, in.integ, reference);
  if (!why.empty()) throw BadInput(why);
}

// A run keeps a record of each step until it ends (timings.csv, the spans of sampled steps):
// 89 B of host memory a step measured (peak resident set, 2 M steps against 1000, a 2x2 cloth).
constexpr std::int64_t kStepRecordBytes = 96;
void check_records_fit(const Params& p) {
  const auto limit = host_memory_limit();
  const std::int64_t need = std::int64_t(p.max_steps) * kStepRecordBytes;
  if (limit && need > limit->bytes / 2)
    throw BadInput(std::to_string(p.max_steps) + " steps keep " + gib(need) + " of step records in host memory; " +
                   limit->name + " leaves " + gib(limit->bytes) + " (at most half of it for them): run fewer steps");
}

// Bytes a run writes for `steps` steps, and what they are. Measured (cpu, a 128² cloth, 3000
// steps): timings.csv 48 a step, spans.csv 108; with --trace spans.csv 229 and trace.json 629;
// GL runs' timings and spans up to 213 a step; frames of 1024² pixels 118-146 kB.
std::pair<std::int64_t, std::string> output_bytes(const RunArgs& a, const RunInput& in, std::int64_t steps) {
  std::int64_t need = steps * (a.trace ? 56 + 240 + 640 : 56 + 184);
  std::string what = std::to_string(steps) + " steps' timings" + (a.trace ? ", spans and trace" : " and spans");
  if (!a.no_state) {
    need += ply_bytes(in.model);
    what += ", state.ply";
  }
  if (a.frames) {
    need += (steps / *a.frames + 1) * 160'000;
    what += ", frames at 160 kB";
  }
  if (a.energy) {
    need += (steps / *a.energy + 2) * 120;
    what += ", energies";
  }
  return {need, what};
}

// Refuses a run whose files would not fit in the free space of its output folder's file
// system; a convergence run, which may stop at min_steps, only where those would not, with a
// note where all its steps would not.
// The output folder, or the nearest folder above it that exists.
std::filesystem::path existing_part(const std::filesystem::path& out) {
  std::error_code ec;
  std::filesystem::path at = std::filesystem::absolute(out, ec);
  while (!std::filesystem::exists(at, ec) && at.has_parent_path() && at != at.parent_path()) at = at.parent_path();
  return at;
}

}  // namespace

void require_writable(const std::filesystem::path& out) {
  if (out.empty()) throw BadInput("--out '': an empty path names no folder");
  const std::filesystem::path at = existing_part(out);
  const std::string folder = "output folder '" + out.string() + "'";
  struct statfs f{};
  constexpr long kKernelFileSystems[] = {PROC_SUPER_MAGIC, SYSFS_MAGIC,      CGROUP_SUPER_MAGIC, CGROUP2_SUPER_MAGIC,
                                         DEBUGFS_MAGIC,    TRACEFS_MAGIC,    SECURITYFS_MAGIC,   PSTOREFS_MAGIC,
                                         BPF_FS_MAGIC,     DEVPTS_SUPER_MAGIC};
  if (::statfs(at.c_str(), &f) == 0 && std::ranges::find(kKernelFileSystems, long(f.f_type)) != std::end(kKernelFileSystems))
    throw BadInput(folder + ": '" + at.string() + "' is on one of the kernel's file systems (such as proc or sysfs)");
  if (std::error_code ec; !std::filesystem::is_directory(at, ec))
    throw BadInput(folder + ": '" + at.string() + "' is not a folder");
  if (::access(at.c_str(), W_OK) != 0) throw BadInput(folder + ": '" + at.string() + "' is not writable");
}

namespace {

void check_disk_fits(const RunArgs& a, const RunInput& in) {
  const std::filesystem::path at = existing_part(in.out);
  const std::string folder = "output folder '" + in.out.string() + "'";
  struct statvfs v{};
  if (::statvfs(at.c_str(), &v) != 0 || v.f_blocks == 0) return;  // no size known (ramfs, some FUSE file systems)
  const std::int64_t free = std::int64_t(v.f_bavail) * std::int64_t(v.f_frsize);
  const Params& p = in.params;
  const auto [need, what] = output_bytes(a, in, in.until_converged ? std::min(p.min_steps, p.max_steps) : p.max_steps);
  if (need > free)
    throw BadInput(folder + ": this run writes " + (in.until_converged ? "at least " : "about ") + bytes_text(need) +
                   " (" + what + ") and its file system has " + bytes_text(free) + " free: free some or give another --out");
  if (const auto [most, _] = output_bytes(a, in, p.max_steps); in.until_converged && most > free)
    std::cerr << "deformlab: note: " << folder << " has " << bytes_text(free) << " free; this run writes "
              << bytes_text(most) << " if it runs all " << p.max_steps << " steps without converging\n";
}

}  // namespace

std::vector<int> parse_size(const std::string& s, int dims, const char* flag) {
  const std::string pat = dims == 2 ? "WxH" : "WxHxD";
  std::vector<int> out;
  std::stringstream ss(s);
  for (std::string part; std::getline(ss, part, 'x');) {
    if (part.empty() || !std::all_of(part.begin(), part.end(), ::isdigit))
      throw std::invalid_argument(std::string(flag) + " '" + s + "': expected " + pat +
                                  ", positive whole numbers joined by a lower-case x (" +
                                  (dims == 2 ? "128x128" : "16x16x16") + ")");
    const long long v = std::stoll(part.size() > 12 ? std::string("9999999999999") : part);
    if (v <= 0 || v > 1'000'000'000)
      throw std::invalid_argument(std::string(flag) + " '" + s + "': each size must be between 1 and 10^9");
    out.push_back(int(v));
  }
  if (int(out.size()) != dims || s.back() == 'x')
    throw std::invalid_argument(std::string(flag) + " '" + s + "': expected " + pat);
  return out;
}

std::string stop_rule_start(const Params& p) {
  const std::string why = p.drag.active() ? " (min_steps and the drag path's end at t = " +
                                                significant_trimmed(p.drag.end_time(), 6) + " s)"
                                          : " (min_steps)";
  const int step = first_stop_step(p);
  return step == std::numeric_limits<int>::max() ? "the stop rule starts past the last step an int counts" + why
                                                  : "the stop rule starts at step " + std::to_string(step) + why;
}

namespace {

// The options on the model, once the pipeline is known.
void check_pipeline(const RunInput& in) {
  try {
    check_options(*in.entry, in.options, in.x.scene.model.topology);
  } catch (const std::invalid_argument& e) {
    throw BadInput(e.what());
  }
}

// read_run_input, or for `view` read_run_model: no output folder, and the pipeline left for
// resolve_pipeline where choosing it needs a GL context (`best`), and a GL pipeline's availability.
RunInput read(const RunArgs& a, bool view) {
  RunInput in;
  in.x = read_experiment(a);
  if (!view) {
    const std::string name = in.x.name.empty() ? std::string("run") : in.x.name;
    in.out = a.out ? *a.out : "runs/" + name + (in.x.raw.contains("sweep") ? "-run" : "");
    require_folder_or_nothing(in.out);
    require_holds_nothing_but(in.out, Holds::run);
    require_writable(in.out);
  }
  in.integ = integrator_of(in.x);
  if (!view || in.x.pipeline != "best") in.entry = find_pipeline(in.x, in.integ);
  in.options = parse_options(a.options, in.entry);
  // Whether a GL pipeline is available waits, in `view`, for its window's context.
  if (in.entry && (!view || !(is_gl(in.entry->traits.force) || is_gl(in.entry->traits.update))))
    require_runs(in.entry, in.x, in.integ);
  else if (in.entry)
    require_supports(in.entry, in.x, in.integ);
  if (a.gl_device && !view && !a.frames && !is_gl(in.entry->traits.force) &&
      !is_gl(in.entry->traits.update))
    throw BadInput("--gl-device: pipeline '" + in.entry->name + "' runs no OpenGL pass, and no --frames are drawn");
  apply_model_flags(a, in.x.scene.model);
  apply_param_flags(a, in.x.scene.params);
  if (in.entry) check_pipeline(in);
  in.until_converged = a.until_converged || (in.x.until_converged && !a.steps);
  if (a.threshold && !in.until_converged)
    throw BadInput("--threshold applies to a run until converged (--until-converged); this one takes a fixed number "
                   "of steps");
  check_records_fit(in.x.scene.params);
  if (a.compare && *a.compare != "reference")
    throw BadInput("--compare '" + *a.compare +
                   "': the only pipeline to compare with is 'reference' (double precision)");
  if (a.compare && in.entry && in.entry->name == "reference")
    throw BadInput("--compare reference: the pipeline run is 'reference' itself");
  // A grid is counted before it is built; a mesh once it is read.
  const bool mesh = in.x.scene.model.topology == Topology::general;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    if (!mesh) check_fits(in, bool(a.compare), model_size(in.x.scene.model));
    in.model = build_model(in.x.scene);
  } catch (const std::invalid_argument& e) {  // a grid too large: named by where its size was given
    if (mesh) throw;
    throw BadInput(std::string(a.grid ? "--grid" : a.lattice ? "--lattice" : a.scene ? *a.scene + ".model" :
                               a.experiment ? *a.experiment + ".scene.model" : "the paper-drag experiment's model") +
                   " (" + describe(in.x.scene.model) + "): " + e.what());
  }
  if (mesh) check_fits(in, bool(a.compare), in.model.size());
  in.build_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  in.params = resolve_params(in.x.scene, in.model);
  if (in.until_converged && a.steps && first_stop_step(in.params) > in.params.max_steps)
    throw BadInput("--steps " + std::to_string(in.params.max_steps) + " with --until-converged: " +
                   stop_rule_start(in.params) + ", so give at least that many steps");
  if (!view) check_disk_fits(a, in);
  return in;
}

}  // namespace

RunInput read_run_input(const RunArgs& a) { return read(a, false); }

RunInput read_run_model(const RunArgs& a) { return read(a, true); }

void resolve_pipeline(const RunArgs& a, RunInput& in) {
  if (!in.entry) {
    in.entry = find_pipeline(in.x, in.integ);
    in.options = parse_options(a.options, in.entry);
    check_pipeline(in);
    check_fits(in, bool(a.compare), in.model.size());
  }
  require_runs(in.entry, in.x, in.integ);
}

}  // namespace deformlab::app
