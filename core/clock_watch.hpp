// ClockWatch: the GPU's SM clock while timed work runs, and what held it down. A GPU under
// sustained load lowers its clock at its power cap (the H100 at 700 W: 1980 MHz down to as low
// as 1410), so one scene timed twice can differ by the clock alone; a time shown with its clock
// says which. Read through NVML, the driver's management library, loaded at run time: there
// is no build or link dependency, and where the driver is absent the watch has no samples.
#pragma once
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

namespace deformlab {

// The reasons NVML gives for a clock below the top one that lower it under load (its
// "clocks event reasons"): the power cap, thermal and hardware slowdowns; not idling or
// application clock settings.
std::string slowdown_names(std::uint64_t reasons);

struct ClockSample {
  double t_ms = 0;            // host clock, ms since the watch started
  unsigned sm_mhz = 0;        // SM clock
  std::uint64_t reasons = 0;  // NVML's active clocks event reasons, slowdowns only
};

struct ClockSummary {
  std::string device;  // the watched GPU's name and PCI bus id; empty without NVML
  int samples = 0;
  unsigned sm_mhz_min = 0, sm_mhz_median = 0, sm_mhz_max = 0;
  unsigned sm_mhz_top = 0;     // the device's highest SM clock
  double slowed = 0;           // fraction of samples with a slowdown active
  std::uint64_t reasons = 0;   // every slowdown seen (NVML bits)
  bool watched() const { return samples > 0; }
};

// One line for a user: "SM clock 1485-1980 MHz (median 1980, top 1980); power cap in 12% of
// 41 samples (NVML, every 5 ms, DEVICE)", or why there is none.
std::string describe(const ClockSummary& s);
// For manifests and cells: the summary's fields, the slowdowns by name and what the clock is;
// null where nothing was watched.
nlohmann::json to_json(const ClockSummary& s);

// to_json's inverse: an unwatched summary for null.
ClockSummary clock_summary(const nlohmann::json& j);

// The clocks of many timed cases (a bench's, an experiment's cells): the range of their median
// SM clocks and each case timed while a slowdown held the clock down.
class ClockTally {
 public:
  void add(const std::string& label, const ClockSummary& c);
  // "the cases' median SM clocks 1485-1980 MHz; 2 of 30 cases timed while a slowdown held the
  // clock down: LABEL (power cap in 40% of samples, 1410-1980 MHz); ..." or "...; no slowdown
  // while any of the 30 cases was timed" ("" when none was watched), naming cases by `noun`; with
  // `one_per_line` each slowed case on a line of its own, indented.
  std::string describe(const std::string& noun, bool one_per_line = false) const;
  bool empty() const { return watched_ == 0; }

 private:
  int watched_ = 0;
  unsigned lo_ = ~0u, hi_ = 0;
  std::vector<std::string> slowed_;
};

class ClockWatch {
 public:
  // Starts sampling the GPU with PCI bus id `pci_bus_id` (empty: NVML's first device) every
  // `period_ms` on a thread of its own; does nothing where NVML cannot be loaded.
  explicit ClockWatch(const std::string& pci_bus_id = {}, int period_ms = kPeriodMs);
  ~ClockWatch();
  ClockWatch(const ClockWatch&) = delete;
  ClockWatch& operator=(const ClockWatch&) = delete;
  // Stops sampling (after one last sample) and summarises what was seen since the start.
  ClockSummary stop();
  // The samples so far, in order.
  std::vector<ClockSample> samples() const;
  // Whether NVML is there and sees a GPU.
  static bool available();
  static constexpr int kPeriodMs = 5;

 private:
  void sample();
  struct Nvml;
  std::shared_ptr<const Nvml> nvml_;
  void* device_ = nullptr;
  std::string name_;
  unsigned top_mhz_ = 0;
  double start_ = 0;
  mutable std::mutex mutex_;
  std::vector<ClockSample> samples_;
  std::atomic<bool> running_{false};
  std::thread thread_;
};

}  // namespace deformlab
