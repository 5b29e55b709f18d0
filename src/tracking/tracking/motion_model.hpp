// tracking/motion_model: the kinematic bicycle (Ackermann) model of seed 001 as an extended
// Kalman filter over a vehicle's rear-axle centre, heading, speed, acceleration and steering.
//
// Contract: a MotionModel is a value (no heap, fixed-size Eigen matrices) holding one
// vehicle's state x and covariance P. predict(dt) propagates both with the bicycle equations
// below; update() folds in one world detection of the box centre (and its heading when the
// detector knows it). The wheelbase L and the rear-axle-to-centre offset d come from the
// vehicle's ASM shape (or its length) and may change over the track: setGeometry() moves the
// rear-axle state so that the box centre stays where it was. A parked vehicle (v = 0) stays
// exactly where it is: the bicycle cannot turn on the spot. flipDirection() turns the state
// by 180 degrees (same footprint, opposite driving direction), for heading disambiguation.
// All calls are allocation-free; non-finite inputs are rejected (false), never propagated.
//
// State (index = MotionState), SI units, world ENU frame (docs/conventions.md):
//   x, y  rear-axle centre, m          psi   heading, rad, counter-clockwise from east
//   v     speed along psi, m/s          a     acceleration, m/s^2
//   delta equivalent front-wheel steering angle, rad
// Equations over one step dt (exact arc for constant delta):
//   s = v dt + a dt^2 / 2,  kappa = tan(delta) / L,  dpsi = s kappa
//   x' = x + s sinc(dpsi / 2) cos(psi + dpsi / 2),  y' = y + s sinc(dpsi / 2) sin(psi + dpsi / 2)
//   psi' = psi + dpsi,  v' = v + a dt,  a' = a exp(-dt / tauA),
//   delta' = delta exp(-dt / tauD)  (tauD = 0, the default: delta' = delta)
// except in the standstill dead band (|v| < standstillSpeed, |a| small), where x, y, psi keep
// their values and v, a decay to 0 with standstillDecay_s; so a vehicle with fixed delta drives a
// circle of radius L / tan(delta) about its rear axle. Measurement: the box centre c = (x, y) + d
// (cos psi, sin psi), and psi itself when known.
#pragma once

#include <Eigen/Core>

#include "geometry/rotated_box.hpp"  // kPi

namespace vp::tracking {

enum MotionState : int { kX = 0, kY, kPsi, kV, kA, kDelta, kStateSize };

using StateVector = Eigen::Matrix<double, kStateSize, 1>;
using StateMatrix = Eigen::Matrix<double, kStateSize, kStateSize>;

// Process and measurement noise (1 sigma). Defaults tuned on synthetic seed 1 only
// (docs/tracking.md); the measurement noise and the steering decay (config: tracking.*) are the
// shipped configuration's, tuned with detector v6 on the tuning seeds.
struct MotionNoise {
  double positionDiffusion_mPerSqrtS = 0.05;   // model error on x, y
  double headingDiffusion_radPerSqrtS = 0.02;  // model error on psi
  double jerk_mPerS3 = 1.0;                    // white jerk drives a and v
  double steeringRate_radPerS = 0.15;          // white steering rate drives delta
  double accelerationDecay_s = 3.0;            // tauA: a relaxes to 0 (drivers stop accelerating)
  double steeringDecay_s =
      2.0;  // tauD: delta relaxes to 0 (drivers straighten), [0, 60]; 0 = never
  double maxSteering_rad = 0.6;         // |delta| is clamped (mechanical limit)
  double standstillSpeed_mps = 0.3;     // below: the mean does not move (dead band)
  double standstillDecay_s = 0.5;       // v, a relax to 0 inside the dead band
  double measurementPosition_m = 0.30;  // lifted detection centre, per axis, (0, 10]
  // Detection heading: 8 deg ((0, 90] deg in the configuration file).
  double measurementHeading_rad = 8.0 * (geometry::kPi / 180.0);
  double initialSpeed_mps = 20.0;  // prior spread of v at track birth
  double initialAcceleration_mps2 = 1.5;
  double initialSteering_rad = 0.15;
};

// Innovation of one detection: z - h(x) and its covariance S = H P H^T + R, for gating.
struct Innovation {
  Eigen::Vector3d residual{Eigen::Vector3d::Zero()};  // centre x, centre y, heading
  Eigen::Matrix3d covariance{Eigen::Matrix3d::Identity()};
  int size = 2;  // 2: position only, 3: with heading
};

class MotionModel {
 public:
  MotionModel() = default;

  // Starts a track at a detected box centre and heading, speed 0 with a wide prior;
  // alongAxisFactor as in update().
  void initialise(const Eigen::Vector2d& centre, double heading_rad, double wheelbase_m,
                  double rearToCentre_m, const MotionNoise& noise, double alongAxisFactor = 1.0);

  // Propagates the state by dt >= 0 seconds; false (state unchanged) for a bad dt.
  bool predict(double dt, const MotionNoise& noise);

  // Innovation of a detection against the predicted state; hasHeading adds the heading row.
  Innovation innovation(const Eigen::Vector2d& centre, double heading_rad, bool hasHeading,
                        const MotionNoise& noise) const;
  // EKF update with that detection; false (state unchanged) when S is not positive definite.
  // alongAxisFactor >= 1 scales the position noise along the track's axis only (a detection
  // that tells where the vehicle is across its lane better than where along it).
  bool update(const Eigen::Vector2d& centre, double heading_rad, bool hasHeading,
              const MotionNoise& noise, double alongAxisFactor = 1.0);

  // New wheelbase / rear-to-centre offset (fused ASM shape); keeps the box centre fixed.
  void setGeometry(double wheelbase_m, double rearToCentre_m);
  // Same footprint, opposite driving direction: psi + pi, v, a, delta negated.
  void flipDirection();

  const StateVector& state() const { return x_; }
  const StateMatrix& covariance() const { return p_; }
  Eigen::Vector2d rearAxle() const { return {x_[kX], x_[kY]}; }
  Eigen::Vector2d centre() const;
  double heading() const;  // wrapped to [0, 2 pi)
  double yawRate() const;  // v tan(delta) / L, rad/s
  double wheelbase() const { return wheelbase_; }
  double rearToCentre() const { return rearToCentre_; }
  // Covariance of the predicted box centre (for the Mahalanobis gate), m^2.
  Eigen::Matrix2d centreCovariance() const;
  // Covariance of (centre x, centre y, heading), m^2, m rad, rad^2.
  Eigen::Matrix3d poseCovariance() const;
  // Standard deviation of yawRate() from the speed and steering covariance (first order), rad/s.
  double yawRateSigma() const;

 private:
  StateVector x_{StateVector::Zero()};
  StateMatrix p_{StateMatrix::Identity()};
  double wheelbase_ = 2.7;
  double rearToCentre_ = 1.35;
};

}  // namespace vp::tracking
