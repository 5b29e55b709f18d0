// geodesy/attitude: from the autopilot's attitude and the camera mount/gimbal to the
// camera's orientation in the world ENU frame. Conventions are in docs/conventions.md.
//
// Contract:
//  - The autopilot reports the body attitude as a unit quaternion q_nb (w, x, y, z) that
//    rotates vectors from the body frame (FRD: x forward, y right, z down) to the local
//    NED frame, as MAVLink ATTITUDE_QUATERNION and PX4's vehicle_attitude do.
//  - Euler angles are aerospace Tait-Bryan ZYX: R = Rz(yaw) * Ry(pitch) * Rx(roll).
//  - The camera mount is a fixed rotation from the body frame to the gimbal base frame
//    (FRD); the gimbal rotates the camera head relative to that base (body-locked) or
//    relative to NED (earth-locked, as stabilised gimbals report). In the camera head frame
//    (FRD) the optical axis is x; gimbal pitch -90 deg therefore looks straight down.
//  - The camera frame is OpenCV's (x right, y down, z optical axis).
// All functions are pure and allocation-free.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace vp::geodesy {

struct EulerAnglesDeg {
  double roll_deg = 0.0;
  double pitch_deg = 0.0;
  double yaw_deg = 0.0;
};

enum class GimbalReference { Body, Earth };

struct CameraMount {
  EulerAnglesDeg bodyToBase{};                // fixed mount rotation, body FRD -> gimbal base FRD
  Eigen::Vector3d leverArm_m{0.0, 0.0, 0.0};  // camera centre in the body frame, m (FRD)
};

struct GimbalState {
  EulerAnglesDeg angles{0.0, -90.0, 0.0};  // camera head relative to the reference
  GimbalReference reference = GimbalReference::Body;
};

// Rotation matrix of aerospace ZYX Euler angles (maps the rotated frame into the reference).
Eigen::Matrix3d rotationFromEuler(const EulerAnglesDeg& angles);
EulerAnglesDeg eulerFromRotation(const Eigen::Matrix3d& rotation);

// Fixed frame changes.
Eigen::Matrix3d enuFromNed();         // vectors NED -> ENU (its own inverse)
Eigen::Matrix3d headFrdFromCamera();  // vectors OpenCV camera -> camera head FRD

// Orientation of the OpenCV camera frame in the local ENU frame at the drone's position:
// R_enu_cam = R_enu_ned * R_ned_head * R_head_cam.
Eigen::Matrix3d cameraToLocalEnu(const Eigen::Quaterniond& bodyToNed, const CameraMount& mount,
                                 const GimbalState& gimbal);

}  // namespace vp::geodesy
