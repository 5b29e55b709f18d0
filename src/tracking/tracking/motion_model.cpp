#include "tracking/motion_model.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

#include "geometry/rotated_box.hpp"

namespace vp::tracking {
namespace {

bool finite(const Eigen::Vector2d& v) {
  return std::isfinite(v.x()) && std::isfinite(v.y());
}

// sin(u) / u, exact to double precision also near 0 (Taylor term below the cut-off).
double sinc(double u) {
  if (std::abs(u) < 1e-4) {
    return 1.0 - u * u / 6.0;
  }
  return std::sin(u) / u;
}

// Measurement Jacobian rows: centre x, centre y, heading.
Eigen::Matrix<double, 3, kStateSize> measurementJacobian(const StateVector& x, double d) {
  Eigen::Matrix<double, 3, kStateSize> h = Eigen::Matrix<double, 3, kStateSize>::Zero();
  h(0, kX) = 1.0;
  h(0, kPsi) = -d * std::sin(x[kPsi]);
  h(1, kY) = 1.0;
  h(1, kPsi) = d * std::cos(x[kPsi]);
  h(2, kPsi) = 1.0;
  return h;
}

template <int M>
bool kalmanUpdate(StateVector& x, StateMatrix& p, const Eigen::Matrix<double, M, kStateSize>& h,
                  const Eigen::Matrix<double, M, 1>& residual,
                  const Eigen::Matrix<double, M, M>& r) {
  const Eigen::Matrix<double, M, M> s = h * p * h.transpose() + r;
  const Eigen::LLT<Eigen::Matrix<double, M, M>> llt(s);
  if (llt.info() != Eigen::Success) {
    return false;
  }
  const Eigen::Matrix<double, kStateSize, M> pht = p * h.transpose();
  const Eigen::Matrix<double, kStateSize, M> k = llt.solve(pht.transpose()).transpose();
  x += k * residual;
  // Joseph form: stays symmetric positive semi-definite under rounding.
  const StateMatrix ikh = StateMatrix::Identity() - k * h;
  p = ikh * p * ikh.transpose() + k * r * k.transpose();
  return true;
}

// Covariance of a detected centre: sigma per axis, k sigma along the axis at heading psi,
// sigma^2 (I + (k^2 - 1) u u^T) with u = (cos psi, sin psi).
Eigen::Matrix2d centreNoise(double sigma, double psi, double alongAxisFactor) {
  const Eigen::Vector2d u(std::cos(psi), std::sin(psi));
  return sigma * sigma *
         (Eigen::Matrix2d::Identity() +
          (alongAxisFactor * alongAxisFactor - 1.0) * u * u.transpose());
}

}  // namespace

void MotionModel::initialise(const Eigen::Vector2d& centre, double heading_rad, double wheelbase_m,
                             double rearToCentre_m, const MotionNoise& noise,
                             double alongAxisFactor) {
  wheelbase_ = wheelbase_m;
  rearToCentre_ = rearToCentre_m;
  const double psi = geometry::wrapTwoPi(heading_rad);
  x_ = StateVector::Zero();
  x_[kX] = centre.x() - rearToCentre_m * std::cos(psi);
  x_[kY] = centre.y() - rearToCentre_m * std::sin(psi);
  x_[kPsi] = psi;
  p_ = StateMatrix::Zero();
  const double sp = noise.measurementPosition_m;
  // A bad factor (not finite, < 1) counts as 1: initialise() cannot fail.
  const double k = std::isfinite(alongAxisFactor) ? std::max(1.0, alongAxisFactor) : 1.0;
  p_.topLeftCorner<2, 2>() =
      centreNoise(sp, psi, k) +
      Eigen::Matrix2d::Identity() * std::pow(rearToCentre_m * noise.measurementHeading_rad, 2);
  p_(kPsi, kPsi) = noise.measurementHeading_rad * noise.measurementHeading_rad;
  p_(kV, kV) = noise.initialSpeed_mps * noise.initialSpeed_mps;
  p_(kA, kA) = noise.initialAcceleration_mps2 * noise.initialAcceleration_mps2;
  p_(kDelta, kDelta) = noise.initialSteering_rad * noise.initialSteering_rad;
}

bool MotionModel::predict(double dt, const MotionNoise& noise) {
  if (!(dt >= 0.0) || !std::isfinite(dt)) {
    return false;
  }
  if (dt == 0.0) {
    return true;
  }
  const double psi = x_[kPsi];
  const double v = x_[kV];
  const double a = x_[kA];
  const double delta = x_[kDelta];
  const double cosDelta = std::cos(delta);
  const double kappa = std::tan(delta) / wheelbase_;
  const double dKappa = 1.0 / (wheelbase_ * cosDelta * cosDelta);  // d kappa / d delta
  const double s = v * dt + 0.5 * a * dt * dt;
  const double dPsi = s * kappa;
  const double theta = psi + 0.5 * dPsi;
  const double chord = s * sinc(0.5 * dPsi);
  const double decay = std::exp(-dt / noise.accelerationDecay_s);

  if (std::abs(v) < noise.standstillSpeed_mps &&
      std::abs(a) < noise.standstillSpeed_mps / noise.standstillDecay_s) {
    // Standstill dead band on the mean: a standing car does not creep with the noise of its
    // speed estimate (a parked car stays put), and its speed and acceleration relax to 0.
    // The covariance below still uses the moving Jacobian, so position residuals keep
    // feeding v and a car pulling away leaves the band within a few frames.
    const double stop = std::exp(-dt / noise.standstillDecay_s);
    x_[kV] = v * stop;
    x_[kA] = a * stop;
  } else {
    x_[kX] += chord * std::cos(theta);
    x_[kY] += chord * std::sin(theta);
    x_[kPsi] = geometry::wrapTwoPi(psi + dPsi);
    x_[kV] = v + a * dt;
    x_[kA] = a * decay;
  }
  // Optional mean reversion of the steering: without measurements (a lost track) a noisy
  // steering estimate would otherwise drive the prediction round in circles.
  const double steeringDecay =
      noise.steeringDecay_s > 0.0 ? std::exp(-dt / noise.steeringDecay_s) : 1.0;
  x_[kDelta] = std::clamp(delta * steeringDecay, -noise.maxSteering_rad, noise.maxSteering_rad);

  // Jacobian of the midpoint form (chord ~ s): the sinc factor changes it by O(dpsi^2).
  StateMatrix f = StateMatrix::Identity();
  const double c = std::cos(theta);
  const double sn = std::sin(theta);
  const double dsDv = dt;
  const double dsDa = 0.5 * dt * dt;
  f(kX, kPsi) = -s * sn;
  f(kY, kPsi) = s * c;
  f(kX, kV) = dsDv * c - s * sn * 0.5 * kappa * dsDv;
  f(kY, kV) = dsDv * sn + s * c * 0.5 * kappa * dsDv;
  f(kX, kA) = dsDa * c - s * sn * 0.5 * kappa * dsDa;
  f(kY, kA) = dsDa * sn + s * c * 0.5 * kappa * dsDa;
  f(kX, kDelta) = -s * sn * 0.5 * s * dKappa;
  f(kY, kDelta) = s * c * 0.5 * s * dKappa;
  f(kPsi, kV) = kappa * dsDv;
  f(kPsi, kA) = kappa * dsDa;
  f(kPsi, kDelta) = s * dKappa;
  f(kV, kA) = dt;
  f(kA, kA) = decay;
  f(kDelta, kDelta) = steeringDecay;

  // White jerk (continuous) integrated into v and a; white steering rate into delta; small
  // diffusion on position and heading for what the bicycle does not model (lane changes,
  // detector bias that moves with the pose).
  StateMatrix q = StateMatrix::Zero();
  const double j2 = noise.jerk_mPerS3 * noise.jerk_mPerS3;
  q(kX, kX) = q(kY, kY) =
      noise.positionDiffusion_mPerSqrtS * noise.positionDiffusion_mPerSqrtS * dt;
  q(kPsi, kPsi) = noise.headingDiffusion_radPerSqrtS * noise.headingDiffusion_radPerSqrtS * dt;
  q(kV, kV) = j2 * dt * dt * dt / 3.0;
  q(kV, kA) = q(kA, kV) = j2 * dt * dt / 2.0;
  q(kA, kA) = j2 * dt;
  q(kDelta, kDelta) = noise.steeringRate_radPerS * noise.steeringRate_radPerS * dt;

  p_ = f * p_ * f.transpose() + q;
  return true;
}

Innovation MotionModel::innovation(const Eigen::Vector2d& centre, double heading_rad,
                                   bool hasHeading, const MotionNoise& noise) const {
  Innovation out;
  const Eigen::Vector2d predicted = this->centre();
  out.residual.head<2>() = centre - predicted;
  out.residual[2] = hasHeading ? geometry::angleDifference(heading_rad, x_[kPsi]) : 0.0;
  const auto h = measurementJacobian(x_, rearToCentre_);
  Eigen::Matrix3d r = Eigen::Matrix3d::Zero();
  r(0, 0) = r(1, 1) = noise.measurementPosition_m * noise.measurementPosition_m;
  r(2, 2) = noise.measurementHeading_rad * noise.measurementHeading_rad;
  out.covariance = h * p_ * h.transpose() + r;
  out.size = hasHeading ? 3 : 2;
  return out;
}

bool MotionModel::update(const Eigen::Vector2d& centre, double heading_rad, bool hasHeading,
                         const MotionNoise& noise, double alongAxisFactor) {
  if (!finite(centre) || (hasHeading && !std::isfinite(heading_rad)) || !(alongAxisFactor >= 1.0) ||
      !std::isfinite(alongAxisFactor)) {
    return false;
  }
  const Eigen::Matrix<double, 3, kStateSize> h = measurementJacobian(x_, rearToCentre_);
  const Eigen::Vector2d predicted = this->centre();
  // Along the track's axis k times the sigma.
  const Eigen::Matrix2d rPosition =
      centreNoise(noise.measurementPosition_m, x_[kPsi], alongAxisFactor);
  bool ok = false;
  if (hasHeading) {
    Eigen::Vector3d residual;
    residual.head<2>() = centre - predicted;
    residual[2] = geometry::angleDifference(heading_rad, x_[kPsi]);
    Eigen::Matrix3d r = Eigen::Matrix3d::Zero();
    r.topLeftCorner<2, 2>() = rPosition;
    r(2, 2) = noise.measurementHeading_rad * noise.measurementHeading_rad;
    ok = kalmanUpdate<3>(x_, p_, h, residual, r);
  } else {
    const Eigen::Matrix<double, 2, kStateSize> h2 = h.topRows<2>();
    const Eigen::Vector2d residual = centre - predicted;
    ok = kalmanUpdate<2>(x_, p_, h2, residual, rPosition);
  }
  x_[kPsi] = geometry::wrapTwoPi(x_[kPsi]);
  x_[kDelta] = std::clamp(x_[kDelta], -noise.maxSteering_rad, noise.maxSteering_rad);
  return ok;
}

void MotionModel::setGeometry(double wheelbase_m, double rearToCentre_m) {
  if (!(wheelbase_m > 0.1) || !std::isfinite(rearToCentre_m)) {
    return;
  }
  const double shift = rearToCentre_ - rearToCentre_m;
  const double c = std::cos(x_[kPsi]);
  const double s = std::sin(x_[kPsi]);
  x_[kX] += shift * c;
  x_[kY] += shift * s;
  StateMatrix j = StateMatrix::Identity();
  j(kX, kPsi) = -shift * s;
  j(kY, kPsi) = shift * c;
  p_ = j * p_ * j.transpose();
  wheelbase_ = wheelbase_m;
  rearToCentre_ = rearToCentre_m;
}

void MotionModel::flipDirection() {
  // The centre stays: new rear axle = centre - d f' with f' = -f, i.e. old rear + 2 d f.
  const double c = std::cos(x_[kPsi]);
  const double s = std::sin(x_[kPsi]);
  StateMatrix j = StateMatrix::Identity();
  j(kX, kPsi) = -2.0 * rearToCentre_ * s;
  j(kY, kPsi) = 2.0 * rearToCentre_ * c;
  j(kV, kV) = j(kA, kA) = j(kDelta, kDelta) = -1.0;
  x_[kX] += 2.0 * rearToCentre_ * c;
  x_[kY] += 2.0 * rearToCentre_ * s;
  x_[kPsi] = geometry::wrapTwoPi(x_[kPsi] + geometry::kPi);
  x_[kV] = -x_[kV];
  x_[kA] = -x_[kA];
  x_[kDelta] = -x_[kDelta];
  p_ = j * p_ * j.transpose();
}

Eigen::Vector2d MotionModel::centre() const {
  return {x_[kX] + rearToCentre_ * std::cos(x_[kPsi]), x_[kY] + rearToCentre_ * std::sin(x_[kPsi])};
}

double MotionModel::heading() const {
  return geometry::wrapTwoPi(x_[kPsi]);
}

double MotionModel::yawRate() const {
  return x_[kV] * std::tan(x_[kDelta]) / wheelbase_;
}

Eigen::Matrix2d MotionModel::centreCovariance() const {
  // Two rows only: the association asks for it per track and step.
  const Eigen::Matrix<double, 2, kStateSize> h =
      measurementJacobian(x_, rearToCentre_).topRows<2>();
  return h * p_ * h.transpose();
}

Eigen::Matrix3d MotionModel::poseCovariance() const {
  const Eigen::Matrix<double, 3, kStateSize> h = measurementJacobian(x_, rearToCentre_);
  return h * p_ * h.transpose();
}

double MotionModel::yawRateSigma() const {
  // omega = v tan(delta) / L: d omega / d v = tan(delta) / L, d omega / d delta = v / (L cos^2).
  const double c = std::cos(x_[kDelta]);
  Eigen::Matrix<double, 1, kStateSize> j = Eigen::Matrix<double, 1, kStateSize>::Zero();
  j(0, kV) = std::tan(x_[kDelta]) / wheelbase_;
  j(0, kDelta) = x_[kV] / (wheelbase_ * c * c);
  return std::sqrt(std::max(0.0, (j * p_ * j.transpose())(0, 0)));
}

}  // namespace vp::tracking
