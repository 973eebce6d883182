#include "event_spans.hpp"

#include <cuda_runtime.h>

#include "check.cuh"

namespace deformlab::cuda {

EventSpans::~EventSpans() {
  for (std::size_t k = 0; k < begin_.size(); ++k) {
    cudaEventDestroy(begin_[k]);
    cudaEventDestroy(end_[k]);
  }
}

void EventSpans::begin(const Profiler& p, const char* name, CUstream_st* s) {
  if (free_.empty()) {
    cudaEvent_t b = nullptr, e = nullptr;
    check(cudaEventCreate(&b), "creating a timing event");
    check(cudaEventCreate(&e), "creating a timing event");
    begin_.push_back(b);
    end_.push_back(e);
    free_.push_back(begin_.size() - 1);
  }
  const std::size_t k = free_.back();
  free_.pop_back();
  pending_.push_back({name, p.step(), p.now_ms(), k});
  range_.emplace(name);
  check(cudaEventRecord(begin_[k], s), "recording a span's start");
}

void EventSpans::end(CUstream_st* s) {
  check(cudaEventRecord(end_[pending_.back().pair], s), "recording a span's end");
  range_.reset();
}

void EventSpans::collect(Profiler* p) {
  for (const Pending& s : pending_) {
    check(cudaEventSynchronize(end_[s.pair]), "waiting for a timed span");
    float ms = 0.f;
    check(cudaEventElapsedTime(&ms, begin_[s.pair], end_[s.pair]), "reading a span's CUDA events");
    if (p) p->add({s.name, s.step, s.start_ms, double(ms), "CUDA events"});
    free_.push_back(s.pair);
  }
  pending_.clear();
}

}  // namespace deformlab::cuda
