// platform/dds/ros2_conversion: field-by-field copies into preallocated ROS 2 samples.
#include "platform/dds/ros2_conversion.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace vp::platform::dds::ros2 {
namespace {

constexpr std::int64_t kNsPerSecond = 1'000'000'000;

// A sequence that borrows fixed storage: never released by Cyclone, never grown.
template <typename Sequence, typename T>
void borrow(Sequence& sequence, T* buffer, std::size_t capacity) {
  sequence._buffer = buffer;
  sequence._maximum = static_cast<std::uint32_t>(capacity);
  sequence._length = 0;
  sequence._release = false;
}

// The sample's char* points at the buffer's own string, which lives as long as the sample.
char* borrowString(std::string& text) {
  return text.data();
}

geometry_msgs_msg_dds__Point_ toPoint(const std::array<double, 3>& enu) {
  return geometry_msgs_msg_dds__Point_{enu[0], enu[1], enu[2]};
}

vp_msgs_msg_dds__GeodeticPoint_ toGeodetic(const geodesy::GeodeticPoint& point) {
  return vp_msgs_msg_dds__GeodeticPoint_{point.latitude_deg, point.longitude_deg, point.height_m};
}

// Row-major index of (row, col) in a 6x6 covariance.
constexpr std::size_t at6(std::size_t row, std::size_t col) {
  return row * 6 + col;
}

}  // namespace

builtin_interfaces_msg_dds__Time_ toRosTime(std::int64_t time_ns) {
  std::int64_t seconds = time_ns / kNsPerSecond;
  std::int64_t nanoseconds = time_ns % kNsPerSecond;
  if (nanoseconds < 0) {  // floor, so that nanosec stays in [0, 1e9)
    --seconds;
    nanoseconds += kNsPerSecond;
  }
  return builtin_interfaces_msg_dds__Time_{static_cast<std::int32_t>(seconds),
                                           static_cast<std::uint32_t>(nanoseconds)};
}

void toRosSample(const messages::VehicleState& state, vp_msgs_msg_dds__VehicleState_& sample,
                 std::array<float, shape::kMaxShapeComponents>& gamma,
                 std::array<geometry_msgs_msg_dds__Point32_, shape::kKeypointCount>& keypoints) {
  sample.drone_id = state.droneId;
  sample.track_id = state.trackId;
  sample.measurement_time = toRosTime(state.measurementTime_ns);
  sample.track_age_s = state.trackAge_s;
  sample.position = toGeodetic(state.position);
  sample.enu_m = toPoint(state.enu_m);
  sample.heading_enu_rad = state.headingEnu_rad;
  sample.heading_true_north_deg = state.headingTrueNorth_deg;
  sample.speed_mps = state.speed_mps;
  sample.velocity_enu_mps[0] = state.velocityEnu_mps[0];
  sample.velocity_enu_mps[1] = state.velocityEnu_mps[1];
  sample.yaw_rate_radps = state.yawRate_radps;
  sample.acceleration_mps2 = state.acceleration_mps2;
  sample.length_m = state.length_m;
  sample.width_m = state.width_m;
  sample.height_m = state.height_m;
  sample.type = static_cast<std::uint8_t>(state.type);
  static_assert(sizeof(sample.type_probability) / sizeof(float) == shape::kVehicleTypeCount);
  std::copy(state.typeProbability.begin(), state.typeProbability.end(), sample.type_probability);
  const auto gammaCount =
      static_cast<std::size_t>(std::clamp(state.shape.count, 0, shape::kMaxShapeComponents));
  std::copy_n(state.shape.gamma.begin(), gammaCount, gamma.begin());
  borrow(sample.asm_gamma, gamma.data(), gamma.size());
  sample.asm_gamma._length = static_cast<std::uint32_t>(gammaCount);
  static_assert(sizeof(sample.pose_covariance) / sizeof(float) == 6);
  std::copy(state.poseCovariance.begin(), state.poseCovariance.end(), sample.pose_covariance);
  sample.height_variance_m2 = state.heightVariance_m2;
  sample.speed_variance_m2ps2 = state.speedVariance_m2ps2;
  sample.yaw_rate_variance_rad2ps2 = state.yawRateVariance_rad2ps2;
  sample.detection_confidence = state.detectionConfidence;
  sample.status = static_cast<std::uint8_t>(state.status);
  sample.utm_zone = state.utmZone;
  sample.utm_northern_hemisphere = state.utmNorthernHemisphere;
  sample.utm_easting_m = state.utmEasting_m;
  sample.utm_northing_m = state.utmNorthing_m;
  sample.rear_axle_enu_m = toPoint(state.rearAxleEnu_m);
  sample.rear_axle_position = toGeodetic(state.rearAxlePosition);
  sample.length_variance_m2 = state.lengthVariance_m2;
  sample.width_variance_m2 = state.widthVariance_m2;
  const std::size_t keypointCount = std::min<std::size_t>(state.keypointCount, keypoints.size());
  for (std::size_t i = 0; i < keypointCount; ++i) {
    keypoints[i] = geometry_msgs_msg_dds__Point32_{
        state.keypointsEnu_m[i][0], state.keypointsEnu_m[i][1], state.keypointsEnu_m[i][2]};
  }
  borrow(sample.keypoints_enu_m, keypoints.data(), keypoints.size());
  sample.keypoints_enu_m._length = static_cast<std::uint32_t>(keypointCount);
}

