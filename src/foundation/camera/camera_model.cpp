#include "camera/camera_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

namespace vp::camera {

namespace {

// The equivalent spherical model maps a distorted radius r_d to the field angle
// 2*asin(r_d/2), which reaches 90 deg at r_d = sqrt(2) where the ideal radius tan(angle)
// diverges. Stop 1 mrad short of it so every radius inside the field stays finite.
constexpr double kSphericalMaxFieldAngle_rad = std::numbers::pi / 2.0 - 1e-3;

// Undistortion stops once the distortion of the estimate reproduces the input within this
// (normalised) residual; with a Jacobian near identity the error of the ideal point is of
// the same order, far below the 1e-9 the contract promises.
constexpr double kUndistortResidualTol = 1e-12;
constexpr int kUndistortMaxIterations = 50;
// Halvings of a Newton step that increases the residual before we give up.
constexpr int kMaxStepHalvings = 30;

// Samples per image-corner radius when searching the monotonic range of the polynomial:
// dense enough that no fold-over can hide between two samples for realistic coefficients.
constexpr int kFieldSamplesPerCornerRadius = 2000;
// The search covers at least this many corner radii, both ideal and distorted.
constexpr double kFieldSearchCornerRadii = 3.0;
// ...and never more than this many, for polynomials that stay monotonic for ever.
constexpr double kFieldSearchCapCornerRadii = 30.0;

std::string formatValue(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

bool fail(std::string* why, const std::string& message) {
  if (why != nullptr) {
    *why = message;
  }
  return false;
}

// Brown-Conrady radial profile along a ray: r * (1 + k1 r^2 + k2 r^4 + k3 r^6).
double radialProfile(const Distortion& d, double r) {
  const double r2 = r * r;
  return r * (1.0 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3)));
}

double radialProfileDerivative(const Distortion& d, double r) {
  const double r2 = r * r;
  return 1.0 + r2 * (3.0 * d.k1 + r2 * (5.0 * d.k2 + r2 * 7.0 * d.k3));
}

struct BrownConradyEval {
  Eigen::Vector2d distorted;
  Eigen::Matrix2d jacobian;  // d distorted / d ideal
};

BrownConradyEval brownConradyWithJacobian(const Distortion& d, const Eigen::Vector2d& ideal) {
  const double x = ideal.x();
  const double y = ideal.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
  const double dRadialDr2 = d.k1 + r2 * (2.0 * d.k2 + r2 * 3.0 * d.k3);
  BrownConradyEval out;
  out.distorted.x() = x * radial + 2.0 * d.p1 * x * y + d.p2 * (r2 + 2.0 * x * x);
  out.distorted.y() = y * radial + d.p1 * (r2 + 2.0 * y * y) + 2.0 * d.p2 * x * y;
  const double offDiagonal = 2.0 * x * y * dRadialDr2 + 2.0 * d.p1 * x + 2.0 * d.p2 * y;
  out.jacobian(0, 0) = radial + 2.0 * x * x * dRadialDr2 + 2.0 * d.p1 * y + 6.0 * d.p2 * x;
  out.jacobian(0, 1) = offDiagonal;
  out.jacobian(1, 0) = offDiagonal;
  out.jacobian(1, 1) = radial + 2.0 * y * y * dRadialDr2 + 6.0 * d.p1 * y + 2.0 * d.p2 * x;
  return out;
}

Eigen::Vector2d brownConrady(const Distortion& d, const Eigen::Vector2d& ideal) {
  const double x = ideal.x();
  const double y = ideal.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
  return {x * radial + 2.0 * d.p1 * x * y + d.p2 * (r2 + 2.0 * x * x),
          y * radial + d.p1 * (r2 + 2.0 * y * y) + 2.0 * d.p2 * x * y};
}

// Scale factor r_d / r_u of the spherical model (direction is preserved).
double sphericalDistortScale(double idealRadius) {
  if (idealRadius < 1e-12) {
    return 1.0;  // limit of 2 sin(atan(r)/2) / r; the formula is 0/0 at r = 0
  }
  return 2.0 * std::sin(0.5 * std::atan(idealRadius)) / idealRadius;
}

// Scale factor r_u / r_d of the spherical model, valid for r_d < sqrt(2).
double sphericalUndistortScale(double distortedRadius) {
  if (distortedRadius < 1e-12) {
    return 1.0;
  }
  return std::tan(2.0 * std::asin(0.5 * distortedRadius)) / distortedRadius;
}

}  // namespace

