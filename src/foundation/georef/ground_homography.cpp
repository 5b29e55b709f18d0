#include "georef/ground_homography.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include <Eigen/Dense>
#include <Eigen/SVD>

namespace vp::georef {

namespace {

bool fail(std::string* why, const std::string& message) {
  if (why != nullptr) {
    *why = message;
  }
  return false;
}

std::string quoted(const std::string& id) {
  return "'" + id + "'";
}

std::string idList(std::span<const ControlPoint> points, const std::vector<std::size_t>& which) {
  std::string text;
  for (std::size_t k = 0; k < which.size(); ++k) {
    text += (k == 0 ? "" : ", ") + quoted(points[which[k]].id);
  }
  return text;
}

// Hartley's normalisation: centroid to the origin, mean distance sqrt 2.
Eigen::Matrix3d normalisation(const std::vector<Eigen::Vector2d>& p) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& x : p) {
    mean += x;
  }
  mean /= static_cast<double>(p.size());
  double distance = 0.0;
  for (const auto& x : p) {
    distance += (x - mean).norm();
  }
  distance /= static_cast<double>(p.size());
  const double s = distance > 0.0 ? std::sqrt(2.0) / distance : 1.0;
  Eigen::Matrix3d t;
  t << s, 0, -s * mean.x(), 0, s, -s * mean.y(), 0, 0, 1;
  return t;
}

double rmsSpread(const std::vector<Eigen::Vector2d>& p) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& x : p) {
    mean += x;
  }
  mean /= static_cast<double>(p.size());
  double sum = 0.0;
  for (const auto& x : p) {
    sum += (x - mean).squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(p.size()));
}

// The largest set of points within tolerance of the line through two of them.
std::vector<std::size_t> largestCollinearSet(const std::vector<Eigen::Vector2d>& p,
                                             double tolerance) {
  std::vector<std::size_t> best;
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (std::size_t j = i + 1; j < p.size(); ++j) {
      const Eigen::Vector2d d = p[j] - p[i];
      const double length = d.norm();
      if (length <= 0.0) {
        continue;
      }
      std::vector<std::size_t> on;
      for (std::size_t k = 0; k < p.size(); ++k) {
        const Eigen::Vector2d r = p[k] - p[i];
        if (std::abs(d.x() * r.y() - d.y() * r.x()) / length <= tolerance) {
          on.push_back(k);
        }
      }
      if (on.size() > best.size()) {
        best = std::move(on);
      }
    }
  }
  return best;
}

// A set has 4 points with no 3 on a line unless all, or all but one, lie on one line.
bool checkGeneralPosition(std::span<const ControlPoint> points,
                          const std::vector<Eigen::Vector2d>& p, double share, const char* where,
                          std::string* why) {
  const double tolerance = share * rmsSpread(p);
  const std::vector<std::size_t> line = largestCollinearSet(p, tolerance);
  if (line.size() + 1 >= p.size()) {
    return fail(why, "ground control points " + idList(points, line) + " lie on one line " + where +
                         (line.size() < p.size() ? " (with one point off it)" : "") +
                         ": at least 4 points with no 3 on a line are needed");
  }
  return true;
}

// Residuals of the normalised problem: g_i - pi(H x_i), stacked.
void residuals(const Eigen::Matrix<double, 9, 1>& h, const std::vector<Eigen::Vector3d>& x,
               const std::vector<Eigen::Vector2d>& g, Eigen::VectorXd* r,
               Eigen::MatrixXd* jacobian) {
  const Eigen::Matrix3d H =
      Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(h.data());
  for (std::size_t i = 0; i < x.size(); ++i) {
    const Eigen::Vector3d q = H * x[i];
    const double w = q.z();
    const auto row = static_cast<Eigen::Index>(2 * i);
    (*r)(row) = q.x() / w - g[i].x();
    (*r)(row + 1) = q.y() / w - g[i].y();
    if (jacobian != nullptr) {
      jacobian->row(row).setZero();
      jacobian->row(row + 1).setZero();
      jacobian->block<1, 3>(row, 0) = x[i].transpose() / w;
      jacobian->block<1, 3>(row, 6) = -(q.x() / (w * w)) * x[i].transpose();
      jacobian->block<1, 3>(row + 1, 3) = x[i].transpose() / w;
      jacobian->block<1, 3>(row + 1, 6) = -(q.y() / (w * w)) * x[i].transpose();
    }
  }
}

}  // namespace