void VehicleStateArrayBuffer::reserve(std::size_t maxVehicles, std::size_t maxRemoved,
                                      const std::string& frameId) {
  frameId_ = frameId;
  vehicles_.assign(maxVehicles, vp_msgs_msg_dds__VehicleState_{});
  gamma_.assign(maxVehicles, {});
  keypoints_.assign(maxVehicles, {});
  removed_.assign(maxRemoved, 0);
  sample_ = vp_msgs_msg_dds__VehicleStateArray_{};
  sample_.header.frame_id = borrowString(frameId_);
  borrow(sample_.vehicles, vehicles_.data(), vehicles_.size());
  borrow(sample_.removed_track_ids, removed_.data(), removed_.size());
}

void VehicleStateArrayBuffer::begin(std::uint32_t droneId, std::int64_t time_ns) {
  sample_.header.stamp = toRosTime(time_ns);
  sample_.drone_id = droneId;
  sample_.vehicles._length = 0;
  sample_.removed_track_ids._length = 0;
}

void VehicleStateArrayBuffer::setTime(std::int64_t time_ns) {
  sample_.header.stamp = toRosTime(time_ns);
}

bool VehicleStateArrayBuffer::add(const messages::VehicleState& state) {
  const std::uint32_t index = sample_.vehicles._length;
  if (index >= sample_.vehicles._maximum) {
    return false;
  }
  toRosSample(state, vehicles_[index], gamma_[index], keypoints_[index]);
  sample_.vehicles._length = index + 1;
  return true;
}

bool VehicleStateArrayBuffer::addRemoved(std::uint32_t trackId) {
  const std::uint32_t index = sample_.removed_track_ids._length;
  if (index >= sample_.removed_track_ids._maximum) {
    return false;
  }
  removed_[index] = trackId;
  sample_.removed_track_ids._length = index + 1;
  return true;
}

void DroneStatusBuffer::reserve(const std::string& frameId) {
  frameId_ = frameId;
  sample_ = vp_msgs_msg_dds__DroneStatus_{};
  sample_.header.frame_id = borrowString(frameId_);
}

void DroneStatusBuffer::fill(const messages::DroneStatus& status) {
  sample_.header.stamp = toRosTime(status.time_ns);
  sample_.drone_id = status.droneId;
  sample_.position = toGeodetic(status.position);
  // ours (w, x, y, z) -> geometry_msgs (x, y, z, w)
  sample_.attitude_frd_to_ned = geometry_msgs_msg_dds__Quaternion_{
      status.attitudeQuaternion[1], status.attitudeQuaternion[2], status.attitudeQuaternion[3],
      status.attitudeQuaternion[0]};
  std::copy(status.gimbalEuler_deg.begin(), status.gimbalEuler_deg.end(), sample_.gimbal_euler_deg);
  sample_.frame_rate_hz = status.frameRate_hz;
  sample_.latency_median_ms = status.latencyMedian_ms;
  sample_.latency_p99_ms = status.latencyP99_ms;
  sample_.inference_median_ms = status.inferenceMedian_ms;
  sample_.frames_processed = status.framesProcessed;
  sample_.frames_dropped = status.framesDropped;
  sample_.corrupt_frames = status.corruptFrames;
  sample_.stale_poses = status.stalePoses;
  sample_.outside_dtm = status.outsideDtm;
  sample_.publish_errors = status.publishErrors;
  sample_.active_tracks = status.activeTracks;
  static_assert(sizeof(sample_.model_id) == messages::DroneStatus::kModelIdCapacity + 1);
  std::memcpy(sample_.model_id, status.modelId.data(), sizeof(sample_.model_id));
  sample_.model_id[sizeof(sample_.model_id) - 1] = '\0';
}

