// Tests for tracking/motion_model: the bicycle equations (straight line, constant turn
// radius L / tan(delta)), a parked car staying put, convergence of the speed estimate, the
// geometry change and the 180-degree flip keeping the footprint.
#include "tracking/motion_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "geometry/rotated_box.hpp"
#include "seed_one_options.hpp"

namespace vp::tracking {
namespace {

// The model exposes no setter for v/delta (the filter owns its state); drive it with
// perfect measurements of a known trajectory instead, then check pure prediction.
TEST(MotionModel, StraightLineAtConstantSpeed) {
  MotionNoise noise = test::seedOneNoise();
  MotionModel m;
  m.initialise({0.0, 0.0}, 0.3, 2.7, 1.3, noise);
  const double v = 12.0;
  const Eigen::Vector2d f(std::cos(0.3), std::sin(0.3));
  for (int k = 1; k <= 60; ++k) {
    ASSERT_TRUE(m.predict(0.1, noise));
    ASSERT_TRUE(m.update(v * 0.1 * k * f, 0.3, true, noise));
  }
  EXPECT_NEAR(m.state()[kV], v, 0.05);
  EXPECT_NEAR(m.yawRate(), 0.0, 1e-3);
  // Pure prediction 2 s ahead lands on the line.
  for (int k = 0; k < 20; ++k) {
    m.predict(0.1, noise);
  }
  const Eigen::Vector2d expected = v * 8.0 * f;
  EXPECT_NEAR((m.centre() - expected).norm(), 0.0, 0.1);
  EXPECT_NEAR(geometry::absAngleDifference(m.heading(), 0.3), 0.0, 1e-3);
}

TEST(MotionModel, ConstantSteeringDrivesCircleOfRadiusWheelbaseOverTanDelta) {
  // Converge on a circle driven by the rear axle (d = 0 so centre = rear axle), then
  // predict a full revolution with no measurement: the bicycle must stay on the circle.
  MotionNoise noise = test::seedOneNoise();
  const double wheelbase = 2.8;
  const double delta = 0.2;
  const double radius = wheelbase / std::tan(delta);
  const double v = 8.0;
  const double omega = v / radius;
  MotionModel m;
  m.initialise({radius, 0.0}, 0.5 * geometry::kPi, wheelbase, 0.0, noise);
  for (int k = 1; k <= 100; ++k) {
    const double a = omega * 0.1 * k;
    m.predict(0.1, noise);
    m.update({radius * std::cos(a), radius * std::sin(a)}, a + 0.5 * geometry::kPi, true, noise);
  }
  EXPECT_NEAR(m.state()[kDelta], delta, 0.01);
  EXPECT_NEAR(m.yawRate(), omega, 0.01);
  for (int k = 0; k < 200; ++k) {
    m.predict(0.05, noise);
    EXPECT_NEAR(m.centre().norm(), radius, 0.35) << "step " << k;
  }
}

TEST(MotionModel, PredictionsCompose) {
  // The arc is exact for constant steering, so one 1 s step equals ten 0.1 s steps.
  MotionNoise noise = test::seedOneNoise();
  MotionModel a;
  a.initialise({0.0, 0.0}, 0.0, 2.7, 1.3, noise);
  for (int k = 1; k <= 50; ++k) {
    a.predict(0.1, noise);
    a.update({1.0 * 0.1 * k * 10.0, 0.0}, 0.0, true, noise);
  }
  MotionModel b = a;
  a.predict(1.0, noise);
  for (int k = 0; k < 10; ++k) {
    b.predict(0.1, noise);
  }
  EXPECT_NEAR((a.centre() - b.centre()).norm(), 0.0, 0.05);
}

TEST(MotionModel, ParkedVehicleStaysPut) {
  MotionNoise noise = test::seedOneNoise();
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 0.05);
  MotionModel m;
  const Eigen::Vector2d where(10.0, -4.0);
  m.initialise(where, 1.0, 2.7, 1.3, noise);
  for (int k = 0; k < 100; ++k) {
    m.predict(0.1, noise);
    m.update(where + Eigen::Vector2d(n(rng), n(rng)), 1.0 + n(rng) * 0.5, true, noise);
  }
  EXPECT_LT(std::abs(m.state()[kV]), 0.15);
  // Ten seconds without a detection (occluded): it must not drift or turn away.
  const Eigen::Vector2d before = m.centre();
  const double headingBefore = m.heading();
  for (int k = 0; k < 100; ++k) {
    m.predict(0.1, noise);
  }
  EXPECT_LT((m.centre() - before).norm(), 0.5);
  EXPECT_LT(geometry::absAngleDifference(m.heading(), headingBefore), 0.05);
  EXPECT_LT((m.centre() - where).norm(), 0.6);
}

TEST(MotionModel, GeometryChangeAndFlipKeepTheFootprintCentre) {
  MotionNoise noise = test::seedOneNoise();
  MotionModel m;
  m.initialise({5.0, 5.0}, 0.7, 2.7, 1.3, noise);
  const Eigen::Vector2d c = m.centre();
  m.setGeometry(2.9, 1.5);
  EXPECT_NEAR((m.centre() - c).norm(), 0.0, 1e-9);
  EXPECT_DOUBLE_EQ(m.wheelbase(), 2.9);
  m.flipDirection();
  EXPECT_NEAR((m.centre() - c).norm(), 0.0, 1e-9);
  EXPECT_NEAR(geometry::absAngleDifference(m.heading(), 0.7 + geometry::kPi), 0.0, 1e-12);
}

// alongAxisFactor k: the position noise along the vehicle's axis is k sigma, across it sigma,
// at birth (covariance) and in an update (gain).
TEST(MotionModel, AlongAxisFactorWeakensPositionOnlyAlongTheAxis) {
  MotionNoise noise = test::seedOneNoise();
  noise.measurementPosition_m = 0.3;
  const double psi = 0.6;
  const Eigen::Vector2d along(std::cos(psi), std::sin(psi));
  const Eigen::Vector2d across(-along.y(), along.x());
  MotionModel weak;
  weak.initialise({0.0, 0.0}, psi, 2.7, 0.0, noise, 10.0);
  const Eigen::Matrix2d c = weak.centreCovariance();
  EXPECT_NEAR(along.dot(c * along), 100.0 * 0.09, 1e-9);
  EXPECT_NEAR(across.dot(c * across), 0.09, 1e-9);

  MotionModel plain;
  plain.initialise({0.0, 0.0}, psi, 2.7, 0.0, noise);
  weak = plain;
  const Eigen::Vector2d z = 0.5 * along + 0.5 * across;
  ASSERT_TRUE(plain.update(z, psi, true, noise));
  ASSERT_TRUE(weak.update(z, psi, true, noise, 10.0));
  EXPECT_NEAR(across.dot(weak.centre()), across.dot(plain.centre()), 1e-9);
  EXPECT_GT(along.dot(plain.centre()), 0.2);
  EXPECT_LT(along.dot(weak.centre()), 0.01);
  EXPECT_FALSE(weak.update(z, psi, true, noise, 0.5));
  EXPECT_FALSE(weak.update(z, psi, true, noise, std::nan("")));
}

TEST(MotionModel, RejectsBadInput) {
  MotionNoise noise = test::seedOneNoise();
  MotionModel m;
  m.initialise({0.0, 0.0}, 0.0, 2.7, 1.3, noise);
  EXPECT_FALSE(m.predict(-0.1, noise));
  EXPECT_FALSE(m.predict(std::nan(""), noise));
  EXPECT_FALSE(m.update({std::nan(""), 0.0}, 0.0, true, noise));
  EXPECT_TRUE(std::isfinite(m.centre().x()));
}

}  // namespace
}  // namespace vp::tracking
