// platform/dds/telemetry_conversion: ROS 2 telemetry samples -> PoseSample.
#include "platform/dds/telemetry_conversion.hpp"

#include <cmath>

#include "geodesy/attitude.hpp"

namespace vp::platform::dds {
namespace {

constexpr std::int64_t kNsPerS = 1'000'000'000;
constexpr std::int64_t kNsPer_us = 1'000;

// Body FLU <-> FRD: y and z change sign (its own inverse).
Eigen::Matrix3d frdFromFlu() {
  return Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();
}

// A unit quaternion from (w, x, y, z), renormalised, with w >= 0 (q and -q are one rotation;
// one sign makes samples comparable).
TelemetryRejection unitQuaternion(double w, double x, double y, double z, Eigen::Quaterniond& q) {
  if (!std::isfinite(w) || !std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
    return TelemetryRejection::NonFinite;
  }
  q = Eigen::Quaterniond(w, x, y, z);
  const double norm = q.norm();
  if (std::abs(norm - 1.0) > kUnitQuaternionTolerance) {
    return TelemetryRejection::NotUnitQuaternion;
  }
  q.coeffs() /= norm;
  if (q.w() < 0.0) {
    q.coeffs() = -q.coeffs();
  }
  return TelemetryRejection::None;
}

TelemetryRejection checkPosition(double latitude_deg, double longitude_deg, double height_m) {
  if (!std::isfinite(latitude_deg) || !std::isfinite(longitude_deg) || !std::isfinite(height_m)) {
    return TelemetryRejection::NonFinite;
  }
  if (std::abs(latitude_deg) > 90.0 || std::abs(longitude_deg) > 180.0) {
    return TelemetryRejection::PositionOutOfRange;
  }
  return TelemetryRejection::None;
}

// PX4's time of validity is timestamp_sample (when the raw data was taken); timestamp is when
// the estimate was published. A publisher that leaves timestamp_sample 0 gets timestamp.
std::int64_t validityTime_ns(std::uint64_t timestamp_us, std::uint64_t timestampSample_us) {
  const std::uint64_t us = timestampSample_us != 0 ? timestampSample_us : timestamp_us;
  return static_cast<std::int64_t>(us) * kNsPer_us;
}

Eigen::Quaterniond canonical(const Eigen::Quaterniond& q) {
  return q.w() < 0.0 ? Eigen::Quaterniond(-q.coeffs()) : q;
}

}  // namespace

const char* toString(PoseSource source) {
  switch (source) {
    case PoseSource::ArduPilotGeoPose:
      return "ardupilot geopose";
    case PoseSource::Px4Attitude:
      return "px4 vehicle_attitude";
    case PoseSource::Px4GlobalPosition:
      return "px4 vehicle_global_position";
  }
  return "unknown";
}

const char* toString(TelemetryRejection rejection) {
  switch (rejection) {
    case TelemetryRejection::None:
      return "none";
    case TelemetryRejection::NonFinite:
      return "non-finite value";
    case TelemetryRejection::NotUnitQuaternion:
      return "quaternion not of unit length";
    case TelemetryRejection::PositionOutOfRange:
      return "latitude/longitude out of range";
  }
  return "unknown";
}

Eigen::Quaterniond nedFrdFromEnuFlu(const Eigen::Quaterniond& enuFlu) {
  // R_ned_frd = R_ned_enu * R_enu_flu * R_flu_frd; the two outer factors are reflections
  // (det -1) but their product with a rotation is a rotation again.
  const Eigen::Matrix3d nedFrd =
      geodesy::enuFromNed() * enuFlu.normalized().toRotationMatrix() * frdFromFlu();
  return canonical(Eigen::Quaterniond(nedFrd).normalized());
}

Eigen::Quaterniond enuFluFromNedFrd(const Eigen::Quaterniond& nedFrd) {
  const Eigen::Matrix3d enuFlu =
      geodesy::enuFromNed() * nedFrd.normalized().toRotationMatrix() * frdFromFlu();
  return canonical(Eigen::Quaterniond(enuFlu).normalized());
}

TelemetryRejection fromGeoPose(const geographic_msgs_msg_dds__GeoPoseStamped_& message,
                               double altitudeOffset_m, PoseSample& out) {
  const auto& position = message.pose.position;
  const double height = position.altitude + altitudeOffset_m;
  if (const TelemetryRejection r = checkPosition(position.latitude, position.longitude, height);
      r != TelemetryRejection::None) {
    return r;
  }
  const auto& o = message.pose.orientation;
  Eigen::Quaterniond enuFlu;
  if (const TelemetryRejection r = unitQuaternion(o.w, o.x, o.y, o.z, enuFlu);
      r != TelemetryRejection::None) {
    return r;
  }
  out.source = PoseSource::ArduPilotGeoPose;
  out.hasPosition = true;
  out.hasAttitude = true;
  const std::int64_t sec = message.header.stamp.sec;
  out.time_ns = sec * kNsPerS + static_cast<std::int64_t>(message.header.stamp.nanosec);
  out.timeBase =
      sec >= kUtcStampThreshold_s ? TelemetryTimeBase::Utc : TelemetryTimeBase::AutopilotBoot;
  out.position = {position.latitude, position.longitude, height};
  out.bodyToNed = nedFrdFromEnuFlu(enuFlu);
  out.horizontalStd_m = std::numeric_limits<float>::quiet_NaN();
  out.verticalStd_m = std::numeric_limits<float>::quiet_NaN();
  return TelemetryRejection::None;
}

TelemetryRejection fromPx4Attitude(const px4_msgs_msg_dds__VehicleAttitude_& message,
                                   PoseSample& out) {
  // PX4's q is already ours: Hamilton (w, x, y, z), body FRD -> NED.
  Eigen::Quaterniond q;
  if (const TelemetryRejection r =
          unitQuaternion(message.q[0], message.q[1], message.q[2], message.q[3], q);
      r != TelemetryRejection::None) {
    return r;
  }
  out.source = PoseSource::Px4Attitude;
  out.hasPosition = false;
  out.hasAttitude = true;
  out.time_ns = validityTime_ns(message.timestamp, message.timestamp_sample);
  out.timeBase = TelemetryTimeBase::AutopilotBoot;
  out.bodyToNed = q;
  out.horizontalStd_m = std::numeric_limits<float>::quiet_NaN();
  out.verticalStd_m = std::numeric_limits<float>::quiet_NaN();
  return TelemetryRejection::None;
}

TelemetryRejection fromPx4GlobalPosition(const px4_msgs_msg_dds__VehicleGlobalPosition_& message,
                                         PoseSample& out) {
  const double height = message.alt_ellipsoid;
  if (const TelemetryRejection r = checkPosition(message.lat, message.lon, height);
      r != TelemetryRejection::None) {
    return r;
  }
  out.source = PoseSource::Px4GlobalPosition;
  out.hasPosition = true;
  out.hasAttitude = false;
  out.time_ns = validityTime_ns(message.timestamp, message.timestamp_sample);
  out.timeBase = TelemetryTimeBase::AutopilotBoot;
  out.position = {message.lat, message.lon, height};
  out.horizontalStd_m = message.eph;
  out.verticalStd_m = message.epv;
  return TelemetryRejection::None;
}

}  // namespace vp::platform::dds
