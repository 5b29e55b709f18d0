#include "periodic_reports.hpp"

#include <array>

#include "loop_log.hpp"
#include "messages/occupancy.hpp"

namespace vp::app {

void PeriodicReports::init(const PeriodicWiring& wiring) {
  wiring_ = wiring;
  if (wiring_.writers != nullptr && wiring_.dds->occupancyRate_hz > 0.0) {
    grid_.resize(wiring_.dds->grid.rows, wiring_.dds->grid.cols);
  }
}

void PeriodicReports::start(std::int64_t now_ns) {
  nextStatsNs_ = now_ns + static_cast<std::int64_t>(wiring_.statsPeriod_s * 1e9);
  nextStatusNs_ = now_ns;
  nextOccupancyNs_ = now_ns;
  nextWatchdogNs_ = now_ns;
}

void PeriodicReports::tick(std::int64_t now_ns, const FrameOutcome& frame) {
  if (wiring_.writers != nullptr) {
    if (now_ns >= nextStatusNs_) {
      const double period_s = 1.0 / wiring_.dds->statusRate_hz;
      publishStatus(now_ns + wiring_.monotonicToUtc_ns, frame);
      nextStatusNs_ = now_ns + static_cast<std::int64_t>(period_s * 1e9);
    }
    // A grid is an observation: an idle tick (no processed frame) publishes none and leaves the
    // period to the next frame, so a subscriber never gets an empty grid stamped at the epoch.
    if (wiring_.dds->occupancyRate_hz > 0.0 && now_ns >= nextOccupancyNs_ && frame.processed) {
      publishOccupancy(frame);
      nextOccupancyNs_ = now_ns + static_cast<std::int64_t>(1e9 / wiring_.dds->occupancyRate_hz);
    }
  }
  platform::SystemdNotifier& notifier = *wiring_.notifier;
  if (notifier.watchdogInterval_ns() > 0 && now_ns >= nextWatchdogNs_) {
    notifier.watchdog();
    nextWatchdogNs_ = now_ns + notifier.watchdogInterval_ns();
  }
  if (now_ns >= nextStatsNs_) {
    logStats();
    nextStatsNs_ = now_ns + static_cast<std::int64_t>(wiring_.statsPeriod_s * 1e9);
  }
}

void PeriodicReports::publishStatus(std::int64_t nowUtc_ns, const FrameOutcome& frame) {
  const telemetry::PoseEstimate& pose = frame.pose;
  const LoopStats& stats = *wiring_.stats;
  messages::DroneStatus status;
  status.droneId = wiring_.dds->droneId;
  status.time_ns = nowUtc_ns;
  status.position = pose.pose.position;
  const Eigen::Quaterniond& q = pose.pose.bodyToNed;
  status.attitudeQuaternion = {q.w(), q.x(), q.y(), q.z()};
  status.gimbalEuler_deg = {static_cast<float>(pose.pose.gimbal.angles.roll_deg),
                            static_cast<float>(pose.pose.gimbal.angles.pitch_deg),
                            static_cast<float>(pose.pose.gimbal.angles.yaw_deg)};
  const diagnostics::LatencyHistogram& e2e = stats.period(Stage::EndToEnd);
  status.latencyMedian_ms = static_cast<float>(static_cast<double>(e2e.median_ns()) / 1e6);
  status.latencyP99_ms = static_cast<float>(static_cast<double>(e2e.p99_ns()) / 1e6);
  status.inferenceMedian_ms =
      static_cast<float>(static_cast<double>(stats.period(Stage::Detector).median_ns()) / 1e6);
  const LoopCounters c = wiring_.allCounters->counters();
  status.frameRate_hz = static_cast<float>(
      static_cast<double>(c.framesProcessed - framesAtStatus_) * wiring_.dds->statusRate_hz);
  status.framesProcessed = c.framesProcessed;
  status.framesDropped = c.framesDropped;
  status.corruptFrames = c.badFrames;
  status.stalePoses = c.stalePose + c.noPose + c.invalidPose;
  status.outsideDtm = c.outsideDtm;
  status.publishErrors = c.publishErrors;
  status.activeTracks = static_cast<std::uint32_t>(frame.states.size());
  status.setModelId(wiring_.modelId);
  if (!wiring_.writers->writeStatus(status).ok()) {
    ++wiring_.counters->publishErrors;
  }
  framesAtStatus_ = c.framesProcessed;
}

void PeriodicReports::publishOccupancy(const FrameOutcome& frame) {
  // The observed area is the frame's ground footprint as perception computed it.
  const config::OccupancyGridSpec& spec = wiring_.dds->grid;
  grid_.droneId = wiring_.dds->droneId;
  grid_.time_ns = frame.timeUtc_ns;
  grid_.originEast_m = spec.originEast_m;
  grid_.originNorth_m = spec.originNorth_m;
  grid_.resolution_m = static_cast<float>(spec.resolution_m);
  messages::rasterizeOccupancy(frame.footprint, frame.states, grid_);
  if (!wiring_.writers->writeOccupancy(grid_).ok()) {
    ++wiring_.counters->publishErrors;
  }
}

void PeriodicReports::logStats() {
  const LoopCounters c = wiring_.allCounters->counters();
  std::array<char, 1024> line{};
  formatStatsLine(line, c, *wiring_.stats, static_cast<double>(c.framesProcessed - framesAtStats_),
                  wiring_.statsPeriod_s);
  if (!wiring_.quiet) {
    logLine("%s", line.data());
  }
  wiring_.notifier->status(line.data());
  framesAtStats_ = c.framesProcessed;
  wiring_.stats->startPeriod();
}

}  // namespace vp::app
