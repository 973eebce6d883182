#include "pipeline.hpp"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "timed_work.hpp"

namespace deformlab {

std::vector<double> timed_steps(Pipeline& p, StepTimer& t, int steps) {
  return timed_calls(t, [&] { p.step(); }, steps);
}

WarmUp warm_up(const std::function<void()>& step, const std::function<void()>& drain, double min_ms) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  const auto elapsed_ms = [&] { return std::chrono::duration<double, std::milli>(clock::now() - start).count(); };
  WarmUp w;
  // Batches double up to 256 steps between waits, which keeps fast steps back to back on the device, but take
  // no more steps than the time left needs at the mean step so far: the warm-up ends within about a step of min_ms.
  for (int batch = 1; (w.ms = elapsed_ms()) < min_ms;) {
    for (int k = 0; k < batch; ++k) step();
    drain();
    w.steps += batch;
    const double now = elapsed_ms(), needed = std::ceil((min_ms - now) * w.steps / std::max(now, 1e-6));
    batch = int(std::clamp(needed, 1.0, double(std::min(2 * batch, 256))));
  }
  return w;
}

WarmUp warm_up_from_rest(Pipeline& p, const Model& m, double min_ms) {
  const State rest = rest_state(m);
  p.set_state(rest);
  const WarmUp w = warm_up([&] { p.step(); }, [&] { p.max_displacement(); }, min_ms);
  p.set_state(rest);
  return w;
}

int steps_spanning(double ms, double step_ms, int min_steps, int multiple) {
  const double n = std::max(double(std::max(min_steps, 1)), std::ceil(ms / std::max(step_ms, 1e-6)));
  const double m = std::max(multiple, 1);
  return int(std::min(std::ceil(n / m) * m, 1e6));
}

bool on_gpu(const PipelineEntry& e) { return e.traits.force != Engine::cpu || e.traits.update != Engine::cpu; }

const char* to_string(Math m) { return m == Math::fast ? "fast" : "exact"; }

Math math_option(const PipelineOptions& o) {
  const auto it = o.find("math");
  if (it == o.end() || it->second == "exact") return Math::exact;
  if (it->second == "fast") return Math::fast;
  throw std::invalid_argument("option math '" + it->second + "' is not exact or fast");
}

std::optional<std::int64_t> option_count(std::string_view s, std::int64_t most) {
  if (s.empty() || s.front() < '1' || s.front() > '9') return std::nullopt;
  std::int64_t v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc{} || end != s.data() + s.size() || v > most) return std::nullopt;
  return v;
}

CpuMatch cpu_match(const PipelineEntry& e, const PipelineOptions& o) {
  return math_option(o) == Math::fast ? CpuMatch::rounding : e.traits.cpu_match;
}

bool reads_option(const PipelineEntry& e, const std::string& name) {
  return std::find(e.options.begin(), e.options.end(), name) != e.options.end();
}

void check_options(const PipelineEntry& e, const PipelineOptions& o) {
  for (const auto& [name, value] : o)
    if (!reads_option(e, name))
      throw std::invalid_argument("option '" + name + "' is not an option of " + e.name +
                                  (e.options.empty() ? " (it has none)" : ""));
  if (!e.read_options) return;
  try {
    e.read_options(o);
  } catch (const std::invalid_argument& x) {
    throw std::invalid_argument(e.name + ": " + x.what());
  }
}

void check_options(const PipelineEntry& e, const PipelineOptions& o, Topology t) {
  check_options(e, o);
  if (!e.idle_option) return;
  if (const std::string why = e.idle_option(o, t); !why.empty()) throw std::invalid_argument(e.name + ": " + why);
}

void PipelineRegistry::add(PipelineEntry e) {
  if (find(e.name)) throw std::logic_error("pipeline registered twice: " + e.name);
  entries_.push_back(std::move(e));
}

const PipelineEntry* PipelineRegistry::find(const std::string& name) const {
  for (const auto& e : entries_)
    if (e.name == name) return &e;
  return nullptr;
}

std::string PipelineRegistry::names() const {
  std::string s;
  for (const auto& e : entries_) s += (s.empty() ? "" : ", ") + e.name;
  return s;
}

namespace {

// host_memory_shortfall; with no `e`, the model and its state alone.
std::string shortfall(const ModelSize& m, const PipelineEntry* e, Integrator i, const PipelineOptions& o,
                      const PipelineEntry* reference) {
  constexpr std::int64_t kMaxNodes = std::int64_t(1) << 30;
  auto own = [&](const PipelineEntry* p) { return p && p->footprint ? p->footprint(m, i, o).host : 0; };
  const std::int64_t model = model_host_bytes(m), state = state_host_bytes(m.nodes), pipe = own(e);
  const std::int64_t ref = reference ? own(reference) + state : 0;
  const std::int64_t need = model + pipe + state + ref;
  const auto limit = host_memory_limit();
  if (m.nodes <= kMaxNodes && (!limit || need <= limit->bytes)) return {};
  std::ostringstream os;
  os << "a model of " << m.nodes << " nodes";
  if (m.nodes > kMaxNodes) {
    os << " exceeds the limit of 2^30 nodes";
    return os.str();
  }
  if (e) os << " on " << e->name;
  os << " needs " << (e ? "" : "at least ") << gib(need) << " of host memory (model " << gib(model);
  if (e) os << ", pipeline " << gib(pipe);
  os << ", state " << gib(state);
  if (reference) os << ", " << reference->name << " pipeline and state " << gib(ref);
  os << "); " << limit->name << " leaves " << gib(limit->bytes);
  return os.str();
}

}  // namespace

std::string host_memory_shortfall(const ModelSize& m, const PipelineEntry& e, Integrator i,
                                  const PipelineOptions& o, const PipelineEntry* reference) {
  return shortfall(m, &e, i, o, reference);
}

std::string model_memory_shortfall(const ModelSize& m, Integrator i, const PipelineEntry* reference) {
  return shortfall(m, nullptr, i, {}, reference);
}

}  // namespace deformlab
