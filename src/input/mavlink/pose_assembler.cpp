#include "mavlink/pose_assembler.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace vp::mavlink {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr double kDegE7 = 1e-7;
constexpr double kMmToM = 1e-3;

Eigen::Quaterniond toQuaternion(const std::array<float, 4>& q) {
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized();
}

double yawOf(const Eigen::Quaterniond& q) {
  return geodesy::eulerFromRotation(q.toRotationMatrix()).yaw_deg / kRadToDeg;
}

}  // namespace

void BootClockMapper::observe(std::uint32_t boot_ms, std::int64_t receive_ns) {
  if (count_ > 0 && boot_ms + kRebootJump_ms < lastBootMs_) {
    count_ = 0;
    next_ = 0;
    ++restarts_;
  }
  lastBootMs_ = boot_ms;
  offsets_[next_] = receive_ns - static_cast<std::int64_t>(boot_ms) * 1'000'000;
  next_ = (next_ + 1) % kWindow;
  count_ = std::min(count_ + 1, kWindow);
  offsetNs_ = *std::min_element(offsets_.begin(), offsets_.begin() + static_cast<long>(count_));
}

bool MavlinkPoseAssembler::quaternionOk(const std::array<float, 4>& q) const {
  double norm2 = 0.0;
  for (const float c : q) {
    if (!std::isfinite(c)) {
      return false;
    }
    norm2 += static_cast<double>(c) * static_cast<double>(c);
  }
  return std::abs(std::sqrt(norm2) - 1.0) <= config_.quaternionNormTolerance;
}

bool MavlinkPoseAssembler::add(const Message& message, std::uint8_t systemId,
                               std::int64_t receive_ns) {
  if (config_.systemId != 0 && systemId != config_.systemId) {
    ++counters_.otherSystem;
    return false;
  }
  receive_ns -= config_.linkLatency_ns;
  if (const auto* q = std::get_if<AttitudeQuaternion>(&message)) {
    if (!quaternionOk(q->q)) {
      ++counters_.rejected;
      return false;
    }
    sawQuaternion_ = true;
    return addAttitude(q->timeBoot_ms, toQuaternion(q->q), receive_ns);
  }
  if (const auto* a = std::get_if<Attitude>(&message)) {
    if (sawQuaternion_) {
      return false;  // the quaternion stream is the attitude source
    }
    if (!std::isfinite(a->roll_rad) || !std::isfinite(a->pitch_rad) || !std::isfinite(a->yaw_rad)) {
      ++counters_.rejected;
      return false;
    }
    const geodesy::EulerAnglesDeg euler{static_cast<double>(a->roll_rad) * kRadToDeg,
                                        static_cast<double>(a->pitch_rad) * kRadToDeg,
                                        static_cast<double>(a->yaw_rad) * kRadToDeg};
    return addAttitude(a->timeBoot_ms, Eigen::Quaterniond(geodesy::rotationFromEuler(euler)),
                       receive_ns);
  }
  if (const auto* p = std::get_if<GlobalPositionInt>(&message)) {
    return addPosition(*p, receive_ns);
  }
  if (const auto* g = std::get_if<GimbalDeviceAttitudeStatus>(&message)) {
    return addGimbal(*g, receive_ns);
  }
  return false;
}

bool MavlinkPoseAssembler::addAttitude(std::uint32_t timeBoot_ms,
                                       const Eigen::Quaterniond& bodyToNed,
                                       std::int64_t receive_ns) {
  autopilotClock_.observe(timeBoot_ms, receive_ns);
  latestYawRad_ = yawOf(bodyToNed);
  hasAttitude_ = true;
  if (!hasPosition_) {
    ++counters_.noPositionYet;
    return false;
  }
  sample_.timestamp_ns = autopilotClock_.toLocal_ns(timeBoot_ms);
  sample_.bodyToNed = bodyToNed;
  ++counters_.samples;
  return true;
}

bool MavlinkPoseAssembler::addPosition(const GlobalPositionInt& m, std::int64_t receive_ns) {
  geodesy::GeodeticPoint point;
  point.latitude_deg = m.latitude_degE7 * kDegE7;
  point.longitude_deg = m.longitude_degE7 * kDegE7;
  point.height_m = m.altitudeMsl_mm * kMmToM + config_.geoidSeparation_m;
  if (!geodesy::isValid(point)) {
    ++counters_.rejected;
    return false;
  }
  autopilotClock_.observe(m.timeBoot_ms, receive_ns);
  sample_.position = point;
  sample_.positionTimestamp_ns = autopilotClock_.toLocal_ns(m.timeBoot_ms);
  hasPosition_ = true;
  return false;
}

bool MavlinkPoseAssembler::addGimbal(const GimbalDeviceAttitudeStatus& m, std::int64_t receive_ns) {
  const bool vehicleFlag = (m.flags & kGimbalFlagYawInVehicleFrame) != 0;
  const bool earthFlag = (m.flags & kGimbalFlagYawInEarthFrame) != 0;
  if ((vehicleFlag && earthFlag) || !quaternionOk(m.q)) {
    ++counters_.rejected;
    return false;
  }
  // Without the new flags, the older YAW_LOCK flag says "yaw relative to north".
  const bool yawInEarth = earthFlag || (!vehicleFlag && (m.flags & kGimbalFlagYawLock) != 0);
  Eigen::Quaterniond headToNed = toQuaternion(m.q);
  if (!yawInEarth) {
    if (!hasAttitude_ && !(vehicleFlag && std::isfinite(m.deltaYaw_rad) && m.hasExtensions)) {
      ++counters_.rejected;  // a vehicle-relative yaw needs the vehicle's heading
      return false;
    }
    // delta_yaw is only meaningful with the new frame flags (common.xml).
    const double deltaYaw_rad = (vehicleFlag && m.hasExtensions && std::isfinite(m.deltaYaw_rad))
                                    ? static_cast<double>(m.deltaYaw_rad)
                                    : latestYawRad_;
    headToNed = Eigen::AngleAxisd(deltaYaw_rad, Eigen::Vector3d::UnitZ()) * headToNed;
  }
  gimbalClock_.observe(m.timeBoot_ms, receive_ns);
  sample_.hasGimbal = true;
  sample_.gimbal.reference = geodesy::GimbalReference::Earth;
  sample_.gimbal.angles = geodesy::eulerFromRotation(headToNed.toRotationMatrix());
  sample_.gimbalTimestamp_ns = gimbalClock_.toLocal_ns(m.timeBoot_ms);
  return false;
}

}  // namespace vp::mavlink
