// tools/rsu_subscriber/state_format: text formatting of received states.
#include "state_format.hpp"

#include <algorithm>
#include <array>
#include <cstdio>

namespace vp::rsu {
namespace {

void appendDouble(std::string& out, double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  out += buffer;
}
void appendFloat(std::string& out, float value) {
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.9g", static_cast<double>(value));
  out += buffer;
}

// The fields in column order; `emit` gets (name, text) pairs.
template <class Emit>
void forEachField(EventKind kind, const messages::VehicleState& s, double latency_ms, Emit emit) {
  const auto d = [&](const char* name, double v) {
    std::string t;
    appendDouble(t, v);
    emit(name, t, false);
  };
  const auto f = [&](const char* name, float v) {
    std::string t;
    appendFloat(t, v);
    emit(name, t, false);
  };
  const auto i = [&](const char* name, long long v) { emit(name, std::to_string(v), false); };
  const auto str = [&](const char* name, const char* v) { emit(name, v, true); };
  static const char* const kProb[] = {"p_estate", "p_compact", "p_sports", "p_sedan",
                                      "p_suv",    "p_van",     "p_large"};
  static const char* const kGamma[] = {"gamma0", "gamma1", "gamma2", "gamma3",
                                       "gamma4", "gamma5", "gamma6", "gamma7"};
  static const char* const kCov[] = {"cov_ee", "cov_en", "cov_eh", "cov_nn", "cov_nh", "cov_hh"};
  str("event", kind == EventKind::State ? "state" : "disposed");
  i("drone_id", s.droneId);
  i("track_id", s.trackId);
  i("measurement_time_ns", s.measurementTime_ns);
  d("latency_ms", latency_ms);
  str("status", tracking::toString(s.status));
  d("latitude_deg", s.position.latitude_deg);
  d("longitude_deg", s.position.longitude_deg);
  d("height_m", s.position.height_m);
  d("east_m", s.enu_m[0]);
  d("north_m", s.enu_m[1]);
  d("up_m", s.enu_m[2]);
  d("heading_enu_rad", s.headingEnu_rad);
  d("heading_true_north_deg", s.headingTrueNorth_deg);
  f("speed_mps", s.speed_mps);
  f("velocity_east_mps", s.velocityEnu_mps[0]);
  f("velocity_north_mps", s.velocityEnu_mps[1]);
  f("yaw_rate_radps", s.yawRate_radps);
  f("acceleration_mps2", s.acceleration_mps2);
  f("length_m", s.length_m);
  f("width_m", s.width_m);
  f("height_box_m", s.height_m);
  str("type", shape::toString(s.type));
  for (int k = 0; k < shape::kVehicleTypeCount; ++k) {
    f(kProb[k], s.typeProbability[static_cast<std::size_t>(k)]);
  }
  i("shape_count", s.shape.count);
  for (int k = 0; k < shape::kMaxShapeComponents; ++k) {
    f(kGamma[k], s.shape.gamma[static_cast<std::size_t>(k)]);
  }
  for (int k = 0; k < 6; ++k) {
    f(kCov[k], s.poseCovariance[static_cast<std::size_t>(k)]);
  }
  f("height_variance_m2", s.heightVariance_m2);
  f("speed_variance_m2ps2", s.speedVariance_m2ps2);
  f("yaw_rate_variance_rad2ps2", s.yawRateVariance_rad2ps2);
  f("detection_confidence", s.detectionConfidence);
  f("track_age_s", s.trackAge_s);
  i("utm_zone", s.utmZone);
  str("utm_hemisphere", s.utmNorthernHemisphere ? "N" : "S");
  d("utm_easting_m", s.utmEasting_m);
  d("utm_northing_m", s.utmNorthing_m);
  d("rear_axle_east_m", s.rearAxleEnu_m[0]);
  d("rear_axle_north_m", s.rearAxleEnu_m[1]);
  d("rear_axle_up_m", s.rearAxleEnu_m[2]);
  d("rear_axle_latitude_deg", s.rearAxlePosition.latitude_deg);
  d("rear_axle_longitude_deg", s.rearAxlePosition.longitude_deg);
  d("rear_axle_height_m", s.rearAxlePosition.height_m);
  f("length_variance_m2", s.lengthVariance_m2);
  f("width_variance_m2", s.widthVariance_m2);
  i("keypoint_count", s.keypointCount);
  // Every keypoint slot (fixed columns; beyond keypoint_count they are 0).
  static const std::array<std::string, 3 * shape::kKeypointCount> kKeypointColumns = [] {
    std::array<std::string, 3 * shape::kKeypointCount> names;
    const char* const axes[3] = {"e", "n", "u"};
    for (std::size_t k = 0; k < names.size(); ++k) {
      names[k] = "kp" + std::to_string(k / 3) + "_" + axes[k % 3] + "_m";
    }
    return names;
  }();
  for (std::size_t k = 0; k < kKeypointColumns.size(); ++k) {
    f(kKeypointColumns[k].c_str(), s.keypointsEnu_m[k / 3][k % 3]);
  }
}

}  // namespace

const std::string& csvHeader() {
  static const std::string header = [] {
    std::string h;
    forEachField(EventKind::State, messages::VehicleState{}, 0.0,
                 [&](const char* name, const std::string&, bool) {
                   h += h.empty() ? "" : ",";
                   h += name;
                 });
    return h;
  }();
  return header;
}

std::string formatCsv(EventKind kind, const messages::VehicleState& state, double latency_ms) {
  std::string row;
  forEachField(kind, state, latency_ms, [&](const char*, const std::string& text, bool) {
    row += row.empty() ? "" : ",";
    row += text;
  });
  return row;
}

std::string formatJson(EventKind kind, const messages::VehicleState& state, double latency_ms) {
  std::string line = "{";
  forEachField(kind, state, latency_ms,
               [&](const char* name, const std::string& text, bool quoted) {
                 line += line.size() > 1 ? "," : "";
                 line += '"';
                 line += name;
                 line += "\":";
                 // NaN/inf cannot appear: the publisher validates every state before writing it.
                 line += quoted ? "\"" + text + "\"" : text;
               });
  return line + "}";
}

std::string LatencyStats::summary() const {
  if (samples_.empty()) {
    return "n=0";
  }
  std::vector<double> sorted = samples_;
  std::sort(sorted.begin(), sorted.end());
  const auto at = [&](double q) {
    return sorted[static_cast<std::size_t>(q * static_cast<double>(sorted.size() - 1) + 0.5)];
  };
  char buffer[160];
  std::snprintf(buffer, sizeof(buffer), "n=%zu median=%.3f ms p99=%.3f ms max=%.3f ms",
                sorted.size(), at(0.5), at(0.99), sorted.back());
  return buffer;
}

}  // namespace vp::rsu
