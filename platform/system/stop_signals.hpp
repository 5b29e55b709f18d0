// platform/system/stop_signals: SIGINT and SIGTERM as a stop request the loop polls.
//
// Contract: while a StopSignals object is installed (install() to destruction), SIGINT and
// SIGTERM set a process-wide atomic flag instead of killing the process, and the previous
// handlers come back on destruction. The loop checks stopRequested() once per iteration, and
// every wait on the loop's clock polls it (platform/clock: a long paced wait ends within
// kStopPoll_ns, whichever thread the signal interrupted), then shuts down cleanly (every
// queued buffer returned, DDS instances disposed, files closed).
// A second signal while a stop is pending restores the default action, so a hung shutdown
// can still be interrupted. One instance per process.
#pragma once

#include <string>

namespace vp::platform {

class StopSignals {
 public:
  StopSignals() = default;
  ~StopSignals();
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

  bool install(std::string* why);
  static bool stopRequested();
  static int lastSignal();    // 0 when none
  static void requestStop();  // the same as a signal, for tests and internal fatal errors

 private:
  bool installed_ = false;
};

}  // namespace vp::platform
