#include "ehc_common/stop_signal.h"

#include <atomic>
#include <csignal>

namespace ehc_common {

namespace {
std::atomic<int> g_stop_signal{0};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void onStopSignal(int signal) {
  g_stop_signal.store(signal);
  std::signal(SIGINT, SIG_DFL);  // the next one of either kind ends the process
  std::signal(SIGTERM, SIG_DFL);
}
}  // namespace

void installStopSignals() {
  struct sigaction sa {};
  sa.sa_handler = onStopSignal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

bool stopRequested() { return g_stop_signal.load() != 0; }
int stopSignal() { return g_stop_signal.load(); }
int stopExitCode() { return stopRequested() ? 128 + stopSignal() : 0; }
void requestStop(int signal) { g_stop_signal.store(signal); }

}  // namespace ehc_common
