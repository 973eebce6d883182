// Pipeline: a force backend + update backend + integrator (+ interop mode), named by one
// short string. Every pipeline runs the same model, params and schedule.
#pragma once
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "integrator.hpp"
#include "memory.hpp"
#include "model.hpp"
#include "params.hpp"
#include "profiler.hpp"
#include "state.hpp"
#include "step_timer.hpp"

namespace deformlab {

class Pipeline {
 public:
  virtual ~Pipeline() = default;
  virtual void set_state(const State& s) = 0;
  virtual State state() = 0;  // a read-back on GPU pipelines: not for every step
  virtual void step() = 0;    // advance by params.dt with the integrator's schedule
  // Replaces the drag handle (its node, path and mode) from the next step on, as the viewer's
  // picking does; the path is read at the pipeline's own time. Throws std::invalid_argument
  // for a handle that does not fit the model.
  virtual void set_drag(const DragHandle& d) = 0;
  // Largest node displacement |x_{n+1} - x_n| of the last step, computed where the state
  // lives; NaN when any position or velocity is not finite.
  virtual double max_displacement() = 0;
  // Checks that do not hold the device up. A pipeline that keeps the state from before its last
  // launch (steps_per_launch() steps) can take that launch back (once, until the next launch);
  // the run loop then checks step n while the launch after it runs and takes that launch back
  // when n met the stop rule. queue_displacement() queues the read of the last step's
  // max_displacement() and returns at once; take_displacement() waits for it (one read at a
  // time, taken before the launch after the next one). Pipelines that cannot step back need not
  // queue: the run waits at each check.
  virtual bool can_step_back() const { return false; }
  virtual void step_back() { throw std::logic_error("this pipeline cannot take a step back"); }
  virtual void queue_displacement() { throw std::logic_error("this pipeline does not queue its checks"); }
  virtual double take_displacement() { throw std::logic_error("this pipeline does not queue its checks"); }
  // Steps it queues into one launch (cuda-temporal: k); a check launches the steps held so far
  // (so a check at a step that ends no launch waits for its step).
  virtual int steps_per_launch() const { return 1; }
  // A timer of this pipeline's steps on the clock of the device that runs them (valid while
  // the pipeline lives). The default: the host clock, for pipelines that step on the host.
  virtual std::unique_ptr<StepTimer> step_timer() { return std::make_unique<HostStepTimer>(); }
  // The OpenGL buffer holding the current positions, a vec4 per node (w: inverse mass), ready
  // for GL to read: renderers draw from it without a copy. 0 where the state is not in GL.
  virtual unsigned gl_position_buffer() { return 0; }
  // How the profiler's stage spans are timed ("host clock", "CUDA events", "GL timer queries").
  virtual std::string timing_method() const { return "host clock"; }
  // Pipelines that time their stages add spans (force, hand-off, update, ...) to `p` from
  // now on; null stops it. The default records nothing.
  virtual void set_profiler(Profiler* p) { (void)p; }
  // The options this pipeline chose for itself, by the machine it runs on, where none was given
  // (the hybrids' interop mode), as PipelineOptions would name them; runs and cells record them.
  virtual std::map<std::string, std::string> chosen_options() const { return {}; }
};

// Per-pipeline settings by name, e.g. {"tile": "16x8"} or {"interop": "map"}; each
// pipeline lists the names it reads in its kind (PipelineKind::options).
using PipelineOptions = std::map<std::string, std::string>;

// How a GPU pipeline's kernels and shaders do their float arithmetic (the pipeline option
// "math", the precision option): `exact` does the CPU float pipeline's operations (no
// contraction into fused multiply-adds, correctly rounded division and square root); `fast`
// lets the compiler contract and use the hardware's approximate reciprocal and reciprocal
// square root (nvcc's fast math, GLSL's defaults). Exact is the default (README: why).
enum class Math { exact, fast };
const char* to_string(Math m);
// The option "math" ("exact" or "fast"), else exact; throws std::invalid_argument.
Math math_option(const PipelineOptions& o);
// A count in an option's value: decimal digits with no sign, space or leading zero, from 1 to
// `most`, else nothing. One spelling a number, so that a sweep does not take one value spelt two
// ways for two option sets.
std::optional<std::int64_t> option_count(std::string_view s, std::int64_t most);

// What a pipeline needs to be built.
struct PipelineSetup {
  const Model& model;
  const Params& params;
  Integrator integrator;
  PipelineOptions options = {};
};

// What runs a pipeline's force or update passes. Reports bound each pass by the calibrated
// ceiling of what runs it (experiments/ceilings.hpp).
enum class Engine { cpu, cuda, gl_compute, gl_transform_feedback };

// How a pipeline's results compare with the `cpu` pipeline's from the same state.
enum class CpuMatch { bitwise, rounding };

// What a pipeline is, as plain data for tests, sweeps and reports. A name carries the same
// traits whether or not this build has its backend (PipelineKind).
struct PipelineTraits {
  Engine force = Engine::cpu, update = Engine::cpu;
  bool deterministic = true;  // bitwise equal run to run
  CpuMatch cpu_match = CpuMatch::bitwise;  // with exact math (fast math: rounding)
  bool grids_only = false;  // runs cloth and lattice grids, not general models (meshes)
  // Its passes run on two APIs, which hand the state over twice per force evaluation.
  bool hands_off() const { return force != update; }
  bool operator==(const PipelineTraits&) const = default;
};

// A pipeline as every build knows it, whichever backends the build has: written once, in
// core/pipeline_kinds.cpp, in order of their step times measured on a 2048^2 cloth.
struct PipelineKind {
  std::string name;
  std::string summary;
  std::string needs;  // what a build needs to have it ("CUDA", "OpenGL", ...; empty: every build)
  PipelineTraits traits;
  std::vector<std::string> options;  // option names it reads (see PipelineOptions)
};
const std::vector<PipelineKind>& pipeline_kinds();
// The kind named `name`; throws std::logic_error where there is none.
const PipelineKind& pipeline_kind(const std::string& name);

struct PipelineEntry {
  std::string name;
  std::string summary;
  PipelineTraits traits;
  // Empty when usable on this build and machine, else the reason it is not.
  std::function<std::string()> unavailable;
  // Empty when the pipeline runs this integrator, else the reason it does not.
  std::function<std::string(Integrator)> unsupported;
  std::function<std::unique_ptr<Pipeline>(const PipelineSetup&)> make;
  std::vector<std::string> options = {};  // option names it reads (see PipelineOptions)
  // Bytes it allocates for a model of this size beyond the model itself: on the host and on
  // its device (checked against the device's free memory when it is built).
  std::function<Footprint(const ModelSize&, Integrator, const PipelineOptions&)> footprint = {};
  // Reads the values of its options, throwing std::invalid_argument at the first it cannot
  // (what depends on the device, such as a GL limit, is checked when the pipeline is made).
  std::function<void(const PipelineOptions&)> read_options = {};
  // Empty when every option of a readable set acts on a model of this topology, else why the
  // first does nothing there (a mesh's option on a grid, a thread block where a kernel takes none).
  std::function<std::string(const PipelineOptions&, Topology)> idle_option = {};
};

// The entry a backend registers for kind `name`: the kind's name, summary, traits and options,
// with the backend's functions.
PipelineEntry described(const std::string& name, std::function<std::string()> unavailable,
                        std::function<std::string(Integrator)> unsupported,
                        std::function<std::unique_ptr<Pipeline>(const PipelineSetup&)> make,
                        std::function<Footprint(const ModelSize&, Integrator, const PipelineOptions&)> footprint,
                        std::function<void(const PipelineOptions&)> read_options = {},
                        std::function<std::string(const PipelineOptions&, Topology)> idle_option = {});

// How `e` run with options `o` compares with the `cpu` pipeline: its trait, or rounding
// where the options choose fast math.
CpuMatch cpu_match(const PipelineEntry& e, const PipelineOptions& o);

// Whether `e` reads the option `name`.
bool reads_option(const PipelineEntry& e, const std::string& name);

// Throws std::invalid_argument, naming `e`, at the first option of `o` that `e` does not read
// or whose value it cannot read: what a run or a sweep checks before anything runs.
void check_options(const PipelineEntry& e, const PipelineOptions& o);
// check_options, then the same for the first option that would do nothing on a model of topology `t`.
void check_options(const PipelineEntry& e, const PipelineOptions& o, Topology t);

// Empty when a run of `e` on a model of size `m` fits in this machine's host memory, else one
// line naming the need (the model, the pipeline's own host buffers, a state read back; with a
// `reference`, as `deformlab run --compare` does, that pipeline and its state too) and the
// limit that refuses it. The device's share is checked when the pipeline is built.
std::string host_memory_shortfall(const ModelSize& m, const PipelineEntry& e, Integrator i,
                                  const PipelineOptions& o, const PipelineEntry* reference = nullptr);
// The same before a pipeline is chosen (`deformlab view`'s `best`): the model and its state alone.
std::string model_memory_shortfall(const ModelSize& m, Integrator i, const PipelineEntry* reference = nullptr);

// Runs `steps` steps of `p`, each timed by `t` (one of p's timers, with nothing pending);
// their ms in order.
std::vector<double> timed_steps(Pipeline& p, StepTimer& t, int steps);

// Untimed steps (`step`, then `drain` waits for the device) until `min_ms` have passed on the
// host clock (none for 0): how many and how long. A GPU left idle (while a model is built, say)
// lowers its clock and takes a few hundred ms of work to raise it again (measured on the H100:
// 345 MHz to 1980), so GPU pipelines are timed after kGpuWarmUpMs of it.
struct WarmUp {
  int steps = 0;
  double ms = 0.0;  // host clock
};
WarmUp warm_up(const std::function<void()>& step, const std::function<void()>& drain, double min_ms);
// warm_up of `p`'s steps (drained by max_displacement) from m's rest state, then `p` back at rest.
WarmUp warm_up_from_rest(Pipeline& p, const Model& m, double min_ms);
inline constexpr double kGpuWarmUpMs = 1000.0;
// Device time that a GPU pipeline's timed steps span at the least, back to back (no wait between
// them) after the warm-up and the return to rest, as a run's are. On the H100 at 2048^2 in fast
// math cuda-fused's first 100-200 steps after the pause took up to 3% longer than the rest, and
// steps timed in batches of about 1 ms with a wait after each took 1-17% longer throughout
// (docs/speed.md, the bench and the run in fast math).
inline constexpr double kGpuTimedMs = 200.0;
// Steps that span about `ms` at `step_ms` a step: at least `min_steps` (from 1), rounded up to a
// multiple of `multiple` (cuda-temporal's launches of up to 8 steps whole).
int steps_spanning(double ms, double step_ms, int min_steps, int multiple = 1);
// Whether any of e's passes runs on a GPU (it then warms up before it is timed).
bool on_gpu(const PipelineEntry& e);
// Whether `e` is one of the OpenGL engines.
inline bool is_gl(Engine e) { return e == Engine::gl_compute || e == Engine::gl_transform_feedback; }

class PipelineRegistry {
 public:
  void add(PipelineEntry e);
  const PipelineEntry* find(const std::string& name) const;
  const std::vector<PipelineEntry>& all() const { return entries_; }
  std::string names() const;  // comma-separated, for messages

 private:
  std::vector<PipelineEntry> entries_;
};

}  // namespace deformlab
