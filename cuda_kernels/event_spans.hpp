// Profiler spans of work queued on a CUDA stream, timed by CUDA events and handed to the
// profiler once resolved (resolving waits for the work, so it happens in batches).
#pragma once
#include <cstddef>
#include <optional>
#include <vector>

#include "core/profiler.hpp"

struct CUstream_st;
struct CUevent_st;

namespace deformlab::cuda {

class EventSpans {
 public:
  EventSpans() = default;
  EventSpans(const EventSpans&) = delete;
  EventSpans& operator=(const EventSpans&) = delete;
  ~EventSpans();

  // A span of the work queued on `s` between begin and end, at the profiler's current step
  // and host time, with an NVTX range of the same name over the host side. Spans may not nest.
  void begin(const Profiler& p, const char* name, CUstream_st* s);
  void end(CUstream_st* s);
  // Waits for the work of the pending spans and adds them to `p` (null: drops them).
  void collect(Profiler* p);
  std::size_t pending() const { return pending_.size(); }

 private:
  struct Pending {
    const char* name;
    int step;
    double start_ms;
    std::size_t pair;
  };
  std::vector<CUevent_st*> begin_, end_;  // event pairs, reused
  std::vector<std::size_t> free_;
  std::vector<Pending> pending_;
  std::optional<NvtxRange> range_;
};

}  // namespace deformlab::cuda