void OccupancyGridBuffer::reserve(std::size_t maxCells, const std::string& frameId) {
  frameId_ = frameId;
  cells_.assign(maxCells, kUnknown);
  sample_ = nav_msgs_msg_dds__OccupancyGrid_{};
  sample_.header.frame_id = borrowString(frameId_);
  sample_.info.origin.orientation.w = 1.0;  // north-up: the grid's axes are east and north
  borrow(sample_.data, cells_.data(), cells_.size());
}

bool OccupancyGridBuffer::fill(const messages::OccupancyGrid& grid) {
  const std::size_t count = static_cast<std::size_t>(grid.rows) * grid.cols;
  if (count > cells_.size() || grid.cells.size() < count) {
    return false;
  }
  sample_.header.stamp = toRosTime(grid.time_ns);
  sample_.info.map_load_time = sample_.header.stamp;
  sample_.info.resolution = grid.resolution_m;
  sample_.info.width = grid.cols;
  sample_.info.height = grid.rows;
  sample_.info.origin.position =
      geometry_msgs_msg_dds__Point_{grid.originEast_m, grid.originNorth_m, 0.0};
  // Both are row-major with row 0 at the origin (south) and columns eastwards.
  for (std::size_t i = 0; i < count; ++i) {
    switch (static_cast<messages::Occupancy>(grid.cells[i])) {
      case messages::Occupancy::Free:
        cells_[i] = kFree;
        break;
      case messages::Occupancy::Occupied:
        cells_[i] = kOccupied;
        break;
      case messages::Occupancy::Unobserved:
      default:
        cells_[i] = kUnknown;
        break;
    }
  }
  sample_.data._length = static_cast<std::uint32_t>(count);
  return true;
}

