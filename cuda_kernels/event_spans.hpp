// Timing of work queued on CUDA streams by CUDA events: EventTimer times spans by pairs of
// events, EventSpans hands them to the profiler with their names, EventStepTimer times steps
// by one event at each step's end.
#pragma once
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/profiler.hpp"
#include "core/step_timer.hpp"

struct CUstream_st;
struct CUevent_st;

namespace deformlab::cuda {

// Spans of the work queued on a stream between begin and end, timed by a pair of events each
// (pairs are reused). Spans of one timer may not nest; several timers may.
class EventTimer {
 public:
  EventTimer() = default;
  EventTimer(const EventTimer&) = delete;
  EventTimer& operator=(const EventTimer&) = delete;
  ~EventTimer();
  void begin(CUstream_st* s);
  void end(CUstream_st* s);
  // ms of the spans ended since the last call, in order (waits for their work).
  std::vector<double> take();

 private:
  void resolve(std::size_t count);  // the oldest `count` pending spans into done_
  std::vector<CUevent_st*> begin_, end_;  // event pairs
  std::vector<std::size_t> free_, pending_;
  std::vector<double> done_;  // resolved, not yet taken
};

class EventSpans {
 public:
  // A span of the work queued on `s` between begin and end, at the profiler's current step
  // and host time, with an NVTX range of the same name over the host side. Spans may not nest.
  // Work for `steps` steps (cuda-temporal's launch: the current step and those before it)
  // gives each of them an equal share.
  void begin(const Profiler& p, const char* name, CUstream_st* s, int steps = 1);
  void end(CUstream_st* s);
  // Waits for the work of the pending spans and adds them to `p` (null: drops them).
  void collect(Profiler* p);
  std::size_t pending() const { return pending_.size(); }

 private:
  struct Pending {
    const char* name;
    int step;
    double start_ms;
    int steps;
  };
  EventTimer timer_;
  std::vector<Pending> pending_;
  std::optional<NvtxRange> range_;
};

// Steps timed back to back by one CUDA event at each step's end (and one before the first step
// after a take): a step's time runs from the end of the step before to its own, as the device
// ran them, idle time between them included. A pair of events around each step would instead
// add the device's launch latency to every step replayed from a graph (10 us of 130 at 2048^2
// on the H100). cuda-temporal queues k steps in one launch: an event then ends k steps, each
// timed as 1/k of the interval (`launched` counts the steps queued on the device; `flush`
// queues those still held back).
class EventStepTimer final : public StepTimer {
 public:
  EventStepTimer(CUstream_st* s, const std::int64_t* launched, std::function<void()> flush)
      : s_(s), launched_(launched), flush_(std::move(flush)) {}
  EventStepTimer(const EventStepTimer&) = delete;
  EventStepTimer& operator=(const EventStepTimer&) = delete;
  ~EventStepTimer() override;
  void begin() override;
  void end() override;
  std::vector<double> take() override;
  std::string clock() const override { return "CUDA events"; }

 private:
  void mark();
  void resolve();  // the steps marked so far into done_; the last mark stays as the next step's start
  CUstream_st* s_;
  const std::int64_t* launched_;
  std::int64_t last_ = 0;  // *launched_ at the last mark
  std::function<void()> flush_;
  std::vector<CUevent_st*> events_;
  std::vector<int> steps_;  // steps ended by each event
  std::size_t marks_ = 0;  // events recorded since the last resolve
  std::vector<double> done_;
};

}  // namespace deformlab::cuda
