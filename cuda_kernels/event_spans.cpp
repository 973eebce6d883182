#include "event_spans.hpp"

#include <cuda_runtime.h>

#include <utility>

#include "check.cuh"

namespace deformlab::cuda {

EventTimer::~EventTimer() {
  for (std::size_t k = 0; k < begin_.size(); ++k) {
    cudaEventDestroy(begin_[k]);
    cudaEventDestroy(end_[k]);
  }
}

void EventTimer::resolve(std::size_t count) {
  for (std::size_t k = 0; k < count; ++k) {
    const std::size_t pair = pending_[k];
    check(cudaEventSynchronize(end_[pair]), "waiting for a timed span");
    float ms = 0.f;
    check(cudaEventElapsedTime(&ms, begin_[pair], end_[pair]), "reading a span's CUDA events");
    done_.push_back(double(ms));
    free_.push_back(pair);
  }
  pending_.erase(pending_.begin(), pending_.begin() + long(count));
}

void EventTimer::begin(CUstream_st* s) {
  if (pending_.size() >= 4096) resolve(pending_.size() - 64);  // the older ones are long finished
  if (free_.empty()) {
    cudaEvent_t b = nullptr, e = nullptr;
    check(cudaEventCreate(&b), "creating a timing event");
    check(cudaEventCreate(&e), "creating a timing event");
    begin_.push_back(b);
    end_.push_back(e);
    free_.push_back(begin_.size() - 1);
  }
  pending_.push_back(free_.back());
  free_.pop_back();
  check(cudaEventRecord(begin_[pending_.back()], s), "recording a span's start");
}

void EventTimer::end(CUstream_st* s) { check(cudaEventRecord(end_[pending_.back()], s), "recording a span's end"); }

std::vector<double> EventTimer::take() {
  resolve(pending_.size());
  return std::exchange(done_, {});
}

void EventSpans::begin(const Profiler& p, const char* name, CUstream_st* s, int steps) {
  pending_.push_back({name, p.step(), p.now_ms(), steps});
  range_.emplace(name);
  timer_.begin(s);
}

void EventSpans::end(CUstream_st* s) {
  timer_.end(s);
  range_.reset();
}

void EventSpans::collect(Profiler* p) {
  const std::vector<double> ms = timer_.take();
  for (std::size_t k = 0; k < pending_.size() && p; ++k) {
    const Pending& s = pending_[k];
    for (int q = 0; q < s.steps; ++q)
      p->add({s.name, s.step - s.steps + 1 + q, s.start_ms, ms[k] / s.steps, "CUDA events"});
  }
  pending_.clear();
}

EventStepTimer::~EventStepTimer() {
  for (cudaEvent_t e : events_) cudaEventDestroy(e);
}

void EventStepTimer::begin() {
  if (marks_ == 0) mark();
}

void EventStepTimer::end() {
  if (*launched_ == last_) return;
  mark();
  if (marks_ > 4096) resolve();
}

std::vector<double> EventStepTimer::take() {
  flush_();
  end();
  resolve();
  marks_ = 0;
  return std::exchange(done_, {});
}

void EventStepTimer::mark() {
  if (marks_ == events_.size()) {
    cudaEvent_t e = nullptr;
    check(cudaEventCreate(&e), "creating a timing event");
    events_.push_back(e);
    steps_.push_back(0);
  }
  steps_[marks_] = int(*launched_ - last_);
  last_ = *launched_;
  check(cudaEventRecord(events_[marks_++], s_), "recording a step's end");
}

void EventStepTimer::resolve() {
  if (marks_ == 0) return;
  check(cudaEventSynchronize(events_[marks_ - 1]), "waiting for the timed steps");
  for (std::size_t k = 1; k < marks_; ++k) {
    float ms = 0.f;
    check(cudaEventElapsedTime(&ms, events_[k - 1], events_[k]), "reading the step timer");
    done_.insert(done_.end(), steps_[k], double(ms) / steps_[k]);
  }
  std::swap(events_[0], events_[marks_ - 1]);
  marks_ = 1;
}

}  // namespace deformlab::cuda