std::optional<Eigen::Vector2d> mapToGround(const Eigen::Matrix3d& imageToGround,
                                           const Eigen::Vector2d& pixel) {
  const Eigen::Vector3d q = imageToGround * pixel.homogeneous();
  if (!(q.z() > 1e-12 * q.head<2>().norm()) || !q.allFinite()) {
    return std::nullopt;
  }
  return Eigen::Vector2d(q.x() / q.z(), q.y() / q.z());
}

std::optional<Eigen::Vector2d> mapToImage(const Eigen::Matrix3d& groundToImage,
                                          const Eigen::Vector2d& groundEn) {
  const Eigen::Vector3d q = groundToImage * groundEn.homogeneous();
  if (!(q.z() > 1e-12 * q.head<2>().norm()) || !q.allFinite()) {
    return std::nullopt;
  }
  return Eigen::Vector2d(q.x() / q.z(), q.y() / q.z());
}

bool estimateGroundHomography(std::span<const ControlPoint> points,
                              const HomographyOptions& options, GroundHomography* out,
                              std::string* why) {
  const std::size_t n = points.size();
  std::vector<std::size_t> all(n);
  for (std::size_t i = 0; i < n; ++i) {
    all[i] = i;
  }
  if (n < 4) {
    return fail(why, std::to_string(n) + " ground control point(s)" +
                         (n > 0 ? " (" + idList(points, all) + ")" : std::string()) +
                         ": at least 4 are needed");
  }
  std::map<std::string, std::size_t> seen;
  for (std::size_t i = 0; i < n; ++i) {
    const ControlPoint& p = points[i];
    if (!p.pixel.allFinite() || !p.groundEnu.allFinite()) {
      return fail(why, "ground control point " + quoted(p.id) + ": not a finite position");
    }
    if (!seen.emplace(p.id, i).second) {
      return fail(why, "ground control point id " + quoted(p.id) + " appears twice");
    }
    for (std::size_t j = 0; j < i; ++j) {
      const ControlPoint& q = points[j];
      if ((p.pixel - q.pixel).norm() < options.samePixel_px) {
        return fail(why, "ground control points " + quoted(q.id) + " and " + quoted(p.id) +
                             " are at the same pixel (within " +
                             std::to_string(options.samePixel_px) + " px)");
      }
      if ((p.groundEnu.head<2>() - q.groundEnu.head<2>()).norm() < options.sameGround_m) {
        return fail(why, "ground control points " + quoted(q.id) + " and " + quoted(p.id) +
                             " are at the same ground position (within " +
                             std::to_string(options.sameGround_m) + " m)");
      }
    }
  }
  std::vector<Eigen::Vector2d> pixels(n);
  std::vector<Eigen::Vector2d> ground(n);
  for (std::size_t i = 0; i < n; ++i) {
    pixels[i] = points[i].pixel;
    ground[i] = points[i].groundEnu.head<2>();
  }
  if (!checkGeneralPosition(points, pixels, options.collinearShare, "in the image", why) ||
      !checkGeneralPosition(points, ground, options.collinearShare, "on the ground", why)) {
    return false;
  }

  // Normalised DLT over all points: g ~ H x, two equations per point, the null vector of A.
  const Eigen::Matrix3d tImage = normalisation(pixels);
  const Eigen::Matrix3d tGround = normalisation(ground);
  std::vector<Eigen::Vector3d> x(n);
  std::vector<Eigen::Vector2d> g(n);
  Eigen::MatrixXd a(2 * n, 9);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = tImage * pixels[i].homogeneous();
    g[i] = (tGround * ground[i].homogeneous()).head<2>();
    const auto row = static_cast<Eigen::Index>(2 * i);
    a.row(row) << x[i].x(), x[i].y(), 1.0, 0, 0, 0, -g[i].x() * x[i].x(), -g[i].x() * x[i].y(),
        -g[i].x();
    a.row(row + 1) << 0, 0, 0, x[i].x(), x[i].y(), 1.0, -g[i].y() * x[i].x(), -g[i].y() * x[i].y(),
        -g[i].y();
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeFullV);
  const Eigen::VectorXd& s = svd.singularValues();
  if (!(s(7) > 1e-9 * s(0))) {
    return fail(why, "ground control points " + idList(points, all) +
                         ": the homography is undetermined (degenerate set)");
  }
  Eigen::Matrix<double, 9, 1> h = svd.matrixV().col(8);

  // Levenberg–Marquardt on the ground distances (the normalised ground frame is the metric one
  // scaled, so the same minimum). The scale of h is free: the damping keeps the step defined
  // and h is renormalised after each step.
  Eigen::VectorXd r(2 * n);
  Eigen::MatrixXd jacobian(2 * n, 9);
  residuals(h, x, g, &r, &jacobian);
  double cost = r.squaredNorm();
  const double groundScale = tGround(0, 0);  // normalised units per metre
  out->initialRms_m = std::sqrt(cost / static_cast<double>(n)) / groundScale;
  double lambda = 1e-3;
  int iterations = 0;
  Eigen::VectorXd trial(2 * n);
  for (; iterations < options.maxIterations; ++iterations) {
    const Eigen::Matrix<double, 9, 9> jtj = jacobian.transpose() * jacobian;
    const Eigen::Matrix<double, 9, 1> jtr = jacobian.transpose() * r;
    bool improved = false;
    bool converged = false;
    for (int attempt = 0; attempt < 20 && !improved; ++attempt) {
      Eigen::Matrix<double, 9, 9> damped = jtj;
      for (int k = 0; k < 9; ++k) {
        damped(k, k) += lambda * (jtj(k, k) + 1e-12);
      }
      const Eigen::Matrix<double, 9, 1> step = damped.ldlt().solve(-jtr);
      Eigen::Matrix<double, 9, 1> candidate = h + step;
      candidate.normalize();
      residuals(candidate, x, g, &trial, nullptr);
      const double trialCost = trial.squaredNorm();
      if (std::isfinite(trialCost) && trialCost < cost) {
        const double decrease = cost - trialCost;
        h = candidate;
        cost = trialCost;
        lambda = std::max(lambda / 10.0, 1e-12);
        improved = true;
        converged = decrease <= 1e-12 * cost;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved || converged || cost <= 1e-30) {
      break;
    }
    residuals(h, x, g, &r, &jacobian);
  }
  out->iterations = iterations;

  const Eigen::Matrix3d hn =
      Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(h.data());
  Eigen::Matrix3d imageToGround = tGround.inverse() * hn * tImage;
  imageToGround /= imageToGround.norm();
  // Points in view have w > 0.
  double wSum = 0.0;
  for (const Eigen::Vector2d& p : pixels) {
    wSum += (imageToGround * p.homogeneous()).z();
  }
  if (wSum < 0.0) {
    imageToGround = -imageToGround;
  }
  out->imageToGround = imageToGround;
  out->groundToImage = imageToGround.inverse();
  out->groundToImage /= out->groundToImage.norm();
  if ((out->groundToImage * ground[0].homogeneous()).z() < 0.0) {
    out->groundToImage = -out->groundToImage;
  }

  // The ground plane through the points' heights (least squares).
  Eigen::MatrixXd design(n, 3);
  Eigen::VectorXd heights(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    design.row(row) << 1.0, ground[i].x(), ground[i].y();
    heights(row) = points[i].groundEnu.z();
  }
  const Eigen::Vector3d plane = design.colPivHouseholderQr().solve(heights);
  out->plane = GroundPlane{plane(0), plane(1), plane(2)};

  out->residuals.clear();
  double sum = 0.0;
  out->max_m = 0.0;
  out->maxIndex = 0;
  for (std::size_t i = 0; i < n; ++i) {
    PointResidual residual;
    residual.id = points[i].id;
    const auto lifted = mapToGround(out->imageToGround, pixels[i]);
    const auto back = mapToImage(out->groundToImage, ground[i]);
    if (!lifted || !back) {
      return fail(why, "ground control point " + quoted(points[i].id) +
                           ": beyond the horizon of the fitted view (a wrong pixel or position?)");
    }
    residual.groundError_m = *lifted - ground[i];
    residual.ground_m = residual.groundError_m.norm();
    residual.reprojectedPixel = *back;
    residual.image_px = (*back - pixels[i]).norm();
    sum += residual.ground_m * residual.ground_m;
    if (residual.ground_m > out->max_m) {
      out->max_m = residual.ground_m;
      out->maxIndex = i;
    }
    out->residuals.push_back(std::move(residual));
  }
  out->rms_m = std::sqrt(sum / static_cast<double>(n));
  return true;
}

