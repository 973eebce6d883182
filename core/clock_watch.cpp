#include "clock_watch.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <chrono>
#include <sstream>

#include "profiler.hpp"

namespace deformlab {

namespace {

// NVML's C interface as its reference documents it: calls return 0 on success; a device is an
// opaque handle.
using Device = void*;
constexpr int kSmClock = 1;  // NVML_CLOCK_SM
struct Slowdown {
  std::uint64_t bit;
  const char* name;
};
constexpr Slowdown kSlowdowns[] = {{0x4, "power cap"},
                                   {0x8, "hardware slowdown"},
                                   {0x20, "thermal slowdown (software)"},
                                   {0x40, "thermal slowdown (hardware)"},
                                   {0x80, "power brake"}};

double now_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// "power cap in 25%": the slowdowns seen and the share of samples with one.
std::string slowed_share(const ClockSummary& s) {
  return slowdown_names(s.reasons) + " in " + std::to_string(int(100 * s.slowed + 0.5)) + "%";
}

}  // namespace

struct ClockWatch::Nvml {
  void* lib = nullptr;
  int (*init)() = nullptr;
  int (*shutdown)() = nullptr;
  int (*by_index)(unsigned, Device*) = nullptr;
  int (*by_bus_id)(const char*, Device*) = nullptr;
  int (*name)(Device, char*, unsigned) = nullptr;
  int (*clock)(Device, int, unsigned*) = nullptr;
  int (*max_clock)(Device, int, unsigned*) = nullptr;
  int (*reasons)(Device, unsigned long long*) = nullptr;

