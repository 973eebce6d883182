// SIGINT and SIGTERM during long work: caught while an InterruptCatcher lives and recorded, so
// that the work stops at its next step, cleans up and says so. A second signal ends the process
// at once; a signal the process ignores (nohup) stays ignored.
#pragma once
#include <stdexcept>
#include <string>

namespace deformlab {

class InterruptCatcher {
 public:
  InterruptCatcher();
  ~InterruptCatcher();
  InterruptCatcher(const InterruptCatcher&) = delete;
  InterruptCatcher& operator=(const InterruptCatcher&) = delete;
  // The signal caught since the catcher was made, 0 if none (or if no catcher lives).
  static int caught();
};

// "SIGINT", "SIGTERM", else "signal N".
std::string signal_name(int sig);

// Thrown by work that stopped for a caught signal, its message saying where ("SIGINT at step
// 12 of 100"); the process's exit code is then 128 + signal.
struct Interrupted : std::runtime_error {
  Interrupted(int sig, const std::string& what) : std::runtime_error(what), signal(sig) {}
  int signal;
};

}  // namespace deformlab
