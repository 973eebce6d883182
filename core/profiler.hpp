// Profiling: named spans for the stages and hand-offs of each step, each timed by the clock
// that is true for it (CUDA events for CUDA work, GL timer queries for GL work, the host
// clock for what the CPU does or waits for), written as CSV and as a Chrome trace JSON that
// opens in Perfetto. NVTX ranges with the same names mark the host side for Nsight (the
// NVTX header is header-only; the ranges cost nothing unless a tool is attached).
#pragma once
#include <chrono>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace deformlab {

// Span names shared by every pipeline.
namespace span {
inline constexpr const char* step = "step";
inline constexpr const char* force = "force";
inline constexpr const char* hand_off = "hand-off";
inline constexpr const char* update = "update";
// One pass that evaluates the forces and integrates (cuda-fused, the glsl-tf and
// glsl-compute passes): the two stages cannot be timed apart.
inline constexpr const char* force_update = "force+update";
inline constexpr const char* constraints = "constraints";
inline constexpr const char* reductions = "reductions";
// A frame drawn and written out (--frames), on the host clock.
inline constexpr const char* frame = "frame";
}  // namespace span

// The median of timings (the upper one of an even count); 0 for none.
double median(std::vector<double> v);

struct Span {
  std::string name;
  int step = 0;           // the step the span belongs to (0: before the first step)
  double start_ms = 0.0;  // host clock when its work was issued, ms since the profiler started
  double ms = 0.0;        // duration, ms
  std::string clock;      // how `ms` was measured ("CUDA events", "GL timer queries", "host clock")
};

class Profiler {
 public:
  Profiler();
  // Host clock, ms since the profiler was made.
  double now_ms() const;
  void set_step(int step) { step_ = step; }
  int step() const { return step_; }
  // Pipelines time their stages (events or queries around each pass, which the device runs
  // too) only in steps the profiler samples: all of them by default, else the windows of
  // kSampleWindow steps that begin at step 1, 1 + every x kSampleWindow, ... (a launch of up
  // to 8 steps, timed at its last step, ends in every window). Steps before the first (0) are
  // always sampled.
  static constexpr int kSampleWindow = 8;
  void sample_every(int windows) { every_ = windows; }
  bool sampled() const { return sampled(step_); }
  bool sampled(int step) const { return every_ <= 1 || step <= 0 || (step - 1) / kSampleWindow % every_ == 0; }
  // What the sampling covers, as a user reads it.
  std::string sampled_steps() const;
  // How many of steps 1..n it samples.
  int sampled_count(int n) const;
  void add(Span s);
  // The spans kept (all of them, unless streamed without keeping them).
  const std::vector<Span>& spans() const { return spans_; }
  // From now on each span is written to the CSV file `path` as it is added (name,step,start_ms,
  // ms,clock, one line per span) and kept in spans() only with `keep`; summary() needs neither.
  // A long run then holds one number per step and stage instead of its spans.
  void stream_csv(const std::string& path, bool keep);
  // Flushes and closes the streamed file (throws std::runtime_error when writing failed).
  void end_stream();

  // Per span name, in the order names first appear: the spans of one step summed (RK4 has
  // four force passes), then the median over the steps that have the span.
  struct Stage {
    std::string name, clock;
    int steps = 0;           // steps with this span
    int spans = 0;           // spans in all
    double median_ms = 0.0;  // per step
    double total_ms = 0.0;
  };
  std::vector<Stage> summary() const;

  // Chrome trace JSON (complete events; one track per clock), opens in Perfetto. GPU spans
  // are placed at the host time their work was issued, with their GPU-measured durations.
  void write_trace(const std::string& path) const;

 private:
  struct Totals {  // what summary() needs of one span name
    Stage stage;
    std::vector<double> per_step;  // summed ms of each step with the span
    int last_step = -1;
  };
  std::chrono::steady_clock::time_point t0_;
  std::vector<Span> spans_;
  std::vector<Totals> totals_;
  std::unique_ptr<std::ofstream> stream_;
  std::string stream_path_;
  int stream_error_ = 0;  // errno at the stream's first failed write
  bool keep_ = true;
  int step_ = 0;
  int every_ = 1;
};

// The profiler to time this step's stages with: `p` where it samples the step, else null.
inline Profiler* sampling(Profiler* p) { return p && p->sampled() ? p : nullptr; }

// An NVTX range named like the span it covers, for as long as the object lives.
class NvtxRange {
 public:
  explicit NvtxRange(const char* name);
  ~NvtxRange();
  NvtxRange(const NvtxRange&) = delete;
  NvtxRange& operator=(const NvtxRange&) = delete;
};

// A span timed by the host clock, with its NVTX range; records nothing when `p` is null.
class HostSpan {
 public:
  HostSpan(Profiler* p, const char* name);
  ~HostSpan();
  HostSpan(const HostSpan&) = delete;
  HostSpan& operator=(const HostSpan&) = delete;

 private:
  Profiler* p_;
  const char* name_;
  double start_ = 0.0;
  NvtxRange range_;
};

}  // namespace deformlab
