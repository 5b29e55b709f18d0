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
  return geodesy::eulerFromRotation(q.toRotationMatrix()).yawDeg / kRadToDeg;
}

}  // namespace

void BootClockMapper::observe(std::uint32_t bootMs, std::int64_t receiveNs) {
  if (count_ > 0 && bootMs + kRebootJumpMs < lastBootMs_) {
    count_ = 0;
    next_ = 0;
    ++restarts_;
  }
  lastBootMs_ = bootMs;
  offsets_[next_] = receiveNs - static_cast<std::int64_t>(bootMs) * 1'000'000;
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
                               std::int64_t receiveNs) {
  if (config_.systemId != 0 && systemId != config_.systemId) {
    ++counters_.otherSystem;
    return false;
  }
  receiveNs -= config_.linkLatencyNs;
  if (const auto* q = std::get_if<AttitudeQuaternion>(&message)) {
    if (!quaternionOk(q->q)) {
      ++counters_.rejected;
      return false;
    }
    sawQuaternion_ = true;
    return addAttitude(q->timeBootMs, toQuaternion(q->q), receiveNs);
  }
  if (const auto* a = std::get_if<Attitude>(&message)) {
    if (sawQuaternion_) {
      return false;  // the quaternion stream is the attitude source
    }
    if (!std::isfinite(a->rollRad) || !std::isfinite(a->pitchRad) || !std::isfinite(a->yawRad)) {
      ++counters_.rejected;
      return false;
    }
    const geodesy::EulerAnglesDeg euler{static_cast<double>(a->rollRad) * kRadToDeg,
                                        static_cast<double>(a->pitchRad) * kRadToDeg,
                                        static_cast<double>(a->yawRad) * kRadToDeg};
    return addAttitude(a->timeBootMs, Eigen::Quaterniond(geodesy::rotationFromEuler(euler)),
                       receiveNs);
  }
  if (const auto* p = std::get_if<GlobalPositionInt>(&message)) {
    return addPosition(*p, receiveNs);
  }
  if (const auto* g = std::get_if<GimbalDeviceAttitudeStatus>(&message)) {
    return addGimbal(*g, receiveNs);
  }
  return false;
}

bool MavlinkPoseAssembler::addAttitude(std::uint32_t timeBootMs,
                                       const Eigen::Quaterniond& bodyToNed,
                                       std::int64_t receiveNs) {
  autopilotClock_.observe(timeBootMs, receiveNs);
  latestYawRad_ = yawOf(bodyToNed);
  hasAttitude_ = true;
  if (!hasPosition_) {
    ++counters_.noPositionYet;
    return false;
  }
  sample_.timestampNs = autopilotClock_.toLocalNs(timeBootMs);
  sample_.bodyToNed = bodyToNed;
  ++counters_.samples;
  return true;
}

bool MavlinkPoseAssembler::addPosition(const GlobalPositionInt& m, std::int64_t receiveNs) {
  geodesy::GeodeticPoint point;
  point.latitudeDeg = m.latitudeDegE7 * kDegE7;
  point.longitudeDeg = m.longitudeDegE7 * kDegE7;
  point.heightM = m.altitudeMslMm * kMmToM + config_.geoidSeparationM;
  if (!geodesy::isValid(point)) {
    ++counters_.rejected;
    return false;
  }
  autopilotClock_.observe(m.timeBootMs, receiveNs);
  sample_.position = point;
  sample_.positionTimestampNs = autopilotClock_.toLocalNs(m.timeBootMs);
  hasPosition_ = true;
  return false;
}

bool MavlinkPoseAssembler::addGimbal(const GimbalDeviceAttitudeStatus& m, std::int64_t receiveNs) {
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
    if (!hasAttitude_ && !(vehicleFlag && std::isfinite(m.deltaYawRad) && m.hasExtensions)) {
      ++counters_.rejected;  // a vehicle-relative yaw needs the vehicle's heading
      return false;
    }
    // delta_yaw is only meaningful with the new frame flags (common.xml).
    const double deltaYawRad = (vehicleFlag && m.hasExtensions && std::isfinite(m.deltaYawRad))
                                   ? static_cast<double>(m.deltaYawRad)
                                   : latestYawRad_;
    headToNed = Eigen::AngleAxisd(deltaYawRad, Eigen::Vector3d::UnitZ()) * headToNed;
  }
  gimbalClock_.observe(m.timeBootMs, receiveNs);
  sample_.hasGimbal = true;
  sample_.gimbal.reference = geodesy::GimbalReference::Earth;
  sample_.gimbal.angles = geodesy::eulerFromRotation(headToNed.toRotationMatrix());
  sample_.gimbalTimestampNs = gimbalClock_.toLocalNs(m.timeBootMs);
  return false;
}

}  // namespace vp::mavlink