const char* toString(LensModel model) {
  switch (model) {
    case LensModel::Pinhole:
      return "pinhole";
    case LensModel::BrownConrady:
      return "brown_conrady";
    case LensModel::EquivalentSpherical:
      return "equivalent_spherical";
  }
  return "unknown";
}

std::optional<LensModel> lensModelFromString(const std::string& name) {
  for (LensModel model :
       {LensModel::Pinhole, LensModel::BrownConrady, LensModel::EquivalentSpherical}) {
    if (name == toString(model)) {
      return model;
    }
  }
  return std::nullopt;
}

const char* toString(CameraError error) {
  switch (error) {
    case CameraError::PointBehindCamera:
      return "point behind camera";
    case CameraError::OutsideValidField:
      return "outside the valid field of the lens model";
    case CameraError::NoConvergence:
      return "undistortion did not converge";
  }
  return "unknown";
}

bool CameraModel::init(const Intrinsics& intrinsics, const Distortion& distortion,
                       std::string* why) {
  if (intrinsics.width_px <= 0) {
    return fail(why, "width_px must be > 0, got " + std::to_string(intrinsics.width_px));
  }
  if (intrinsics.height_px <= 0) {
    return fail(why, "height_px must be > 0, got " + std::to_string(intrinsics.height_px));
  }
  const std::pair<const char*, double> focals[] = {{"fx_px", intrinsics.fx_px},
                                                   {"fy_px", intrinsics.fy_px}};
  for (const auto& [name, value] : focals) {
    if (!std::isfinite(value)) {
      return fail(why, std::string(name) + " must be finite, got " + formatValue(value));
    }
    if (value <= 0.0) {
      return fail(why, std::string(name) + " must be > 0, got " + formatValue(value));
    }
  }
  // The principal point may legitimately lie outside the image (cropped sensors).
  const std::pair<const char*, double> finiteValues[] = {
      {"cx_px", intrinsics.cx_px}, {"cy_px", intrinsics.cy_px}, {"k1", distortion.k1},
      {"k2", distortion.k2},       {"p1", distortion.p1},       {"p2", distortion.p2},
      {"k3", distortion.k3}};
  for (const auto& [name, value] : finiteValues) {
    if (!std::isfinite(value)) {
      return fail(why, std::string(name) + " must be finite, got " + formatValue(value));
    }
  }

  double maxIdeal = std::numeric_limits<double>::infinity();
  double maxDistorted = std::numeric_limits<double>::infinity();
  switch (distortion.model) {
    case LensModel::Pinhole:
      break;
    case LensModel::EquivalentSpherical:
      maxIdeal = std::tan(kSphericalMaxFieldAngle_rad);
      maxDistorted = 2.0 * std::sin(0.5 * kSphericalMaxFieldAngle_rad);
      break;
    case LensModel::BrownConrady: {
      // The radial polynomial turns back on itself (fold-over) past its first stationary
      // point: beyond it two ideal radii share one distorted radius and undistortion is
      // ambiguous. Find the first radius where the derivative stops being positive.
      double cornerRadius = 0.0;
      for (double u : {-0.5, intrinsics.width_px - 0.5}) {
        for (double v : {-0.5, intrinsics.height_px - 0.5}) {
          cornerRadius =
              std::max(cornerRadius, std::hypot((u - intrinsics.cx_px) / intrinsics.fx_px,
                                                (v - intrinsics.cy_px) / intrinsics.fy_px));
        }
      }
      const double step = cornerRadius / kFieldSamplesPerCornerRadius;
      const double searchRadius = kFieldSearchCornerRadii * cornerRadius;
      const double capRadius = kFieldSearchCapCornerRadii * cornerRadius;
      double previous = 0.0;
      for (int i = 1;; ++i) {
        const double r = i * step;
        if (radialProfileDerivative(distortion, r) <= 0.0) {
          // Bisect the stationary point between the last good sample and this one.
          double lo = previous;
          double hi = r;
          for (int k = 0; k < 60; ++k) {
            const double mid = 0.5 * (lo + hi);
            (radialProfileDerivative(distortion, mid) > 0.0 ? lo : hi) = mid;
          }
          maxIdeal = lo;
          break;
        }
        if ((r >= searchRadius && radialProfile(distortion, r) >= searchRadius) || r >= capRadius) {
          maxIdeal = r;
          break;
        }
        previous = r;
      }
      maxDistorted = radialProfile(distortion, maxIdeal);
      break;
    }
  }

  intrinsics_ = intrinsics;
  distortion_ = distortion;
  maxIdealRadius_ = maxIdeal;
  maxDistortedRadius_ = maxDistorted;
  return true;
}

