#include "tracking/from_perception.hpp"

#include <vector>

#include <gtest/gtest.h>

namespace vp::tracking {
namespace {

perception::VehicleObservation lifted(double x, bool directionKnown) {
  perception::VehicleObservation o;
  o.timestamp_ns = 42;
  o.liftStatus = perception::LiftStatus::Ok;
  o.ground.centreEnu = {x, -3.0, 261.5};
  o.ground.headingEnu_rad = 4.0;
  o.ground.length_m = 4.6;
  o.ground.width_m = 1.85;
  o.detection.score = 0.7F;
  o.detection.directionKnown = directionKnown;
  o.detection.typeProbabilities = {0.1F, 0.1F, 0.1F, 0.5F, 0.1F, 0.05F, 0.05F};
  o.detection.gamma.count = 3;
  o.detection.gamma.gamma = {0.5F, -1.0F, 0.25F};
  return o;
}

TEST(FromPerception, KeepsEveryFieldTheTrackerNeeds) {
  const perception::VehicleObservation o = lifted(12.5, false);
  WorldDetection d;
  ASSERT_TRUE(toWorldDetection(o, &d));
  EXPECT_EQ(d.timestamp_ns, 42);
  EXPECT_EQ(d.centreEnu, Eigen::Vector2d(12.5, -3.0));
  EXPECT_EQ(d.headingEnu_rad, 4.0);
  EXPECT_FALSE(d.headingKnown);
  EXPECT_EQ(d.length_m, 4.6);
  EXPECT_EQ(d.width_m, 1.85);
  EXPECT_EQ(d.score, 0.7F);
  EXPECT_EQ(d.typeProbabilities, o.detection.typeProbabilities);
  EXPECT_EQ(d.shape.count, 3);
  EXPECT_EQ(d.shape.gamma, o.detection.gamma.gamma);
  ASSERT_TRUE(toWorldDetection(lifted(1.0, true), &d));
  EXPECT_TRUE(d.headingKnown);
}

TEST(FromPerception, OnlyLiftedObservationsBecomeWorldDetections) {
  std::vector<perception::VehicleObservation> observations = {lifted(1.0, true), lifted(2.0, true),
                                                              lifted(3.0, true), lifted(4.0, true)};
  observations[1].liftStatus = perception::LiftStatus::StalePose;
  observations[2].liftStatus = perception::LiftStatus::OutsideDtm;
  WorldDetection untouched;
  untouched.length_m = -1.0;
  EXPECT_FALSE(toWorldDetection(observations[1], &untouched));
  EXPECT_EQ(untouched.length_m, -1.0);

  std::vector<WorldDetection> out(4);
  ASSERT_EQ(toWorldDetections(observations, out), 2U);
  EXPECT_EQ(out[0].centreEnu.x(), 1.0);
  EXPECT_EQ(out[1].centreEnu.x(), 4.0);
  // Capacity bounds the output.
  ASSERT_EQ(toWorldDetections(observations, std::span(out).first(1)), 1U);
}

}  // namespace
}  // namespace vp::tracking
