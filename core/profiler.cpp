#include "profiler.hpp"

#include <algorithm>
#include <fstream>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "write_error.hpp"

#if DEFORMLAB_NVTX
#include <nvtx3/nvToolsExt.h>
#endif

namespace deformlab {

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
  return v[v.size() / 2];
}

Profiler::Profiler() : t0_(std::chrono::steady_clock::now()) {}

std::string Profiler::sampled_steps() const {
  if (every_ <= 1) return "every step";
  return "steps 1-" + std::to_string(kSampleWindow) + " of every " + std::to_string(every_ * kSampleWindow);
}

int Profiler::sampled_count(int n) const {
  if (every_ <= 1) return n;
  const int period = kSampleWindow * every_;
  return n / period * kSampleWindow + std::min(n % period, kSampleWindow);
}

double Profiler::now_ms() const {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0_).count();
}

namespace {

void write_row(std::ostream& f, const Span& s) {
  f << s.name << ',' << s.step << ',' << s.start_ms << ',' << s.ms << ",\"" << s.clock << "\"\n";
}

}  // namespace

void Profiler::add(Span s) {
  auto it = std::find_if(totals_.begin(), totals_.end(), [&](const Totals& t) { return t.stage.name == s.name; });
  if (it == totals_.end()) {
    totals_.push_back({Stage{s.name, s.clock}});
    it = totals_.end() - 1;
  } else if (it->stage.clock != s.clock && it->stage.clock.find(s.clock) == std::string::npos) {
    it->stage.clock += ", " + s.clock;
  }
  ++it->stage.spans;
  it->stage.total_ms += s.ms;
  if (s.step == it->last_step) {
    it->per_step.back() += s.ms;  // RK4's four force passes in one step
  } else {
    it->per_step.push_back(s.ms);
    it->last_step = s.step;
  }
  if (stream_) {
    write_row(*stream_, s);
    if (!*stream_ && !stream_error_) stream_error_ = errno;  // the first failed write's reason, if any
  }
  if (keep_) spans_.push_back(std::move(s));
}

std::vector<Profiler::Stage> Profiler::summary() const {
  std::vector<Stage> out;
  for (const Totals& t : totals_) {
    Stage g = t.stage;
    g.steps = int(t.per_step.size());
    g.median_ms = median(t.per_step);
    out.push_back(std::move(g));
  }
  return out;
}

void Profiler::stream_csv(const std::string& path, bool keep) {
  stream_ = std::make_unique<std::ofstream>(path);
  if (!*stream_) throw write_error(path);
  *stream_ << "name,step,start_ms,ms,clock\n" << std::setprecision(9);
  stream_path_ = path;
  keep_ = keep;
}

void Profiler::end_stream() {
  if (!stream_) return;
  errno = 0;
  stream_->close();
  const bool ok = bool(*stream_);
  stream_.reset();
  if (!ok) throw write_error(stream_path_, stream_error_ ? stream_error_ : errno);
}

void Profiler::write_trace(const std::string& path) const {
  // One track (tid) per clock, named by metadata events.
  std::vector<std::string> clocks;
  nlohmann::json events = nlohmann::json::array();
  for (const Span& s : spans_) {
    auto it = std::find(clocks.begin(), clocks.end(), s.clock);
    if (it == clocks.end()) {
      clocks.push_back(s.clock);
      it = clocks.end() - 1;
      events.push_back({{"name", "thread_name"}, {"ph", "M"}, {"pid", 1}, {"tid", int(it - clocks.begin()) + 1},
                        {"args", {{"name", s.clock}}}});
    }
    events.push_back({{"name", s.name},
                      {"cat", s.clock},
                      {"ph", "X"},
                      {"pid", 1},
                      {"tid", int(it - clocks.begin()) + 1},
                      {"ts", s.start_ms * 1000.0},
                      {"dur", s.ms * 1000.0},
                      {"args", {{"step", s.step}}}});
  }
  write_file(path, [&](std::ostream& f) {
    f << nlohmann::json{{"traceEvents", events}, {"displayTimeUnit", "ms"}}.dump() << "\n";
  });
}

#if DEFORMLAB_NVTX
NvtxRange::NvtxRange(const char* name) { nvtxRangePushA(name); }
NvtxRange::~NvtxRange() { nvtxRangePop(); }
#else
NvtxRange::NvtxRange(const char*) {}
NvtxRange::~NvtxRange() = default;
#endif

HostSpan::HostSpan(Profiler* p, const char* name)
    : p_(p), name_(name), start_(p ? p->now_ms() : 0.0), range_(name) {}

HostSpan::~HostSpan() {
  if (p_) p_->add({name_, p_->step(), start_, p_->now_ms() - start_, "host clock"});
}

}  // namespace deformlab