std::optional<RecoveredCamera> recoverCamera(const GroundHomography& view,
                                             const camera::Intrinsics& intrinsics) {
  if (!(intrinsics.fx_px > 0.0) || !(intrinsics.fy_px > 0.0)) {
    return std::nullopt;
  }
  // A ground point (E, N) is X = A (E, N, 1) on the plane; a camera with centre C and rotation
  // R (world -> camera) sees it at K R (X - C) = K R [a1, a2, a3 - C] (E, N, 1). So
  // K^-1 groundToImage = lambda R [a1, a2, a3 - C].
  const GroundPlane& p = view.plane;
  const Eigen::Vector3d a1(1.0, 0.0, p.b);
  const Eigen::Vector3d a2(0.0, 1.0, p.c);
  const Eigen::Vector3d a3(0.0, 0.0, p.a);
  Eigen::Matrix3d kInverse;
  kInverse << 1.0 / intrinsics.fx_px, 0.0, -intrinsics.cx_px / intrinsics.fx_px, 0.0,
      1.0 / intrinsics.fy_px, -intrinsics.cy_px / intrinsics.fy_px, 0.0, 0.0, 1.0;
  const Eigen::Matrix3d m = kInverse * view.groundToImage;
  const Eigen::Vector3d m1 = m.col(0);
  const Eigen::Vector3d m2 = m.col(1);
  const Eigen::Vector3d m3 = m.col(2);
  double lambda =
      std::sqrt((m1.squaredNorm() + m2.squaredNorm()) / (a1.squaredNorm() + a2.squaredNorm()));
  if (!(lambda > 0.0) || !std::isfinite(lambda)) {
    return std::nullopt;
  }
  // The plane lies in front of the camera: a3 - C has a positive depth.
  if (m3.z() < 0.0) {
    lambda = -lambda;
  }
  // R from the two plane directions (orthogonal Procrustes).
  Eigen::Matrix3d from;
  from.col(0) = a1;
  from.col(1) = a2;
  from.col(2) = a1.cross(a2);
  Eigen::Matrix3d to;
  to.col(0) = m1 / lambda;
  to.col(1) = m2 / lambda;
  to.col(2) = to.col(0).cross(to.col(1));
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(to * from.transpose(),
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  const Eigen::Matrix3d r = svd.matrixU() * d * svd.matrixV().transpose();
  RecoveredCamera camera;
  camera.centreEnu = a3 - r.transpose() * (m3 / lambda);
  camera.cameraToEnu = r.transpose();
  camera.heightAboveGround_m =
      camera.centreEnu.z() - p.heightAt(camera.centreEnu.x(), camera.centreEnu.y());
  if (!camera.centreEnu.allFinite() || !(camera.heightAboveGround_m > 0.0)) {
    return std::nullopt;
  }
  return camera;
}

}  // namespace vp::georef
