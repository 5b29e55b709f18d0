// firmware_app/periodic_reports: what the loop reports on a clock rather than per frame: the
// drone status (dds.status_rate_hz) and the occupancy grid (dds.occupancy_rate_hz) over DDS,
// the systemd watchdog kick (half the unit's WatchdogSec) and the statistics line
// (app.stats_period_s, on stderr and as systemd STATUS=).
//
// Contract: init() allocates the occupancy grid (start-up); everything in PeriodicWiring is
// borrowed and must outlive the PeriodicReports. start() schedules the first reports (status,
// occupancy and watchdog at once, statistics after one period). tick() runs on the processing
// thread after each processed frame with that frame's outcome (its published states and the
// ground footprint perception computed: nothing is lifted here) and sends what is due; it
// never allocates (Cyclone's write path aside) and counts a failed write in publishErrors.
// The loop's idle ticks (no frame for a while) pass an outcome not processed: status, watchdog
// and statistics go on, but the occupancy grid waits for the next frame.
#pragma once

#include <cstdint>

#include "config/config.hpp"
#include "dds_link.hpp"
#include "frame_step.hpp"
#include "loop_stats.hpp"
#include "messages/messages.hpp"
#include "platform/system/systemd_notify.hpp"

namespace vp::app {

// Every count of the loop at this moment (the app's: processing, capture, channel, pose input).
class CounterSource {
 public:
  virtual LoopCounters counters() const = 0;

 protected:
  ~CounterSource() = default;
};

struct PeriodicWiring {
  const config::DdsConfig* dds = nullptr;
  double statsPeriod_s = 10.0;
  bool quiet = false;             // no statistics line on stderr (STATUS= still goes out)
  DdsWriters* writers = nullptr;  // null with DDS off: no status, no occupancy
  platform::SystemdNotifier* notifier = nullptr;
  LoopStats* stats = nullptr;
  LoopCounters* counters = nullptr;  // the processing thread's (publish errors)
  const CounterSource* allCounters = nullptr;
  const char* modelId = "";  // the drone status's model id (borrowed)
  std::int64_t monotonicToUtc_ns = 0;
};

class PeriodicReports {
 public:
  void init(const PeriodicWiring& wiring);
  void start(std::int64_t now_ns);
  void tick(std::int64_t now_ns, const FrameOutcome& frame);

 private:
  void publishStatus(std::int64_t nowUtc_ns, const FrameOutcome& frame);
  void publishOccupancy(const FrameOutcome& frame);
  void logStats();

  PeriodicWiring wiring_{};
  messages::OccupancyGrid grid_;
  std::int64_t nextStatsNs_ = 0;
  std::int64_t nextStatusNs_ = 0;
  std::int64_t nextOccupancyNs_ = 0;
  std::int64_t nextWatchdogNs_ = 0;
  std::uint64_t framesAtStats_ = 0;   // processed frames at the last statistics line
  std::uint64_t framesAtStatus_ = 0;  // ... at the last drone status
};

}  // namespace vp::app