  template <class F>
  bool find(F& f, const char* symbol) {
    f = reinterpret_cast<F>(dlsym(lib, symbol));
    return f != nullptr;
  }
  Nvml() {
    lib = dlopen("libnvidia-ml.so.1", RTLD_NOW | RTLD_LOCAL);
    if (!lib) return;
    // Drivers before 535 name the reasons call by its older name.
    const bool found = find(init, "nvmlInit_v2") && find(shutdown, "nvmlShutdown") &&
                       find(by_index, "nvmlDeviceGetHandleByIndex_v2") &&
                       find(by_bus_id, "nvmlDeviceGetHandleByPciBusId_v2") && find(name, "nvmlDeviceGetName") &&
                       find(clock, "nvmlDeviceGetClockInfo") && find(max_clock, "nvmlDeviceGetMaxClockInfo") &&
                       (find(reasons, "nvmlDeviceGetCurrentClocksEventReasons") ||
                        find(reasons, "nvmlDeviceGetCurrentClocksThrottleReasons"));
    if (!found || init() != 0) {
      dlclose(lib);
      lib = nullptr;
    }
  }
  ~Nvml() {
    if (!lib) return;
    shutdown();
    dlclose(lib);
  }
  static std::shared_ptr<const Nvml> get() {
    static const auto nvml = std::make_shared<const Nvml>();
    return nvml->lib ? nvml : nullptr;
  }
};

std::string slowdown_names(std::uint64_t reasons) {
  std::string s;
  for (const Slowdown& d : kSlowdowns)
    if (reasons & d.bit) s += (s.empty() ? "" : ", ") + std::string(d.name);
  return s;
}

std::string describe(const ClockSummary& s) {
  if (!s.watched()) return "SM clock not read (no NVIDIA driver's NVML here)";
  std::ostringstream os;
  os << "SM clock " << s.sm_mhz_min << "-" << s.sm_mhz_max << " MHz (median " << s.sm_mhz_median << ", top "
     << s.sm_mhz_top << "); " << (s.slowed > 0 ? slowed_share(s) : "no slowdown in any") << " of " << s.samples
     << " samples (NVML, every " << ClockWatch::kPeriodMs << " ms, " << s.device << ")";
  return os.str();
}

nlohmann::json to_json(const ClockSummary& s) {
  if (!s.watched()) return nullptr;
  return {{"device", s.device},
          {"samples", s.samples},
          {"sm_mhz_min", s.sm_mhz_min},
          {"sm_mhz_median", s.sm_mhz_median},
          {"sm_mhz_max", s.sm_mhz_max},
          {"sm_mhz_top", s.sm_mhz_top},
          {"slowed_fraction", s.slowed},
          {"slowdowns", slowdown_names(s.reasons)},
          {"slowdown_bits", s.reasons},
          {"clock", "NVML, sampled every " + std::to_string(ClockWatch::kPeriodMs) + " ms on the host"}};
}

ClockSummary clock_summary(const nlohmann::json& j) {
  ClockSummary s;
  if (j.is_null()) return s;
  s.device = j.at("device").get<std::string>();
  s.samples = j.at("samples").get<int>();
  s.sm_mhz_min = j.at("sm_mhz_min").get<unsigned>();
  s.sm_mhz_median = j.at("sm_mhz_median").get<unsigned>();
  s.sm_mhz_max = j.at("sm_mhz_max").get<unsigned>();
  s.sm_mhz_top = j.at("sm_mhz_top").get<unsigned>();
  s.slowed = j.at("slowed_fraction").get<double>();
  s.reasons = j.at("slowdown_bits").get<std::uint64_t>();
  return s;
}

void ClockTally::add(const std::string& label, const ClockSummary& c) {
  if (!c.watched()) return;
  ++watched_;
  lo_ = std::min(lo_, c.sm_mhz_median);
  hi_ = std::max(hi_, c.sm_mhz_median);
  if (c.slowed > 0)
    slowed_.push_back(label + " (" + slowed_share(c) + " of samples, " + std::to_string(c.sm_mhz_min) + "-" +
                      std::to_string(c.sm_mhz_max) + " MHz)");
}

std::string ClockTally::describe(const std::string& noun, bool one_per_line) const {
  if (watched_ == 0) return "";
  std::ostringstream os;
  os << "the " << noun << "s' median SM clocks " << lo_;
  if (hi_ != lo_) os << "-" << hi_;
  if (slowed_.empty()) {
    os << " MHz; no slowdown while any of the " << watched_ << " " << noun << "s was timed";
    return os.str();
  }
  os << " MHz; " << slowed_.size() << " of " << watched_ << " " << noun << "s timed while a slowdown held the clock down";
  const char* sep = one_per_line ? "\n  " : "; ";
  os << (one_per_line ? ":\n  " : ": ");
  for (std::size_t k = 0; k < slowed_.size(); ++k) os << (k ? sep : "") << slowed_[k];
  return os.str();
}

bool ClockWatch::available() {
  const auto nvml = Nvml::get();
  Device d = nullptr;
  return nvml && nvml->by_index(0, &d) == 0;
}

ClockWatch::ClockWatch(const std::string& pci_bus_id, int period_ms) : nvml_(Nvml::get()), start_(now_ms()) {
  if (!nvml_) return;
  Device d = nullptr;
  if ((pci_bus_id.empty() ? nvml_->by_index(0, &d) : nvml_->by_bus_id(pci_bus_id.c_str(), &d)) != 0) return;
  device_ = d;
  char name[96] = {};
  nvml_->name(d, name, sizeof name);
  name_ = std::string(name) + (pci_bus_id.empty() ? ", NVML device 0" : ", " + pci_bus_id);
  nvml_->max_clock(d, kSmClock, &top_mhz_);
  sample();
  running_ = true;
  thread_ = std::thread([this, period_ms] {
    while (running_) {
      std::this_thread::sleep_for(std::chrono::milliseconds(period_ms));
      sample();
    }
  });
}

ClockWatch::~ClockWatch() { stop(); }

void ClockWatch::sample() {
  ClockSample s;
  s.t_ms = now_ms() - start_;
  unsigned long long reasons = 0;
  if (nvml_->clock(device_, kSmClock, &s.sm_mhz) != 0 || nvml_->reasons(device_, &reasons) != 0) return;
  for (const Slowdown& d : kSlowdowns) s.reasons |= reasons & d.bit;
  const std::lock_guard lock(mutex_);
  samples_.push_back(s);
}

std::vector<ClockSample> ClockWatch::samples() const {
  const std::lock_guard lock(mutex_);
  return samples_;
}

ClockSummary ClockWatch::stop() {
  if (running_.exchange(false)) {
    thread_.join();
    sample();
  }
  ClockSummary sum;
  const std::vector<ClockSample> all = samples();
  if (all.empty()) return sum;
  sum.device = name_;
  sum.samples = int(all.size());
  sum.sm_mhz_top = top_mhz_;
  std::vector<double> mhz;
  int slowed = 0;
  for (const ClockSample& s : all) {
    mhz.push_back(s.sm_mhz);
    sum.reasons |= s.reasons;
    slowed += s.reasons != 0;
  }
  const auto [lo, hi] = std::minmax_element(mhz.begin(), mhz.end());
  sum.sm_mhz_min = unsigned(*lo);
  sum.sm_mhz_max = unsigned(*hi);
  sum.sm_mhz_median = unsigned(median(mhz));
  sum.slowed = double(slowed) / double(all.size());
  return sum;
}

}  // namespace deformlab
