#include "interrupt.hpp"

#include <csignal>

namespace deformlab {

namespace {

volatile std::sig_atomic_t g_caught = 0;
constexpr int kSignals[2] = {SIGINT, SIGTERM};
void (*g_old[2])(int) = {};

void on_signal(int sig) {
  g_caught = sig;
  std::signal(sig, SIG_DFL);  // a second one ends the process at once
}

}  // namespace

InterruptCatcher::InterruptCatcher() {
  g_caught = 0;
  for (int k = 0; k < 2; ++k)
    if ((g_old[k] = std::signal(kSignals[k], on_signal)) == SIG_IGN) std::signal(kSignals[k], SIG_IGN);
}

InterruptCatcher::~InterruptCatcher() {
  for (int k = 0; k < 2; ++k) std::signal(kSignals[k], g_old[k]);
  g_caught = 0;
}

int InterruptCatcher::caught() { return g_caught; }

std::string signal_name(int sig) {
  return sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : "signal " + std::to_string(sig);
}

}  // namespace deformlab
