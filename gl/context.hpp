// The process-wide headless OpenGL context (EGL, no window system) and the GL helpers every
// GL stage shares: error checks named by stage, GPU or host timers, the shader sources.
#pragma once
#define EGL_NO_X11
#include <GL/glew.h>

#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/profiler.hpp"
#include "core/step_timer.hpp"

namespace deformlab::gl {

struct ContextOptions {
  int device = -1;     // EGL device index; -1: the first with EGL_NV_device_cuda, else the first
  bool debug = false;  // KHR_debug callback, every pass checked (also DEFORMLAB_GL_DEBUG=1)
};
// Must be called before the context is first used; throws std::invalid_argument if it is
// already made with other options.
void configure(const ContextOptions& o);

struct ContextInfo {
  std::string vendor, renderer, version, platform;  // platform: how EGL found the display
  bool software = false;  // a CPU rasteriser (llvmpipe): GL timer queries are not meaningful
  bool debug = false;
};

// Makes the context current, creating it on first use. Throws std::invalid_argument with
// one clear reason (no EGL display, no driver, GL older than 4.3 core) when it cannot.
const ContextInfo& context();
// Empty when a context can be made here, else the reason it cannot.
std::string unavailable_reason();
// Takes the context current on this thread (a window's, made and kept by a window system) as
// the process's context instead of the headless one; `platform` names it for manifests. Call
// before any other GL use; throws std::invalid_argument when it is older than 4.3 core.
void adopt_current_context(const std::string& platform);
// True once a context exists (so that manifests can report it without creating one).
bool context_created();

// Throws std::runtime_error naming `stage` if GL reports an error (all pending errors listed).
void check(std::string_view stage);
// Checks after each pass only in debug mode (the per-step check() always runs).
void check_debug(std::string_view stage);

// An embedded shader file (DEFORMLAB_SHADER_DIR, if set, overrides the embedded copies).
std::string shader_file(std::string_view name);

// Times spans of GL work: a GL_TIMESTAMP query at each end on a GPU (taken once the commands
// before it are done), the host clock after glFinish on a software rasteriser (whose queries
// read about 1 ns). Spans of one timer may not nest; several timers may.
class Timer {
 public:
  Timer();
  ~Timer();
  Timer(const Timer&) = delete;
  Timer& operator=(const Timer&) = delete;
  void begin();
  void end();
  // Finished spans since the last call, ms, in order (waits for pending queries).
  std::vector<double> take();
  std::string method() const;

 private:
  void stamp();                    // a timestamp query after the commands issued so far
  void collect(std::size_t keep);  // resolves all but the newest `keep` queries
  bool software_;
  std::vector<unsigned> free_, pending_;  // pending: begin, end, begin, end, ...
  std::vector<double> done_;
  std::chrono::steady_clock::time_point t0_;
};

// Each step between the two ends of a Timer.
class QueryStepTimer final : public StepTimer {
 public:
  void begin() override { t_.begin(); }
  void end() override { t_.end(); }
  std::vector<double> take() override { return t_.take(); }
  std::string clock() const override { return t_.method(); }

 private:
  Timer t_;
};

// Profiler spans of GL work, timed by a Timer and handed to the profiler once resolved
// (resolving waits for the work). Spans may not nest.
class TimerSpans {
 public:
  // A span of the GL commands issued between begin and end, at the profiler's current step
  // and host time, with an NVTX range of the same name over the host side.
  void begin(const Profiler& p, const char* name);
  void end();
  // Waits for the pending spans and adds them to `p` (null: drops them).
  void collect(Profiler* p);
  std::size_t pending() const { return pending_.size(); }
  std::string method() const;

 private:
  struct Pending {
    const char* name;
    int step;
    double start_ms;
  };
  std::unique_ptr<Timer> timer_;  // made on first use
  std::vector<Pending> pending_;
  std::optional<NvtxRange> range_;
};

}  // namespace deformlab::gl
