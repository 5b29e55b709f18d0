// firmware_app/dds_link: the app's DDS side: the perception participant with its three writers
// (vehicle states, drone status, occupancy grid) and, when the pose comes from the flight
// stack's ROS 2 bridge, the telemetry subscriber as a PoseInput.
//
// Contract: open() creates every entity (start-up; fails with Cyclone's message naming the
// call). The writers are platform/dds's: preallocated samples, errors as values; Cyclone's own
// write path allocates 2 per sample (docs/dds.md). DdsPoseInput turns the bridge's samples
// into pose samples on the loop's clock: UTC-stamped samples (ArduPilot with GNSS time) by the
// fixed CLOCK_REALTIME - CLOCK_MONOTONIC offset taken at start, autopilot-boot-stamped ones
// (PX4, ArduPilot without GNSS time) through a mavlink::BootClockMapper on their arrival times
// (millisecond resolution). PX4's attitude and position come as separate samples: an attitude
// sample makes a pose with the latest position (none before the first position); the gimbal is
// the configured default (the bridges publish none).
#pragma once

#include <cstdint>
#include <string>

#include "config/config.hpp"
#include "loop_inputs.hpp"
#include "mavlink/pose_assembler.hpp"
#include "platform/dds/perception_publisher.hpp"
#include "platform/dds/telemetry_subscriber.hpp"

namespace vp::app {

class DdsWriters {
 public:
  bool open(const config::DdsConfig& config, std::string* why);
  platform::dds::VehicleStatePublisher& states() { return states_; }
  const platform::dds::VehicleStatePublisher& states() const { return states_; }
  platform::dds::DroneStatusWriter& status() { return status_; }
  platform::dds::OccupancyWriter& occupancy() { return occupancy_; }

 private:
  platform::dds::Participant participant_;
  platform::dds::VehicleStatePublisher states_;
  platform::dds::DroneStatusWriter status_;
  platform::dds::OccupancyWriter occupancy_;
};

class DdsPoseInput final : public PoseInput {
 public:
  DdsPoseInput(platform::Clock& clock, const geodesy::GimbalState& defaultGimbal,
               std::int64_t monotonicToUtc_ns)
      : clock_(clock), defaultGimbal_(defaultGimbal), monotonicToUtcNs_(monotonicToUtc_ns) {}
  bool open(const config::TelemetryConfig& config, std::string* why);
  void poll(std::int64_t frameTime_ns, telemetry::PoseBuffer& buffer) override;
  const char* name() const override { return "dds"; }

 private:
  platform::Clock& clock_;
  geodesy::GimbalState defaultGimbal_;
  std::int64_t monotonicToUtcNs_;
  platform::dds::Participant participant_;
  platform::dds::TelemetrySubscriber subscriber_;
  platform::dds::PoseRing<64> ring_;
  mavlink::BootClockMapper bootClock_;
  bool havePosition_ = false;
  geodesy::GeodeticPoint position_{};
};

}  // namespace vp::app
