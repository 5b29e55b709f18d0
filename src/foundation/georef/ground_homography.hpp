// georef/ground_homography: the image -> ground homography of a fixed view from ground control
// points (GCPs), for a camera that does not move (a hovering drone without telemetry).
//
// Contract: estimateGroundHomography() takes at least 4 control points, each an ideal (lens
// distortion removed) pixel of the calibrated pinhole camera and its ground point in the world
// ENU frame, refuses degenerate sets with a message naming the points (fewer than 4, the same
// id twice, two points at the same pixel or the same ground position, all points or all but one
// on one line in the image or on the ground), and otherwise estimates the homography that maps
// pixels to ground east/north: normalised DLT over all points (Hartley's normalisation: each
// side moved to its centroid and scaled to a mean distance of sqrt 2), then Levenberg–Marquardt
// on the sum of squared ground distances (m) over all points. The ground's height is the plane
// z = a + b·east + c·north fitted to the points by least squares (a slope is still a plane, so
// the view of it is still a homography). It reports, per point, the ground residual (m: the
// pixel mapped to the ground minus the surveyed point, east/north) and the image residual (px:
// the ground point mapped back to the image). recoverCamera() decomposes the homography with the
// camera's intrinsics into the camera's centre and orientation (used to lift points that stand
// above the ground, and to draw). Pure start-up code: it allocates and never throws.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "camera/camera_model.hpp"

namespace vp::georef {

struct ControlPoint {
  std::string id;
  Eigen::Vector2d pixel{0.0, 0.0};                     // ideal pinhole pixel, px
  Eigen::Vector3d groundEnu{Eigen::Vector3d::Zero()};  // world ENU, m
};

struct PointResidual {
  std::string id;
  Eigen::Vector2d groundError_m{0.0, 0.0};     // pixel lifted minus surveyed point, east/north, m
  double ground_m = 0.0;                       // its length
  Eigen::Vector2d reprojectedPixel{0.0, 0.0};  // the surveyed point mapped into the image, px
  double image_px = 0.0;                       // distance to the given pixel
};

// The ground as a plane z = a + b·east + c·north (world ENU, m).
struct GroundPlane {
  double a = 0.0;
  double b = 0.0;
  double c = 0.0;
  double heightAt(double east, double north) const { return a + b * east + c * north; }
};

struct HomographyOptions {
  // Points closer than this are the same point (a duplicate row): image px, ground m.
  double samePixel_px = 1.0;
  double sameGround_m = 0.05;
  // A point is on the line through two others when it lies within this share of the set's
  // spread (RMS distance from the centroid) of that line; 4 points with no 3 on a line are
  // needed, and a set that is nearly on a line gives an ill-conditioned homography.
  double collinearShare = 0.01;
  int maxIterations = 100;  // Levenberg–Marquardt
};

struct GroundHomography {
  Eigen::Matrix3d imageToGround{Eigen::Matrix3d::Identity()};  // (u, v, 1) -> (E, N, w), w > 0
  Eigen::Matrix3d groundToImage{Eigen::Matrix3d::Identity()};  // its inverse
  GroundPlane plane{};
  std::vector<PointResidual> residuals;  // in the order of the points given
  double rms_m = 0.0;                    // RMS of the ground residuals
  double max_m = 0.0;                    // largest ground residual
  std::size_t maxIndex = 0;              // whose
  int iterations = 0;                    // Levenberg–Marquardt steps taken
  double initialRms_m = 0.0;             // RMS of the DLT alone, before refinement
};

// Fails (false, *why naming the points) on a degenerate set.
bool estimateGroundHomography(std::span<const ControlPoint> points,
                              const HomographyOptions& options, GroundHomography* out,
                              std::string* why);

// Ideal pixel -> ground east/north; nullopt beyond the horizon (w <= 0).
std::optional<Eigen::Vector2d> mapToGround(const Eigen::Matrix3d& imageToGround,
                                           const Eigen::Vector2d& pixel);
// Ground east/north -> ideal pixel; nullopt behind the camera.
std::optional<Eigen::Vector2d> mapToImage(const Eigen::Matrix3d& groundToImage,
                                          const Eigen::Vector2d& groundEn);

struct RecoveredCamera {
  Eigen::Vector3d centreEnu{Eigen::Vector3d::Zero()};        // projection centre, m
  Eigen::Matrix3d cameraToEnu{Eigen::Matrix3d::Identity()};  // OpenCV camera -> world ENU
  double heightAboveGround_m = 0.0;                          // above the plane, vertically
};

// The camera the homography implies, given the pinhole intrinsics; nullopt when the
// decomposition is not a camera above the plane looking at it.
std::optional<RecoveredCamera> recoverCamera(const GroundHomography& view,
                                             const camera::Intrinsics& intrinsics);

}  // namespace vp::georef