std::array<std::uint8_t, 16> trackUuid(std::uint32_t droneId, std::uint32_t trackId) {
  std::array<std::uint8_t, 16> uuid{};
  for (int i = 0; i < 4; ++i) {
    uuid[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(droneId >> (24 - 8 * i));
    uuid[static_cast<std::size_t>(12 + i)] = static_cast<std::uint8_t>(trackId >> (24 - 8 * i));
  }
  uuid[4] = 'v';
  uuid[5] = 'p';
  uuid[6] = 0x80;  // version 8: a custom layout
  uuid[8] = 0x80;  // variant 0b10 (RFC 9562)
  return uuid;
}

std::array<AutowareClass, 2> autowareClasses(const messages::VehicleState& state) {
  constexpr std::uint8_t kCar =
      autoware_perception_msgs_msg_dds__ObjectClassification_Constants_CAR;
  constexpr std::uint8_t kTruck =
      autoware_perception_msgs_msg_dds__ObjectClassification_Constants_TRUCK;
  float car = 0.0F;
  for (int type = 0; type < shape::kCarTypeCount; ++type) {
    car += state.typeProbability[static_cast<std::size_t>(type)];
  }
  const float large = state.typeProbability[static_cast<std::size_t>(shape::VehicleType::Large)];
  const AutowareClass carClass{kCar, car};
  const AutowareClass truckClass{kTruck, large};
  // Ties go to the reported type, so that front() agrees with VehicleState::type.
  const bool truckFirst = large > car || (large == car && state.type == shape::VehicleType::Large);
  return truckFirst ? std::array<AutowareClass, 2>{truckClass, carClass}
                    : std::array<AutowareClass, 2>{carClass, truckClass};
}

void toTrackedObject(
    const messages::VehicleState& state, const AutowareOptions& options,
    autoware_perception_msgs_msg_dds__TrackedObject_& object,
    std::array<autoware_perception_msgs_msg_dds__ObjectClassification_, 2>& classes,
    std::array<geometry_msgs_msg_dds__Point32_, 4>& footprint) {
  const std::array<std::uint8_t, 16> uuid = trackUuid(state.droneId, state.trackId);
  std::copy(uuid.begin(), uuid.end(), object.object_id.uuid);
  object.existence_probability = state.detectionConfidence;

  const std::array<AutowareClass, 2> ours = autowareClasses(state);
  for (std::size_t i = 0; i < classes.size(); ++i) {
    classes[i] = {ours[i].label, ours[i].probability};
  }
  borrow(object.classification, classes.data(), classes.size());
  object.classification._length = static_cast<std::uint32_t>(classes.size());

  // Pose: the box centre (footprint centre lifted by half the height: Autoware's shapes are
  // centred on the pose), yaw = our ENU heading (map = world ENU).
  autoware_perception_msgs_msg_dds__TrackedObjectKinematics_& kin = object.kinematics;
  kin.pose_with_covariance.pose.position = geometry_msgs_msg_dds__Point_{
      state.enu_m[0], state.enu_m[1], state.enu_m[2] + 0.5 * static_cast<double>(state.height_m)};
  const double halfYaw = 0.5 * state.headingEnu_rad;
  kin.pose_with_covariance.pose.orientation =
      geometry_msgs_msg_dds__Quaternion_{0.0, 0.0, std::sin(halfYaw), std::cos(halfYaw)};
  // (x, y, z, roll, pitch, yaw) from our (east, north, heading) covariance; z = ground + h/2,
  // so var(z) = var(h) / 4; roll and pitch are not estimated (vehicles are level): 0.
  double* pose = kin.pose_with_covariance.covariance;
  std::fill_n(pose, 36, 0.0);
  const std::array<float, 6>& c = state.poseCovariance;  // ee, en, eh, nn, nh, hh
  pose[at6(0, 0)] = c[0];
  pose[at6(0, 1)] = pose[at6(1, 0)] = c[1];
  pose[at6(0, 5)] = pose[at6(5, 0)] = c[2];
  pose[at6(1, 1)] = c[3];
  pose[at6(1, 5)] = pose[at6(5, 1)] = c[4];
  pose[at6(5, 5)] = c[5];
  pose[at6(2, 2)] = 0.25 * static_cast<double>(state.heightVariance_m2);
  kin.orientation_availability =
      autoware_perception_msgs_msg_dds__TrackedObjectKinematics_Constants_AVAILABLE;

  // Twist in the vehicle frame (x forward, z up): no lateral slip in our bicycle model.
  kin.twist_with_covariance.twist =
      geometry_msgs_msg_dds__Twist_{{state.speed_mps, 0.0, 0.0}, {0.0, 0.0, state.yawRate_radps}};
  double* twist = kin.twist_with_covariance.covariance;
  std::fill_n(twist, 36, 0.0);
  twist[at6(0, 0)] = state.speedVariance_m2ps2;
  twist[at6(5, 5)] = state.yawRateVariance_rad2ps2;

  // Longitudinal acceleration only; its variance is not estimated (covariance all 0).
  kin.acceleration_with_covariance.accel =
      geometry_msgs_msg_dds__Accel_{{state.acceleration_mps2, 0.0, 0.0}, {0.0, 0.0, 0.0}};
  std::fill_n(kin.acceleration_with_covariance.covariance, 36, 0.0);
  kin.is_stationary = std::fabs(static_cast<double>(state.speed_mps)) < options.stationarySpeed_mps;

  // Box: dimensions plus its footprint in the object frame (front-left first, counter-clockwise).
  object.shape.type = autoware_perception_msgs_msg_dds__Shape_Constants_BOUNDING_BOX;
  object.shape.dimensions =
      geometry_msgs_msg_dds__Vector3_{state.length_m, state.width_m, state.height_m};
  const float halfLength = 0.5F * state.length_m;
  const float halfWidth = 0.5F * state.width_m;
  footprint = {geometry_msgs_msg_dds__Point32_{halfLength, halfWidth, 0.0F},
               geometry_msgs_msg_dds__Point32_{-halfLength, halfWidth, 0.0F},
               geometry_msgs_msg_dds__Point32_{-halfLength, -halfWidth, 0.0F},
               geometry_msgs_msg_dds__Point32_{halfLength, -halfWidth, 0.0F}};
  borrow(object.shape.footprint.points, footprint.data(), footprint.size());
  object.shape.footprint.points._length = static_cast<std::uint32_t>(footprint.size());
}

void TrackedObjectsBuffer::reserve(std::size_t maxObjects, const std::string& frameId,
                                   const AutowareOptions& options) {
  frameId_ = frameId;
  options_ = options;
  objects_.assign(maxObjects, autoware_perception_msgs_msg_dds__TrackedObject_{});
  classes_.assign(maxObjects, {});
  footprints_.assign(maxObjects, {});
  sample_ = autoware_perception_msgs_msg_dds__TrackedObjects_{};
  sample_.header.frame_id = borrowString(frameId_);
  borrow(sample_.objects, objects_.data(), objects_.size());
}

void TrackedObjectsBuffer::begin(std::int64_t time_ns) {
  sample_.header.stamp = toRosTime(time_ns);
  sample_.objects._length = 0;
}

void TrackedObjectsBuffer::setTime(std::int64_t time_ns) {
  sample_.header.stamp = toRosTime(time_ns);
}

bool TrackedObjectsBuffer::add(const messages::VehicleState& state) {
  const std::uint32_t index = sample_.objects._length;
  if (index >= sample_.objects._maximum) {
    return false;
  }
  toTrackedObject(state, options_, objects_[index], classes_[index], footprints_[index]);
  sample_.objects._length = index + 1;
  return true;
}

}  // namespace vp::platform::dds::ros2
