#include "geodesy/attitude.hpp"

#include <gtest/gtest.h>

namespace vp::geodesy {
namespace {

constexpr double kTol = 1e-12;

Eigen::Quaterniond bodyAttitude(double roll_deg, double pitch_deg, double yaw_deg) {
  return Eigen::Quaterniond(rotationFromEuler({roll_deg, pitch_deg, yaw_deg}));
}

void expectNear(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double tol = 1e-12) {
  EXPECT_NEAR((a - b).norm(), 0.0, tol) << a.transpose() << " vs " << b.transpose();
}

TEST(Euler, RoundTrip) {
  for (double roll : {-170.0, -30.0, 0.0, 12.5, 179.0}) {
    for (double pitch : {-89.0, -45.0, 0.0, 20.0, 89.0}) {
      for (double yaw : {-179.0, -90.0, 0.0, 45.0, 170.0}) {
        const EulerAnglesDeg e = eulerFromRotation(rotationFromEuler({roll, pitch, yaw}));
        EXPECT_NEAR(e.roll_deg, roll, 1e-9);
        EXPECT_NEAR(e.pitch_deg, pitch, 1e-9);
        EXPECT_NEAR(e.yaw_deg, yaw, 1e-9);
      }
    }
  }
}

TEST(Euler, YawRotatesForwardTowardsRight) {
  // In NED, yaw +90 deg turns the body's forward axis from north to east.
  expectNear(rotationFromEuler({0, 0, 90}) * Eigen::Vector3d::UnitX(), {0, 1, 0});
  // Pitch +30 deg raises the nose: forward gets a negative down component.
  const Eigen::Vector3d forward = rotationFromEuler({0, 30, 0}) * Eigen::Vector3d::UnitX();
  EXPECT_LT(forward.z(), 0.0);
}

TEST(FixedFrames, AreProperRotations) {
  // NED and ENU are both right-handed: the swap is a rotation (180 deg about (1,1,0)/sqrt2).
  for (const Eigen::Matrix3d& m : {enuFromNed(), headFrdFromCamera()}) {
    EXPECT_NEAR((m * m.transpose() - Eigen::Matrix3d::Identity()).norm(), 0.0, kTol);
    EXPECT_NEAR(m.determinant(), 1.0, kTol);
  }
  expectNear(enuFromNed() * Eigen::Vector3d(1, 2, 3), {2, 1, -3});
}

TEST(CameraToEnu, NadirCameraOnNorthFacingDroneGivesNorthUpImage) {
  const Eigen::Matrix3d r = cameraToLocalEnu(bodyAttitude(0, 0, 0), {}, {});
  expectNear(r * Eigen::Vector3d::UnitZ(), {0, 0, -1});  // optical axis down
  expectNear(r * Eigen::Vector3d::UnitX(), {1, 0, 0});   // image right = east
  expectNear(r * Eigen::Vector3d::UnitY(), {0, -1, 0});  // image down = south
  EXPECT_NEAR(r.determinant(), 1.0, kTol);
}

TEST(CameraToEnu, DroneYawTurnsTheImage) {
  // Heading east: the top of the image looks east.
  const Eigen::Matrix3d r = cameraToLocalEnu(bodyAttitude(0, 0, 90), {}, {});
  expectNear(r * -Eigen::Vector3d::UnitY(), {1, 0, 0});
  expectNear(r * Eigen::Vector3d::UnitZ(), {0, 0, -1});
}

TEST(CameraToEnu, TiltedGimbalLooksForwardAndDown) {
  GimbalState gimbal;
  gimbal.angles = {0.0, -70.0, 0.0};  // 20 deg off nadir, towards the nose
  const Eigen::Matrix3d r = cameraToLocalEnu(bodyAttitude(0, 0, 0), {}, gimbal);
  const Eigen::Vector3d axis = r * Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(axis.z(), -std::cos(20.0 * M_PI / 180.0), 1e-12);
  EXPECT_NEAR(axis.y(), std::sin(20.0 * M_PI / 180.0), 1e-12);  // towards north (the nose)
}

TEST(CameraToEnu, BodyRollMovesABodyLockedCameraButNotAnEarthLockedOne) {
  const Eigen::Quaterniond rolled = bodyAttitude(10, 0, 0);
  const Eigen::Matrix3d locked = cameraToLocalEnu(rolled, {}, {});
  const Eigen::Vector3d axis = locked * Eigen::Vector3d::UnitZ();
  // Rolling right (right wing down) swings a nadir camera's view to the left: west.
  EXPECT_LT(axis.x(), -0.1);
  GimbalState earth;
  earth.reference = GimbalReference::Earth;
  const Eigen::Matrix3d stabilised = cameraToLocalEnu(rolled, {}, earth);
  expectNear(stabilised * Eigen::Vector3d::UnitZ(), {0, 0, -1});
}

TEST(CameraToEnu, MountYawComposesWithBodyYaw) {
  CameraMount mount;
  mount.bodyToBase = {0.0, 0.0, 90.0};  // camera base turned to the right wing
  const Eigen::Matrix3d a = cameraToLocalEnu(bodyAttitude(0, 0, 0), mount, {});
  const Eigen::Matrix3d b = cameraToLocalEnu(bodyAttitude(0, 0, 90), {}, {});
  EXPECT_NEAR((a - b).norm(), 0.0, kTol);
}

}  // namespace
}  // namespace vp::geodesy
