// platform/dds/conversion: field-by-field copies; see docs/dds.md for the field table.
#include "platform/dds/conversion.hpp"

#include <algorithm>
#include <cstring>

namespace vp::platform::dds {
namespace {

vp_msg_Wgs84Position toWire(const geodesy::GeodeticPoint& p) {
  return vp_msg_Wgs84Position{p.latitude_deg, p.longitude_deg, p.height_m};
}
geodesy::GeodeticPoint fromWire(const vp_msg_Wgs84Position& p) {
  return geodesy::GeodeticPoint{p.latitude_deg, p.longitude_deg, p.height_m};
}

static_assert(shape::kVehicleTypeCount == vp_msg_kVehicleTypeCount);
static_assert(shape::kMaxShapeComponents == vp_msg_kMaxShapeComponents);
static_assert(shape::kKeypointCount == vp_msg_kKeypointCount);
static_assert(messages::DroneStatus::kModelIdCapacity + 1 == sizeof(vp_msg_DroneStatus{}.model_id));

}  // namespace

void toSample(const messages::VehicleState& s, vp_msg_VehicleState& out) {
  out.drone_id = s.droneId;
  out.track_id = s.trackId;
  out.measurement_time_ns = s.measurementTime_ns;
  out.track_age_s = s.trackAge_s;
  out.position = toWire(s.position);
  std::copy(s.enu_m.begin(), s.enu_m.end(), out.enu_m);
  out.heading_enu_rad = s.headingEnu_rad;
  out.heading_true_north_deg = s.headingTrueNorth_deg;
  out.speed_mps = s.speed_mps;
  std::copy(s.velocityEnu_mps.begin(), s.velocityEnu_mps.end(), out.velocity_enu_mps);
  out.yaw_rate_radps = s.yawRate_radps;
  out.acceleration_mps2 = s.acceleration_mps2;
  out.length_m = s.length_m;
  out.width_m = s.width_m;
  out.height_m = s.height_m;
  out.type = static_cast<vp_msg_VehicleType>(s.type);  // same order, checked by the tests
  std::copy(s.typeProbability.begin(), s.typeProbability.end(), out.type_probability);
  out.shape_count = static_cast<uint8_t>(std::clamp(s.shape.count, 0, shape::kMaxShapeComponents));
  std::copy(s.shape.gamma.begin(), s.shape.gamma.end(), out.asm_gamma);
  std::copy(s.poseCovariance.begin(), s.poseCovariance.end(), out.pose_covariance);
  out.height_variance_m2 = s.heightVariance_m2;
  out.speed_variance_m2ps2 = s.speedVariance_m2ps2;
  out.yaw_rate_variance_rad2ps2 = s.yawRateVariance_rad2ps2;
  out.detection_confidence = s.detectionConfidence;
  out.status = static_cast<vp_msg_TrackStatus>(s.status);
  out.utm_zone = s.utmZone;
  out.utm_north = s.utmNorthernHemisphere;
  out.utm_easting_m = s.utmEasting_m;
  out.utm_northing_m = s.utmNorthing_m;
  std::copy(s.rearAxleEnu_m.begin(), s.rearAxleEnu_m.end(), out.rear_axle_enu_m);
  out.rear_axle_position = toWire(s.rearAxlePosition);
  out.length_variance_m2 = s.lengthVariance_m2;
  out.width_variance_m2 = s.widthVariance_m2;
  out.keypoint_count = static_cast<uint8_t>(std::min<int>(s.keypointCount, shape::kKeypointCount));
  for (std::size_t k = 0; k < s.keypointsEnu_m.size(); ++k) {
    std::copy(s.keypointsEnu_m[k].begin(), s.keypointsEnu_m[k].end(), out.keypoints_enu_m[k]);
  }
}

messages::VehicleState fromSample(const vp_msg_VehicleState& in) {
  messages::VehicleState s;
  s.droneId = in.drone_id;
  s.trackId = in.track_id;
  s.measurementTime_ns = in.measurement_time_ns;
  s.trackAge_s = in.track_age_s;
  s.position = fromWire(in.position);
  std::copy(std::begin(in.enu_m), std::end(in.enu_m), s.enu_m.begin());
  s.headingEnu_rad = in.heading_enu_rad;
  s.headingTrueNorth_deg = in.heading_true_north_deg;
  s.speed_mps = in.speed_mps;
  std::copy(std::begin(in.velocity_enu_mps), std::end(in.velocity_enu_mps),
            s.velocityEnu_mps.begin());
  s.yawRate_radps = in.yaw_rate_radps;
  s.acceleration_mps2 = in.acceleration_mps2;
  s.length_m = in.length_m;
  s.width_m = in.width_m;
  s.height_m = in.height_m;
  s.type = in.type <= vp_msg_TYPE_LARGE ? static_cast<shape::VehicleType>(in.type)
                                        : shape::VehicleType::Sedan;
  std::copy(std::begin(in.type_probability), std::end(in.type_probability),
            s.typeProbability.begin());
  s.shape.count = std::min<int>(in.shape_count, shape::kMaxShapeComponents);
  std::copy(std::begin(in.asm_gamma), std::end(in.asm_gamma), s.shape.gamma.begin());
  std::copy(std::begin(in.pose_covariance), std::end(in.pose_covariance), s.poseCovariance.begin());
  s.heightVariance_m2 = in.height_variance_m2;
  s.speedVariance_m2ps2 = in.speed_variance_m2ps2;
  s.yawRateVariance_rad2ps2 = in.yaw_rate_variance_rad2ps2;
  s.detectionConfidence = in.detection_confidence;
  s.status = in.status <= vp_msg_TRACK_LOST ? static_cast<messages::TrackStatus>(in.status)
                                            : messages::TrackStatus::Lost;
  s.utmZone = in.utm_zone;
  s.utmNorthernHemisphere = in.utm_north;
  s.utmEasting_m = in.utm_easting_m;
  s.utmNorthing_m = in.utm_northing_m;
  std::copy(std::begin(in.rear_axle_enu_m), std::end(in.rear_axle_enu_m), s.rearAxleEnu_m.begin());
  s.rearAxlePosition = fromWire(in.rear_axle_position);
  s.lengthVariance_m2 = in.length_variance_m2;
  s.widthVariance_m2 = in.width_variance_m2;
  s.keypointCount =
      static_cast<std::uint8_t>(std::min<int>(in.keypoint_count, shape::kKeypointCount));
  for (std::size_t k = 0; k < s.keypointsEnu_m.size(); ++k) {
    std::copy(std::begin(in.keypoints_enu_m[k]), std::end(in.keypoints_enu_m[k]),
              s.keypointsEnu_m[k].begin());
  }
  return s;
}

void toSample(const messages::DroneStatus& s, vp_msg_DroneStatus& out) {
  out.drone_id = s.droneId;
  out.time_ns = s.time_ns;
  out.position = toWire(s.position);
  std::copy(s.attitudeQuaternion.begin(), s.attitudeQuaternion.end(), out.attitude_q_nb);
  std::copy(s.gimbalEuler_deg.begin(), s.gimbalEuler_deg.end(), out.gimbal_euler_deg);
  out.frame_rate_hz = s.frameRate_hz;
  out.latency_median_ms = s.latencyMedian_ms;
  out.latency_p99_ms = s.latencyP99_ms;
  out.inference_median_ms = s.inferenceMedian_ms;
  out.frames_processed = s.framesProcessed;
  out.frames_dropped = s.framesDropped;
  out.corrupt_frames = s.corruptFrames;
  out.stale_poses = s.stalePoses;
  out.outside_dtm = s.outsideDtm;
  out.publish_errors = s.publishErrors;
  out.active_tracks = s.activeTracks;
  std::memcpy(out.model_id, s.modelId.data(), sizeof(out.model_id));
  out.model_id[sizeof(out.model_id) - 1] = '\0';
}

messages::DroneStatus fromSample(const vp_msg_DroneStatus& in) {
  messages::DroneStatus s;
  s.droneId = in.drone_id;
  s.time_ns = in.time_ns;
  s.position = fromWire(in.position);
  std::copy(std::begin(in.attitude_q_nb), std::end(in.attitude_q_nb), s.attitudeQuaternion.begin());
  std::copy(std::begin(in.gimbal_euler_deg), std::end(in.gimbal_euler_deg),
            s.gimbalEuler_deg.begin());
  s.frameRate_hz = in.frame_rate_hz;
  s.latencyMedian_ms = in.latency_median_ms;
  s.latencyP99_ms = in.latency_p99_ms;
  s.inferenceMedian_ms = in.inference_median_ms;
  s.framesProcessed = in.frames_processed;
  s.framesDropped = in.frames_dropped;
  s.corruptFrames = in.corrupt_frames;
  s.stalePoses = in.stale_poses;
  s.outsideDtm = in.outside_dtm;
  s.publishErrors = in.publish_errors;
  s.activeTracks = in.active_tracks;
  s.setModelId(std::string_view(in.model_id, strnlen(in.model_id, sizeof(in.model_id))));
  return s;
}

void toSample(const messages::OccupancyGrid& g, vp_msg_OccupancyGrid& out) {
  out.drone_id = g.droneId;
  out.time_ns = g.time_ns;
  out.origin_east_m = g.originEast_m;
  out.origin_north_m = g.originNorth_m;
  out.resolution_m = g.resolution_m;
  out.rows = g.rows;
  out.cols = g.cols;
  // Borrowed, not copied: the serializer reads it during the write.
  out.cells._buffer = const_cast<uint8_t*>(g.cells.data());
  out.cells._length = static_cast<uint32_t>(g.cells.size());
  out.cells._maximum = out.cells._length;
  out.cells._release = false;
}

void fromSample(const vp_msg_OccupancyGrid& in, messages::OccupancyGrid& grid) {
  grid.droneId = in.drone_id;
  grid.time_ns = in.time_ns;
  grid.originEast_m = in.origin_east_m;
  grid.originNorth_m = in.origin_north_m;
  grid.resolution_m = in.resolution_m;
  grid.rows = in.rows;
  grid.cols = in.cols;
  grid.cells.assign(in.cells._buffer, in.cells._buffer + in.cells._length);
}

}  // namespace vp::platform::dds
