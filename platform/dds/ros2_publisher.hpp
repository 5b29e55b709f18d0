// platform/dds/ros2_publisher: the drone's outputs as ROS 2 topics, so that a ROS 2 node
// (rclcpp/rclpy on any RMW, rviz, ros2 topic echo) and Autoware subscribe without a bridge.
//
// Contract: ROS 2 maps topic /x to the DDS topic rt/x and message pkg/msg/T to the DDS type
// pkg::msg::dds_::T_ (plain CDR, final, no key), in the default partition. The writers here
// follow that: rt/<ns>/vehicle_states (vp_msgs/msg/VehicleStateArray), rt/<ns>/drone_status
// (vp_msgs/msg/DroneStatus), rt/<ns>/occupancy (nav_msgs/msg/OccupancyGrid) and, when enabled,
// rt<autoware topic> (autoware_perception_msgs/msg/TrackedObjects); QoS from the dds.qos
// profiles of the same outputs (Autoware's from vehicle_state). A ROS topic has no instances:
// every frame is one array message holding every published track (confirmed or lost), and a
// track deleted in that frame is listed once in removed_track_ids (VehicleStateArray only).
// Frame protocol as VehicleStatePublisher's: add() every state of the frame, then endFrame()
// writes the frame's messages. open() allocates every sample buffer (start-up; may fail);
// add()/endFrame()/write() neither allocate in our code nor throw, errors are values. Source
// timestamps are the frame / status / grid times (UTC ns).
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "config/dds_config.hpp"
#include "messages/messages.hpp"
#include "platform/dds/dds_handles.hpp"
#include "platform/dds/perception_publisher.hpp"
#include "platform/dds/ros2_conversion.hpp"

namespace vp::platform::dds {

// DDS names of the ROS topics: "rt/<namespace>/<name>" ("rt/<name>" without a namespace), and
// "rt" + the absolute Autoware topic.
std::string ros2TopicName(const config::Ros2Config& ros2, const char* name);
std::string autowareTopicName(const config::AutowareConfig& autoware);

struct Ros2FrameSummary {
  std::uint32_t vehicles = 0;  // in the frame's VehicleStateArray
  std::uint32_t removed = 0;   // track ids listed as removed
  std::uint32_t errors =
      0;  // failed writes, refused states, full buffers (each logged by the caller)
  DdsResult firstError{};  // the first failing DDS call of the frame, if any
};

// Vehicle states of a frame: the VehicleStateArray (when dds.ros2.enabled) and Autoware's
// TrackedObjects (when dds.autoware.enabled).
class Ros2StatePublisher {
 public:
  static constexpr std::size_t kMaxTracks = VehicleStatePublisher::kMaxTracks;

  DdsResult open(const Participant& participant, const config::DdsConfig& config);
  bool isOpen() const { return arrayWriter_.isOpen() || autowareWriter_.isOpen(); }

  // Adds a state to the frame: Tentative tracks never published are Skipped; a state failing
  // messages::validate() is InvalidState; beyond kMaxTracks TableFull.
  PublishResult add(const messages::VehicleState& state);
  // Writes the frame's messages stamped time_ns (frame capture time, UTC) and starts the next.
  Ros2FrameSummary endFrame(std::int64_t time_ns);

  dds_entity_t arrayWriter() const { return arrayWriter_.get(); }
  dds_entity_t autowareWriter() const { return autowareWriter_.get(); }

 private:
  bool wasPublished(std::uint32_t trackId) const;  // in the previous frame's array
  bool inFrame(std::uint32_t trackId) const;

  std::uint32_t droneId_ = 0;
  Topic arrayTopic_;
  Writer arrayWriter_;
  Topic autowareTopic_;
  Writer autowareWriter_;
  ros2::VehicleStateArrayBuffer array_;
  ros2::TrackedObjectsBuffer objects_;
  // Track ids of this frame and of the previous one (to list the removed ones).
  std::array<std::uint32_t, kMaxTracks> current_{};
  std::size_t currentCount_ = 0;
  std::array<std::uint32_t, kMaxTracks> previous_{};
  std::size_t previousCount_ = 0;
};

class Ros2DroneStatusWriter {
 public:
  DdsResult open(const Participant& participant, const config::DdsConfig& config);
  DdsResult write(const messages::DroneStatus& status);
  dds_entity_t writer() const { return writer_.get(); }

 private:
  Topic topic_;
  Writer writer_;
  ros2::DroneStatusBuffer sample_;
};

class Ros2OccupancyWriter {
 public:
  DdsResult open(const Participant& participant, const config::DdsConfig& config);
  DdsResult write(const messages::OccupancyGrid& grid);
  dds_entity_t writer() const { return writer_.get(); }

 private:
  Topic topic_;
  Writer writer_;
  ros2::OccupancyGridBuffer sample_;
};

}  // namespace vp::platform::dds
