// lifting/plane_lifter: from image to world for a fixed view of a planar ground, through the
// homography estimated from ground control points (georef/ground_homography), without a pose
// or a DTM: the lifting of a hovering drone without telemetry.
//
// Contract: init() copies the homography, the ground plane and the camera the view implies, and
// borrows the camera model of the frames it lifts from (the pinhole of the undistorted frame,
// or the raw lens model: its pixels are undistorted first) and the world frame; both must
// outlive it. pixelToGround() maps a pixel to the ground plane (east/north through the
// homography, the height from the plane); boxToGround() lifts an image rotated box as
// Lifter::boxToGround() does: its four corners and centre mapped to the ground, the heading from
// the rear to the front edge, length and width along the ground. With boxHeight_m > 0 each ray
// is taken where it is that high above the plane (the camera centre recovered from the
// homography gives the rays) and the ground below that point is returned. Every failure is a
// LiftError value: OutsideLens (the pixel is beyond the lens model), NoIntersection (beyond the
// horizon of the view, or a box height at or above the camera). All calls are const,
// allocation-free and never throw.
#pragma once

#include <optional>
#include <string>

#include <Eigen/Core>

#include "camera/camera_model.hpp"
#include "core/expected.hpp"
#include "geodesy/geodesy.hpp"
#include "geometry/rotated_box.hpp"
#include "georef/ground_homography.hpp"
#include "lifting/lifting.hpp"

namespace vp::lifting {

class PlaneLifter {
 public:
  PlaneLifter() = default;

  // Fails when the camera has no valid intrinsics.
  bool init(const georef::GroundHomography& view,
            const std::optional<georef::RecoveredCamera>& recovered,
            const camera::CameraModel& camera, const geodesy::LocalFrame& frame,
            std::string* why = nullptr);
  bool initialised() const { return camera_ != nullptr; }

  Expected<Eigen::Vector3d, LiftError> pixelToGround(const Eigen::Vector2d& pixel) const;
  // World ENU point on (or near) the ground -> pixel of the camera model (through the
  // homography, its east/north only).
  Expected<Eigen::Vector2d, LiftError> groundToPixel(const Eigen::Vector3d& pointEnu) const;
  Expected<GroundBox, LiftError> boxToGround(const geometry::RotatedBox& box,
                                             double boxHeight_m = 0.0) const;
  // Square root of the ground area one pixel covers there (m/px); 0 when it cannot be lifted.
  double groundSampleDistance_m(const Eigen::Vector2d& pixel) const;

  double groundHeightAt(double east, double north) const { return plane_.heightAt(east, north); }
  // The camera recovered from the homography (identity pose when it could not be recovered).
  bool hasCameraPose() const { return hasCamera_; }
  const CameraPoseWorld& cameraPose() const { return cameraPose_; }

 private:
  Expected<Eigen::Vector3d, LiftError> groundBelow(const Eigen::Vector2d& pixel,
                                                   double height_m) const;

  Eigen::Matrix3d imageToGround_{Eigen::Matrix3d::Identity()};
  Eigen::Matrix3d groundToImage_{Eigen::Matrix3d::Identity()};
  georef::GroundPlane plane_{};
  bool hasCamera_ = false;
  CameraPoseWorld cameraPose_{};
  const camera::CameraModel* camera_ = nullptr;
  const geodesy::LocalFrame* frame_ = nullptr;
};

}  // namespace vp::lifting
