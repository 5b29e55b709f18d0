// camera/camera_model: the intrinsic camera with its lens distortion.
//
// Contract: pixels are (u, v) with u to the right, v down, origin at the centre of the
// top-left pixel. The camera frame is OpenCV's: x right, y down, z along the optical
// axis. Two lens models are supported besides the ideal pinhole:
//  - Brown-Conrady (OpenCV's k1, k2, p1, p2, k3): the same equations as cv::projectPoints,
//    so coefficients from cv::calibrateCamera apply unchanged;
//  - the "equivalent spherical" model of seed 001: with r_d the distorted and r_u the
//    ideal radius in normalised units (pixel offset / focal length),
//    r_u = tan(2 * asin(r_d / 2)), i.e. L2 = f * tan(2 * asin(L1 / (2 f))).
// distort()/undistort() are exact inverses within 1e-3 px inside the valid field of view;
// they never allocate and are safe to call from the real-time loop. init() validates.
#pragma once

#include <optional>
#include <string>

#include <Eigen/Core>

#include "core/expected.hpp"

namespace vp::camera {

struct Intrinsics {
  int width_px = 0;
  int height_px = 0;
  double fx_px = 0.0;  // focal length, px
  double fy_px = 0.0;
  double cx_px = 0.0;  // principal point, px
  double cy_px = 0.0;
};

enum class LensModel { Pinhole, BrownConrady, EquivalentSpherical };

struct Distortion {
  LensModel model = LensModel::Pinhole;
  // Brown-Conrady coefficients (OpenCV order k1, k2, p1, p2, k3); unused otherwise.
  double k1 = 0.0;
  double k2 = 0.0;
  double p1 = 0.0;
  double p2 = 0.0;
  double k3 = 0.0;
};

const char* toString(LensModel model);
std::optional<LensModel> lensModelFromString(const std::string& name);

enum class CameraError {
  PointBehindCamera,  // ray with z <= 0
  OutsideValidField,  // beyond the lens model's valid radius
  NoConvergence,      // iterative undistortion did not converge
};
const char* toString(CameraError error);

class CameraModel {
 public:
  CameraModel() = default;

  // Validates and stores the model. On failure returns false and fills *why (if given)
  // with a message naming the offending value.
  bool init(const Intrinsics& intrinsics, const Distortion& distortion, std::string* why = nullptr);

  const Intrinsics& intrinsics() const { return intrinsics_; }
  const Distortion& distortion() const { return distortion_; }

  // Ideal (undistorted) normalised coordinates -> distorted pixel.
  Eigen::Vector2d distortNormalized(const Eigen::Vector2d& ideal) const;
  // Distorted pixel -> ideal normalised coordinates (x/z, y/z).
  Expected<Eigen::Vector2d, CameraError> undistortToNormalized(const Eigen::Vector2d& pixel) const;

  // Ideal pixel (pinhole with the same intrinsics) <-> distorted pixel.
  Eigen::Vector2d distortPixel(const Eigen::Vector2d& idealPixel) const;
  Expected<Eigen::Vector2d, CameraError> undistortPixel(const Eigen::Vector2d& pixel) const;

  // Distorted pixel -> unit ray in the camera frame.
  Expected<Eigen::Vector3d, CameraError> pixelToRay(const Eigen::Vector2d& pixel) const;
  // Point or direction in the camera frame -> distorted pixel (may lie outside the image).
  Expected<Eigen::Vector2d, CameraError> projectToPixel(const Eigen::Vector3d& pointCamera) const;

  // True when the pixel lies inside the image (with an optional margin, px). The image
  // covers [-0.5, width - 0.5) x [-0.5, height - 0.5): the outer edges of the border pixels.
  bool inImage(const Eigen::Vector2d& pixel, double margin_px = 0.0) const;

  // Valid field of the lens model (normalised radii): ideal points beyond maxIdealRadius()
  // and distorted points beyond maxDistortedRadius() are OutsideValidField. For
  // Brown-Conrady it ends where the radial polynomial stops increasing (fold-over); for
  // the spherical model just short of 90 deg off-axis; the pinhole has none (infinity).
  double maxIdealRadius() const { return maxIdealRadius_; }
  double maxDistortedRadius() const { return maxDistortedRadius_; }

 private:
  Intrinsics intrinsics_{};
  Distortion distortion_{};
  double maxIdealRadius_ = 1e9;      // normalised, valid field for the lens model
  double maxDistortedRadius_ = 1e9;  // normalised
};

}  // namespace vp::camera