Eigen::Vector2d CameraModel::distortNormalized(const Eigen::Vector2d& ideal) const {
  switch (distortion_.model) {
    case LensModel::Pinhole:
      break;
    case LensModel::BrownConrady:
      return brownConrady(distortion_, ideal);
    case LensModel::EquivalentSpherical:
      return ideal * sphericalDistortScale(ideal.norm());
  }
  return ideal;
}

Expected<Eigen::Vector2d, CameraError> CameraModel::undistortToNormalized(
    const Eigen::Vector2d& pixel) const {
  const Eigen::Vector2d distorted((pixel.x() - intrinsics_.cx_px) / intrinsics_.fx_px,
                                  (pixel.y() - intrinsics_.cy_px) / intrinsics_.fy_px);
  const double distortedRadius = distorted.norm();
  if (!std::isfinite(distortedRadius)) {
    return unexpected(CameraError::OutsideValidField);
  }
  switch (distortion_.model) {
    case LensModel::Pinhole:
      return distorted;
    case LensModel::EquivalentSpherical:
      if (distortedRadius > maxDistortedRadius_) {
        return unexpected(CameraError::OutsideValidField);
      }
      return Eigen::Vector2d(distorted * sphericalUndistortScale(distortedRadius));
    case LensModel::BrownConrady:
      break;
  }

  if (distortedRadius > maxDistortedRadius_) {
    return unexpected(CameraError::OutsideValidField);
  }
  // Newton on F(x) = distort(x) - distorted with the analytic Jacobian. Steps that do not
  // reduce the residual are halved, which keeps the iterate on the monotonic side of the
  // polynomial instead of jumping across the fold-over.
  Eigen::Vector2d ideal = distorted;
  BrownConradyEval eval = brownConradyWithJacobian(distortion_, ideal);
  Eigen::Vector2d residual = eval.distorted - distorted;
  double residualNorm = residual.norm();
  for (int iteration = 0;
       iteration < kUndistortMaxIterations && residualNorm >= kUndistortResidualTol; ++iteration) {
    // 2x2 solve by Cramer's rule: no LU machinery needed for a symmetric 2x2.
    const Eigen::Matrix2d& j = eval.jacobian;
    const double det = j(0, 0) * j(1, 1) - j(0, 1) * j(1, 0);
    if (!(std::abs(det) > 1e-300)) {
      break;  // singular: at the fold itself
    }
    Eigen::Vector2d step(-(j(1, 1) * residual.x() - j(0, 1) * residual.y()) / det,
                         -(j(0, 0) * residual.y() - j(1, 0) * residual.x()) / det);
    bool improved = false;
    for (int halving = 0; halving <= kMaxStepHalvings && !improved; ++halving) {
      const Eigen::Vector2d candidate = ideal + step;
      const BrownConradyEval candidateEval = brownConradyWithJacobian(distortion_, candidate);
      const Eigen::Vector2d candidateResidual = candidateEval.distorted - distorted;
      const double candidateNorm = candidateResidual.norm();
      if (candidateNorm < residualNorm) {
        ideal = candidate;
        eval = candidateEval;
        residual = candidateResidual;
        residualNorm = candidateNorm;
        improved = true;
      }
      step *= 0.5;
    }
    if (!improved) {
      break;  // stalled at a local minimum of the residual or at the precision floor
    }
  }
  if (!(residualNorm < kUndistortResidualTol)) {
    return unexpected(CameraError::NoConvergence);
  }
  // A solution past the stationary point is the folded-over twin, not the ray we want.
  if (ideal.norm() > maxIdealRadius_) {
    return unexpected(CameraError::OutsideValidField);
  }
  return ideal;
}

