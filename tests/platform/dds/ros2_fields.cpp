// tests/platform/dds/ros2_fields: the reader's lines for our values (see the header).
#include "ros2_fields.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace vp::test::ros2 {

// The reader's printing rules: doubles %.17g, floats %.9g, integers in decimal.
std::string text(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  return buffer;
}
std::string textF(float value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.9g", static_cast<double>(value));
  return buffer;
}
std::string textI(long long value) {
  return std::to_string(value);
}

void putTime(Fields& f, const std::string& key, std::int64_t time_ns) {
  f[key + ".sec"] = textI(time_ns / 1'000'000'000);
  f[key + ".nanosec"] = textI(time_ns % 1'000'000'000);
}

void putHeader(Fields& f, const std::string& topic, std::int64_t time_ns,
               const std::string& frame) {
  putTime(f, topic + ".header.stamp", time_ns);
  f[topic + ".header.frame_id"] = frame;
}

void putGeodetic(Fields& f, const std::string& key, const geodesy::GeodeticPoint& p) {
  f[key + ".latitude_deg"] = text(p.latitude_deg);
  f[key + ".longitude_deg"] = text(p.longitude_deg);
  f[key + ".height_m"] = text(p.height_m);
}

void putPoint(Fields& f, const std::string& key, double x, double y, double z) {
  f[key + ".x"] = text(x);
  f[key + ".y"] = text(y);
  f[key + ".z"] = text(z);
}

void putState(Fields& f, const std::string& key, const messages::VehicleState& s) {
  f[key + ".drone_id"] = textI(s.droneId);
  f[key + ".track_id"] = textI(s.trackId);
  putTime(f, key + ".measurement_time", s.measurementTime_ns);
  f[key + ".track_age_s"] = textF(s.trackAge_s);
  putGeodetic(f, key + ".position", s.position);
  putPoint(f, key + ".enu_m", s.enu_m[0], s.enu_m[1], s.enu_m[2]);
  f[key + ".heading_enu_rad"] = text(s.headingEnu_rad);
  f[key + ".heading_true_north_deg"] = text(s.headingTrueNorth_deg);
  f[key + ".speed_mps"] = textF(s.speed_mps);
  f[key + ".velocity_enu_mps.0"] = textF(s.velocityEnu_mps[0]);
  f[key + ".velocity_enu_mps.1"] = textF(s.velocityEnu_mps[1]);
  f[key + ".yaw_rate_radps"] = textF(s.yawRate_radps);
  f[key + ".acceleration_mps2"] = textF(s.acceleration_mps2);
  f[key + ".length_m"] = textF(s.length_m);
  f[key + ".width_m"] = textF(s.width_m);
  f[key + ".height_m"] = textF(s.height_m);
  f[key + ".type"] = textI(static_cast<int>(s.type));
  for (std::size_t k = 0; k < s.typeProbability.size(); ++k) {
    f[key + ".type_probability." + std::to_string(k)] = textF(s.typeProbability[k]);
  }
  f[key + ".asm_gamma.length"] = textI(s.shape.count);
  for (int k = 0; k < s.shape.count; ++k) {
    f[key + ".asm_gamma." + std::to_string(k)] = textF(s.shape.gamma[static_cast<std::size_t>(k)]);
  }
  for (std::size_t k = 0; k < 6; ++k) {
    f[key + ".pose_covariance." + std::to_string(k)] = textF(s.poseCovariance[k]);
  }
  f[key + ".height_variance_m2"] = textF(s.heightVariance_m2);
  f[key + ".speed_variance_m2ps2"] = textF(s.speedVariance_m2ps2);
  f[key + ".yaw_rate_variance_rad2ps2"] = textF(s.yawRateVariance_rad2ps2);
  f[key + ".detection_confidence"] = textF(s.detectionConfidence);
  f[key + ".status"] = textI(static_cast<int>(s.status));
  f[key + ".utm_zone"] = textI(s.utmZone);
  f[key + ".utm_northern_hemisphere"] = textI(s.utmNorthernHemisphere ? 1 : 0);
  f[key + ".utm_easting_m"] = text(s.utmEasting_m);
  f[key + ".utm_northing_m"] = text(s.utmNorthing_m);
  putPoint(f, key + ".rear_axle_enu_m", s.rearAxleEnu_m[0], s.rearAxleEnu_m[1], s.rearAxleEnu_m[2]);
  putGeodetic(f, key + ".rear_axle_position", s.rearAxlePosition);
  f[key + ".length_variance_m2"] = textF(s.lengthVariance_m2);
  f[key + ".width_variance_m2"] = textF(s.widthVariance_m2);
  f[key + ".keypoints_enu_m.length"] = textI(s.keypointCount);
  for (int k = 0; k < s.keypointCount; ++k) {
    const auto& p = s.keypointsEnu_m[static_cast<std::size_t>(k)];
    putPoint(f, key + ".keypoints_enu_m." + std::to_string(k), static_cast<double>(p[0]),
             static_cast<double>(p[1]), static_cast<double>(p[2]));
  }
}

// Autoware's view of a state, from the mapping table of docs/dds.md.
void putObject(Fields& f, const std::string& key, const messages::VehicleState& s) {
  const std::uint8_t uuid[16] = {0,
                                 0,
                                 0,
                                 static_cast<std::uint8_t>(s.droneId),
                                 'v',
                                 'p',
                                 0x80,
                                 0,
                                 0x80,
                                 0,
                                 0,
                                 0,
                                 0,
                                 0,
                                 static_cast<std::uint8_t>(s.trackId >> 8),
                                 static_cast<std::uint8_t>(s.trackId)};
  for (int k = 0; k < 16; ++k) {
    f[key + ".object_id.uuid." + std::to_string(k)] = textI(uuid[k]);
  }
  f[key + ".existence_probability"] = textF(s.detectionConfidence);
  float car = 0.0F;
  for (int k = 0; k < shape::kCarTypeCount; ++k) {
    car += s.typeProbability[static_cast<std::size_t>(k)];
  }
  const float large = s.typeProbability[6];
  const bool truckFirst = large > car;
  f[key + ".classification.length"] = "2";
  f[key + ".classification.0.label"] = truckFirst ? "2" : "1";  // TRUCK : CAR
  f[key + ".classification.0.probability"] = textF(truckFirst ? large : car);
  f[key + ".classification.1.label"] = truckFirst ? "1" : "2";
  f[key + ".classification.1.probability"] = textF(truckFirst ? car : large);
  const std::string kin = key + ".kinematics";
  putPoint(f, kin + ".pose_with_covariance.pose.position", s.enu_m[0], s.enu_m[1],
           s.enu_m[2] + 0.5 * static_cast<double>(s.height_m));
  putPoint(f, kin + ".pose_with_covariance.pose.orientation", 0.0, 0.0,
           std::sin(0.5 * s.headingEnu_rad));
  f[kin + ".pose_with_covariance.pose.orientation.w"] = text(std::cos(0.5 * s.headingEnu_rad));
  std::vector<double> pose(36, 0.0);
  const auto& c = s.poseCovariance;
  pose[0] = c[0];
  pose[1] = pose[6] = c[1];
  pose[5] = pose[30] = c[2];
  pose[7] = c[3];
  pose[11] = pose[31] = c[4];
  pose[35] = c[5];
  pose[14] = static_cast<double>(s.heightVariance_m2) / 4.0;
  std::vector<double> twist(36, 0.0);
  twist[0] = s.speedVariance_m2ps2;
  twist[35] = s.yawRateVariance_rad2ps2;
  for (int k = 0; k < 36; ++k) {
    const std::string i = "." + std::to_string(k);
    f[kin + ".pose_with_covariance.covariance" + i] = text(pose[static_cast<std::size_t>(k)]);
    f[kin + ".twist_with_covariance.covariance" + i] = text(twist[static_cast<std::size_t>(k)]);
    f[kin + ".acceleration_with_covariance.covariance" + i] = "0";
  }
  putPoint(f, kin + ".twist_with_covariance.twist.linear", static_cast<double>(s.speed_mps), 0, 0);
  putPoint(f, kin + ".twist_with_covariance.twist.angular", 0, 0,
           static_cast<double>(s.yawRate_radps));
  putPoint(f, kin + ".acceleration_with_covariance.accel.linear",
           static_cast<double>(s.acceleration_mps2), 0, 0);
  putPoint(f, kin + ".acceleration_with_covariance.accel.angular", 0, 0, 0);
  f[kin + ".orientation_availability"] = "2";  // AVAILABLE
  f[kin + ".is_stationary"] = std::fabs(s.speed_mps) < 0.5F ? "1" : "0";
  f[key + ".shape.type"] = "0";  // BOUNDING_BOX
  f[key + ".shape.footprint.points.length"] = "4";
  const double l = static_cast<double>(0.5F * s.length_m);
  const double w = static_cast<double>(0.5F * s.width_m);
  putPoint(f, key + ".shape.footprint.points.0", l, w, 0);
  putPoint(f, key + ".shape.footprint.points.1", -l, w, 0);
  putPoint(f, key + ".shape.footprint.points.2", -l, -w, 0);
  putPoint(f, key + ".shape.footprint.points.3", l, -w, 0);
  putPoint(f, key + ".shape.dimensions", static_cast<double>(s.length_m),
           static_cast<double>(s.width_m), static_cast<double>(s.height_m));
}

// The reader's output as one field map per message, in arrival order per topic.
std::map<std::string, std::vector<Fields>> parseReader(FILE* pipe) {
  std::map<std::string, std::vector<Fields>> messages;
  char line[4096];
  Fields* current = nullptr;
  while (std::fgets(line, sizeof line, pipe) != nullptr) {
    std::string text(line);
    if (!text.empty() && text.back() == '\n') {
      text.pop_back();
    }
    if (text.rfind("BEGIN ", 0) == 0) {
      current = &messages[text.substr(6)].emplace_back();
    } else if (text.rfind("END ", 0) == 0) {
      current = nullptr;
    } else if (current != nullptr) {
      const std::size_t eq = text.find('=');
      (*current)[text.substr(0, eq)] = text.substr(eq + 1);
    }
  }
  return messages;
}

void expectSame(const Fields& received, const Fields& expected) {
  for (const auto& [key, value] : expected) {
    const auto it = received.find(key);
    if (it == received.end()) {
      ADD_FAILURE() << "missing field " << key;
      continue;
    }
    EXPECT_EQ(it->second, value) << key;
  }
  for (const auto& [key, value] : received) {
    EXPECT_TRUE(expected.count(key) == 1) << "unexpected field " << key << "=" << value;
  }
}

Fields vehicleStateArray(std::int64_t time_ns, const std::string& frameId, std::uint32_t droneId,
                         std::span<const messages::VehicleState> states,
                         std::span<const std::uint32_t> removedTrackIds) {
  Fields f;
  putHeader(f, "vehicle_states", time_ns, frameId);
  f["vehicle_states.drone_id"] = textI(droneId);
  f["vehicle_states.vehicles.length"] = textI(static_cast<long long>(states.size()));
  for (std::size_t k = 0; k < states.size(); ++k) {
    putState(f, "vehicle_states.vehicles." + std::to_string(k), states[k]);
  }
  f["vehicle_states.removed_track_ids.length"] =
      textI(static_cast<long long>(removedTrackIds.size()));
  for (std::size_t k = 0; k < removedTrackIds.size(); ++k) {
    f["vehicle_states.removed_track_ids." + std::to_string(k)] = textI(removedTrackIds[k]);
  }
  return f;
}

Fields trackedObjects(std::int64_t time_ns, const std::string& frameId,
                      std::span<const messages::VehicleState> states) {
  Fields f;
  putHeader(f, "tracked_objects", time_ns, frameId);
  f["tracked_objects.objects.length"] = textI(static_cast<long long>(states.size()));
  for (std::size_t k = 0; k < states.size(); ++k) {
    putObject(f, "tracked_objects.objects." + std::to_string(k), states[k]);
  }
  return f;
}

}  // namespace vp::test::ros2
