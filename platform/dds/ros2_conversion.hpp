// platform/dds/ros2_conversion: messages/ structs -> the ROS 2 wire samples generated from
// interfaces/*/msg (vp_msgs VehicleStateArray and DroneStatus, nav_msgs OccupancyGrid,
// autoware_perception_msgs TrackedObjects), field by field.
//
// Contract: every sequence of a ROS sample points into fixed-capacity storage that the buffer
// classes allocate once in reserve() (start-up); after that begin()/add()/fill() overwrite the
// samples and never allocate nor throw. A buffer that is full refuses the element (add()
// returns false) instead of growing. Strings (header.frame_id) point at the buffer's own copy,
// set at reserve(). Units and frames follow the .msg comments; the Autoware mapping (UUID
// layout, classes, covariance layout, shape) is documented in docs/dds.md, "Autoware".
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "autoware_perception_msgs/msg/TrackedObjects_.h"
#include "messages/messages.hpp"
#include "nav_msgs/msg/OccupancyGrid_.h"
#include "vp_msgs/msg/DroneStatus_.h"
#include "vp_msgs/msg/VehicleStateArray_.h"

namespace vp::platform::dds::ros2 {

// UTC nanoseconds -> builtin_interfaces/Time (floor seconds, nanoseconds in [0, 1e9)).
builtin_interfaces_msg_dds__Time_ toRosTime(std::int64_t time_ns);

// One state into a ROS sample; asm_gamma and keypoints_enu_m point into the given arrays.
void toRosSample(const messages::VehicleState& state, vp_msgs_msg_dds__VehicleState_& sample,
                 std::array<float, shape::kMaxShapeComponents>& gamma,
                 std::array<geometry_msgs_msg_dds__Point32_, shape::kKeypointCount>& keypoints);

// One VehicleStateArray per frame: the vehicles of the frame and the tracks deleted in it.
class VehicleStateArrayBuffer {
 public:
  VehicleStateArrayBuffer() = default;
  VehicleStateArrayBuffer(const VehicleStateArrayBuffer&) = delete;  // the sample points into it
  VehicleStateArrayBuffer& operator=(const VehicleStateArrayBuffer&) = delete;
  void reserve(std::size_t maxVehicles, std::size_t maxRemoved, const std::string& frameId);
  void begin(std::uint32_t droneId, std::int64_t time_ns);  // empties both lists
  void setTime(std::int64_t time_ns);                       // header.stamp
  bool add(const messages::VehicleState& state);            // false when full
  bool addRemoved(std::uint32_t trackId);                   // false when full
  const vp_msgs_msg_dds__VehicleStateArray_& sample() const { return sample_; }

 private:
  vp_msgs_msg_dds__VehicleStateArray_ sample_{};
  std::string frameId_;
  std::vector<vp_msgs_msg_dds__VehicleState_> vehicles_;
  std::vector<std::array<float, shape::kMaxShapeComponents>> gamma_;
  std::vector<std::array<geometry_msgs_msg_dds__Point32_, shape::kKeypointCount>> keypoints_;
  std::vector<std::uint32_t> removed_;
};

class DroneStatusBuffer {
 public:
  DroneStatusBuffer() = default;
  DroneStatusBuffer(const DroneStatusBuffer&) = delete;  // the sample points into it
  DroneStatusBuffer& operator=(const DroneStatusBuffer&) = delete;
  void reserve(const std::string& frameId);
  void fill(const messages::DroneStatus& status);
  const vp_msgs_msg_dds__DroneStatus_& sample() const { return sample_; }

 private:
  vp_msgs_msg_dds__DroneStatus_ sample_{};
  std::string frameId_;
};

// nav_msgs/OccupancyGrid: -1 unobserved, 0 free, 100 occupied; origin = the south-west corner
// of cell (0, 0) in the world ENU frame, identity orientation; width = cols, height = rows.
class OccupancyGridBuffer {
 public:
  OccupancyGridBuffer() = default;
  OccupancyGridBuffer(const OccupancyGridBuffer&) = delete;  // the sample points into it
  OccupancyGridBuffer& operator=(const OccupancyGridBuffer&) = delete;
  static constexpr std::int8_t kUnknown = -1;
  static constexpr std::int8_t kFree = 0;
  static constexpr std::int8_t kOccupied = 100;
  void reserve(std::size_t maxCells, const std::string& frameId);
  bool fill(const messages::OccupancyGrid& grid);  // false when the grid exceeds maxCells
  const nav_msgs_msg_dds__OccupancyGrid_& sample() const { return sample_; }

 private:
  nav_msgs_msg_dds__OccupancyGrid_ sample_{};
  std::string frameId_;
  std::vector<std::int8_t> cells_;
};

// Deterministic object id of a track: bytes 0-3 drone id (big-endian), 4-5 "vp", 6 0x80
// (UUID version 8, custom), 7 0, 8 0x80 (RFC 9562 variant), 9-11 0, 12-15 track id (big-endian).
std::array<std::uint8_t, 16> trackUuid(std::uint32_t droneId, std::uint32_t trackId);

// Our types as Autoware labels: estate..van -> CAR with the sum of their probabilities, large
// (bus or truck) -> TRUCK; the more probable first.
struct AutowareClass {
  std::uint8_t label = 0;
  float probability = 0.0F;
};
std::array<AutowareClass, 2> autowareClasses(const messages::VehicleState& state);

struct AutowareOptions {
  double stationarySpeed_mps = 0.5;
};

// One TrackedObject (classification and footprint point into the given arrays).
void toTrackedObject(
    const messages::VehicleState& state, const AutowareOptions& options,
    autoware_perception_msgs_msg_dds__TrackedObject_& object,
    std::array<autoware_perception_msgs_msg_dds__ObjectClassification_, 2>& classes,
    std::array<geometry_msgs_msg_dds__Point32_, 4>& footprint);

class TrackedObjectsBuffer {
 public:
  TrackedObjectsBuffer() = default;
  TrackedObjectsBuffer(const TrackedObjectsBuffer&) = delete;  // the sample points into it
  TrackedObjectsBuffer& operator=(const TrackedObjectsBuffer&) = delete;
  void reserve(std::size_t maxObjects, const std::string& frameId, const AutowareOptions& options);
  void begin(std::int64_t time_ns);               // empties the list
  void setTime(std::int64_t time_ns);             // header.stamp
  bool add(const messages::VehicleState& state);  // false when full
  const autoware_perception_msgs_msg_dds__TrackedObjects_& sample() const { return sample_; }

 private:
  autoware_perception_msgs_msg_dds__TrackedObjects_ sample_{};
  std::string frameId_;
  AutowareOptions options_{};
  std::vector<autoware_perception_msgs_msg_dds__TrackedObject_> objects_;
  std::vector<std::array<autoware_perception_msgs_msg_dds__ObjectClassification_, 2>> classes_;
  std::vector<std::array<geometry_msgs_msg_dds__Point32_, 4>> footprints_;
};

}  // namespace vp::platform::dds::ros2