Eigen::Vector2d CameraModel::distortPixel(const Eigen::Vector2d& idealPixel) const {
  if (distortion_.model == LensModel::Pinhole) {
    // Exactly the identity: through the normalised plane and back, a fused multiply-add (the
    // default contraction on aarch64) would change the last bit.
    return idealPixel;
  }
  const Eigen::Vector2d ideal((idealPixel.x() - intrinsics_.cx_px) / intrinsics_.fx_px,
                              (idealPixel.y() - intrinsics_.cy_px) / intrinsics_.fy_px);
  const Eigen::Vector2d distorted = distortNormalized(ideal);
  return {intrinsics_.cx_px + intrinsics_.fx_px * distorted.x(),
          intrinsics_.cy_px + intrinsics_.fy_px * distorted.y()};
}

Expected<Eigen::Vector2d, CameraError> CameraModel::undistortPixel(
    const Eigen::Vector2d& pixel) const {
  const auto ideal = undistortToNormalized(pixel);
  if (!ideal) {
    return unexpected(ideal.error());
  }
  return Eigen::Vector2d(intrinsics_.cx_px + intrinsics_.fx_px * ideal->x(),
                         intrinsics_.cy_px + intrinsics_.fy_px * ideal->y());
}

Expected<Eigen::Vector3d, CameraError> CameraModel::pixelToRay(const Eigen::Vector2d& pixel) const {
  const auto ideal = undistortToNormalized(pixel);
  if (!ideal) {
    return unexpected(ideal.error());
  }
  return Eigen::Vector3d(ideal->x(), ideal->y(), 1.0).normalized();
}

Expected<Eigen::Vector2d, CameraError> CameraModel::projectToPixel(
    const Eigen::Vector3d& pointCamera) const {
  if (!(pointCamera.z() > 0.0)) {
    return unexpected(CameraError::PointBehindCamera);
  }
  const Eigen::Vector2d ideal(pointCamera.x() / pointCamera.z(), pointCamera.y() / pointCamera.z());
  const double idealRadius = ideal.norm();
  if (!std::isfinite(idealRadius) || idealRadius > maxIdealRadius_) {
    return unexpected(CameraError::OutsideValidField);
  }
  const Eigen::Vector2d distorted = distortNormalized(ideal);
  return Eigen::Vector2d(intrinsics_.cx_px + intrinsics_.fx_px * distorted.x(),
                         intrinsics_.cy_px + intrinsics_.fy_px * distorted.y());
}

bool CameraModel::inImage(const Eigen::Vector2d& pixel, double margin_px) const {
  // Pixel centres run from 0 to width-1, so the sensor area spans [-0.5, width-0.5).
  return pixel.x() >= -0.5 + margin_px && pixel.x() < intrinsics_.width_px - 0.5 - margin_px &&
         pixel.y() >= -0.5 + margin_px && pixel.y() < intrinsics_.height_px - 0.5 - margin_px;
}

}  // namespace vp::camera
