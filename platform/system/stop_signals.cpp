#include "platform/system/stop_signals.hpp"

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>

namespace vp::platform {

namespace {

std::atomic<int> gSignal{0};
std::atomic<bool> gStop{false};
struct sigaction gPreviousInt {};
struct sigaction gPreviousTerm {};

void onSignal(int signal) {
  if (gStop.exchange(true)) {
    // Second request: give the default action back (async-signal-safe calls only).
    struct sigaction dfl {};
    dfl.sa_handler = SIG_DFL;
    ::sigaction(signal, &dfl, nullptr);
  }
  gSignal.store(signal);
}

}  // namespace

bool StopSignals::install(std::string* why) {
  struct sigaction action {};
  action.sa_handler = &onSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // no SA_RESTART: a blocking call returns EINTR and the loop sees the stop
  if (::sigaction(SIGINT, &action, &gPreviousInt) != 0 ||
      ::sigaction(SIGTERM, &action, &gPreviousTerm) != 0) {
    if (why)
      *why = std::string("sigaction(SIGINT/SIGTERM): ") + std::strerror(errno);
    return false;
  }
  installed_ = true;
  return true;
}

StopSignals::~StopSignals() {
  if (installed_) {
    ::sigaction(SIGINT, &gPreviousInt, nullptr);
    ::sigaction(SIGTERM, &gPreviousTerm, nullptr);
  }
}

bool StopSignals::stopRequested() {
  return gStop.load(std::memory_order_relaxed);
}
int StopSignals::lastSignal() {
  return gSignal.load();
}
void StopSignals::requestStop() {
  gStop.store(true);
}

}  // namespace vp::platform
