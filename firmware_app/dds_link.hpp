// firmware_app/dds_link: the app's DDS side: the perception participant with its writers
// (vehicle states, drone status, occupancy grid) as native keyed topics (dds.native) and as
// ROS 2 topics (dds.ros2, plus Autoware's TrackedObjects with dds.autoware), and, when the pose
// comes from the flight stack's ROS 2 bridge, the telemetry subscriber as a PoseInput.
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
#include "platform/dds/ros2_publisher.hpp"
#include "platform/dds/telemetry_subscriber.hpp"
#include "platform/dds/traffic_publisher.hpp"

namespace vp::app {

// Every enabled output family gets each state, status and grid. The frame protocol is the
// publishers': publish() every state of the frame, then endFrame() (native: disposes the
// tracks that were not published; ROS 2: writes the frame's arrays). A failure is returned
// (the first one of the call); the first failure of the ROS frame writes is also logged.
class DdsWriters {
 public:
  bool open(const config::DdsConfig& config, std::string* why);
  platform::dds::PublishResult publish(const messages::VehicleState& state);
  platform::dds::FrameSummary endFrame(std::int64_t time_ns);
  platform::dds::DdsResult writeStatus(const messages::DroneStatus& status);
  platform::dds::DdsResult writeOccupancy(const messages::OccupancyGrid& grid);
  // The traffic topics (native and/or ROS 2 as the other outputs), after open(), when the app
  // runs the traffic analysis; start-up.
  bool openTraffic(const config::DdsConfig& config, const platform::dds::TrafficFeatureIdViews& ids,
                   const geodesy::LocalFrame& world, std::string* why);
  bool trafficOpen() const { return traffic_.isOpen(); }
  platform::dds::DdsResult writeTrafficStatistics(const traffic::TrafficStatistics& statistics,
                                                  std::int64_t timeUtc_ns) {
    return traffic_.writeStatistics(statistics, timeUtc_ns);
  }
  platform::dds::DdsResult writeTrafficEvent(const traffic::TrafficEvent& event,
                                             std::int64_t timeUtc_ns) {
    return traffic_.writeEvent(event, timeUtc_ns);
  }
  const platform::dds::TrafficPublisher& traffic() const { return traffic_; }

  const platform::dds::VehicleStatePublisher& states() const { return states_; }  // native
  const platform::dds::Ros2StatePublisher& rosStates() const { return rosStates_; }

 private:
  bool native_ = false;
  bool ros2_ = false;
  bool rosStatesOpen_ = false;  // ros2 or autoware
  bool rosErrorLogged_ = false;
  platform::dds::Participant participant_;
  platform::dds::VehicleStatePublisher states_;
  platform::dds::DroneStatusWriter status_;
  platform::dds::OccupancyWriter occupancy_;
  platform::dds::Ros2StatePublisher rosStates_;
  platform::dds::Ros2DroneStatusWriter rosStatus_;
  platform::dds::Ros2OccupancyWriter rosOccupancy_;
  platform::dds::TrafficPublisher traffic_;
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
