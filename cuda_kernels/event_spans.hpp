// Timing of work queued on CUDA streams by pairs of CUDA events: EventTimer times spans,
// EventSpans hands them to the profiler with their names.
#pragma once
#include <cstddef>
#include <optional>
#include <vector>

#include "core/profiler.hpp"

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

}  // namespace deformlab::cuda
