#include "geodesy/attitude.hpp"

#include <algorithm>
#include <cmath>

namespace vp::geodesy {

namespace {
constexpr double kDegToRad = 3.14159265358979323846 / 180.0;
constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;
}  // namespace

Eigen::Matrix3d rotationFromEuler(const EulerAnglesDeg& angles) {
  const Eigen::AngleAxisd yaw(angles.yaw_deg * kDegToRad, Eigen::Vector3d::UnitZ());
  const Eigen::AngleAxisd pitch(angles.pitch_deg * kDegToRad, Eigen::Vector3d::UnitY());
  const Eigen::AngleAxisd roll(angles.roll_deg * kDegToRad, Eigen::Vector3d::UnitX());
  return (yaw * pitch * roll).toRotationMatrix();
}

EulerAnglesDeg eulerFromRotation(const Eigen::Matrix3d& r) {
  // R = Rz(yaw) Ry(pitch) Rx(roll): r20 = -sin(pitch), r21 = cos(pitch) sin(roll),
  // r22 = cos(pitch) cos(roll), r10 = cos(pitch) sin(yaw), r00 = cos(pitch) cos(yaw).
  EulerAnglesDeg e;
  const double sinPitch = std::clamp(-r(2, 0), -1.0, 1.0);
  e.pitch_deg = std::asin(sinPitch) * kRadToDeg;
  if (std::abs(sinPitch) < 1.0 - 1e-12) {
    e.roll_deg = std::atan2(r(2, 1), r(2, 2)) * kRadToDeg;
    e.yaw_deg = std::atan2(r(1, 0), r(0, 0)) * kRadToDeg;
  } else {
    // Gimbal lock (pitch = +-90 deg): only yaw -+ roll is defined; report it as yaw.
    e.roll_deg = 0.0;
    e.yaw_deg = std::atan2(-r(0, 1), r(1, 1)) * kRadToDeg;
  }
  return e;
}

Eigen::Matrix3d enuFromNed() {
  Eigen::Matrix3d m;
  m << 0, 1, 0,  //
      1, 0, 0,   //
      0, 0, -1;
  return m;
}

Eigen::Matrix3d headFrdFromCamera() {
  // Camera x (right) = head y, camera y (down) = head z, camera z (optical axis) = head x.
  Eigen::Matrix3d m;
  m << 0, 0, 1,  //
      1, 0, 0,   //
      0, 1, 0;
  return m;
}

Eigen::Matrix3d cameraToLocalEnu(const Eigen::Quaterniond& bodyToNed, const CameraMount& mount,
                                 const GimbalState& gimbal) {
  const Eigen::Matrix3d gimbalRotation = rotationFromEuler(gimbal.angles);
  Eigen::Matrix3d nedFromHead;
  if (gimbal.reference == GimbalReference::Earth) {
    // An earth-locked gimbal reports the head's attitude in NED directly.
    nedFromHead = gimbalRotation;
  } else {
    nedFromHead = bodyToNed.normalized().toRotationMatrix() * rotationFromEuler(mount.bodyToBase) *
                  gimbalRotation;
  }
  return enuFromNed() * nedFromHead * headFrdFromCamera();
}

}  // namespace vp::geodesy
