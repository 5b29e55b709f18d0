// config/dds_config: the documented defaults of the `dds:` section (the reading is in
// config.cpp, beside the rest of the schema).
#include "config/dds_config.hpp"

namespace vp::config {

QosProfile DdsConfig::defaultVehicleStateQos() {
  // Reliable KEEP_LAST 1: a lost sample is resent only while it is still the newest state of
  // its track, and disposals (track deleted) are never lost. Transient-local: the writer keeps
  // that newest state per track for a reader that matches late (joining, or finishing a DDS
  // Security handshake after the first frames). Lifespan drops states that sat in a queue for
  // more than 5 frames; the deadline flags a track not refreshed for 3 frames.
  QosProfile qos;
  qos.reliability = Reliability::Reliable;
  qos.durability = Durability::TransientLocal;
  qos.maxBlocking_s = 0.01;
  qos.historyDepth = 1;
  qos.deadline_s = 0.3;
  qos.lifespan_s = 0.5;
  qos.livelinessLease_s = 2.0;
  return qos;
}

QosProfile DdsConfig::defaultDroneStatusQos() {
  // Transient-local so that a roadside unit joining late gets the current status at once.
  QosProfile qos;
  qos.reliability = Reliability::Reliable;
  qos.durability = Durability::TransientLocal;
  qos.historyDepth = 1;
  qos.deadline_s = 3.0;
  qos.livelinessLease_s = 5.0;
  return qos;
}

QosProfile DdsConfig::defaultOccupancyQos() {
  // Best effort: a grid is large (fragmented) and superseded by the next one; resending an old
  // one over a lossy link only delays the new one.
  QosProfile qos;
  qos.reliability = Reliability::BestEffort;
  qos.historyDepth = 1;
  qos.lifespan_s = 1.0;
  return qos;
}

QosProfile DdsConfig::defaultTrafficStatisticsQos() {
  // One sample per period (a minute by default): reliable, and transient-local with the last 4
  // periods so that a roadside unit joining late gets the recent counts at once.
  QosProfile qos;
  qos.reliability = Reliability::Reliable;
  qos.durability = Durability::TransientLocal;
  qos.historyDepth = 4;
  return qos;
}

QosProfile DdsConfig::defaultTrafficEventsQos() {
  // Every event matters (a count a roadside unit keeps from them): reliable with a deep history
  // (KEEP_LAST 256 per drone: a burst of events is not lost while a resend is pending), bounded
  // so that a reader that stops acknowledging cannot grow the writer's memory.
  QosProfile qos;
  qos.reliability = Reliability::Reliable;
  qos.durability = Durability::Volatile;
  qos.historyDepth = 256;
  return qos;
}

const char* defaultDdsPluginDir() {
  return VP_DEFAULT_DDS_PLUGIN_DIR;
}

const char* toString(Reliability reliability) {
  return reliability == Reliability::Reliable ? "reliable" : "best_effort";
}

const char* toString(Durability durability) {
  return durability == Durability::TransientLocal ? "transient_local" : "volatile";
}

const char* toString(TelemetrySource source) {
  switch (source) {
    case TelemetrySource::None:
      return "none";
    case TelemetrySource::ArduPilot:
      return "ardupilot";
    case TelemetrySource::Px4:
      return "px4";
  }
  return "none";
}

}  // namespace vp::config
