// tests/perception/lane_prior: the site's lanes as a prior on front/back. Perfect detections of
// vehicles on a grid, each given a short lane of its own (along it, against it, or none): a
// detection shown reversed in its lane is turned round when its own front/back is unsure and
// then equals the correct detection lifted (heading, corners, keypoints, rear axle); one the
// crops are sure of, a vehicle outside every lane and one without a world position are left as
// they were; the prior's value bounds what it turns; no allocation.
#include "perception/lane_prior.hpp"

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "geometry/rotated_box.hpp"
#include "test_scene.hpp"

namespace vp::perception {
namespace {

using testworld::Scene;
using testworld::TruthVehicle;

// What the lanes of a vehicle's cell say about it.
enum class LaneCase { Along, Against, None };
LaneCase laneCaseOf(std::size_t i) {
  return static_cast<LaneCase>(i % 3);
}

struct LaneWorld {
  Scene scene{testworld::plane(0.04, -0.02), camera::LensModel::BrownConrady};
  lifting::DronePose pose = testworld::hoveringPose(30.0, -80.0);
  lifting::CameraPoseWorld cameraPose{};
  site::Site site{"lanes.geojson"};
  std::vector<detection::Detection> truth;    // perfect detections, the true front
  std::vector<VehicleObservation> reference;  // them lifted
  std::vector<VehicleObservation> reversed;   // the same vehicles shown back to front

  LaneWorld() {
    const auto camera = scene.lifter.cameraPose(pose);
    EXPECT_TRUE(camera);
    cameraPose = *camera;
    // Lanes 6 m long: shorter than the grid's step, so a lane holds one vehicle only.
    for (const TruthVehicle& t : testworld::truthVehicles(scene.terrain, 60.0, 9.0)) {
      detection::Detection d;
      if (!testworld::perfectDetection(scene, cameraPose, t, &d)) {
        continue;
      }
      const std::size_t i = truth.size();
      truth.push_back(d);
      if (laneCaseOf(i) == LaneCase::None) {
        continue;
      }
      const double heading =
          t.footprint.headingEnu_rad + (laneCaseOf(i) == LaneCase::Against ? geometry::kPi : 0.0);
      const Eigen::Vector2d forward(std::cos(heading), std::sin(heading));
      const Eigen::Vector2d centre = t.footprint.centreEnu.head<2>();
      // Three vertices with a repeated one: the lane's direction comes from its segments.
      const std::vector<Eigen::Vector2d> line = {centre - 3.0 * forward, centre, centre,
                                                 centre + 3.0 * forward};
      site::Feature lane;
      lane.kind = site::FeatureKind::Lane;
      lane.id = "lane-" + std::to_string(i);
      lane.width_m = 3.5;
      site.append(lane, line);
    }
    reference.resize(truth.size());
    const FrameLiftSummary summary = scene.detectionLifter.liftFrame(
        scene.lifter, 77, telemetry::PoseStatus::Ok, pose, truth, reference);
    EXPECT_EQ(summary.lifted, truth.size());
    std::vector<detection::Detection> turned = truth;
    for (detection::Detection& d : turned) {
      d.box.angle = geometry::wrapTwoPi(d.box.angle + geometry::kPi);
    }
    reversed.resize(truth.size());
    scene.detectionLifter.liftFrame(scene.lifter, 77, telemetry::PoseStatus::Ok, pose, turned,
                                    reversed);
  }
};

void expectSameWorld(const VehicleObservation& a, const VehicleObservation& b, std::size_t i) {
  ASSERT_EQ(a.liftStatus, b.liftStatus) << i;
  EXPECT_NEAR((a.ground.centreEnu - b.ground.centreEnu).norm(), 0.0, 1e-9) << i;
  EXPECT_NEAR(geometry::absAngleDifference(a.ground.headingEnu_rad, b.ground.headingEnu_rad), 0.0,
              1e-9)
      << i;
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_NEAR((a.ground.cornersEnu[k] - b.ground.cornersEnu[k]).norm(), 0.0, 1e-9) << i;
  }
  EXPECT_EQ(a.hasKeypoints, b.hasKeypoints) << i;
  EXPECT_NEAR((a.keypointsEnu - b.keypointsEnu).norm(), 0.0, 1e-9) << i;
  EXPECT_EQ(a.hasRearAxle, b.hasRearAxle) << i;
  EXPECT_NEAR((a.rearAxleEnu - b.rearAxleEnu).norm(), 0.0, 1e-9) << i;
}

TEST(LanePrior, TurnsUnsureDetectionsToTheirLaneAndLeavesTheRest) {
  LaneWorld w;
  ASSERT_GT(w.truth.size(), 60U);
  ASSERT_GT(w.site.count(site::FeatureKind::Lane), 40U);
  LanePrior prior;
  std::string why;
  ASSERT_TRUE(prior.init(&w.site, 0.99, &w.scene.detectionLifter, &why)) << why;
  ASSERT_TRUE(prior.active());

  // Every vehicle shown reversed; of those in a lane along their way, every other one with crops
  // that are sure of the wrong front (p = 0.002: confidence 0.998 above the prior); of those in
  // a lane against their way, likewise sure (a wrong-way driver seen clearly) or unsure.
  std::vector<VehicleObservation> observations = w.reversed;
  for (std::size_t i = 0; i < observations.size(); ++i) {
    observations[i].detection.flipProbability = (i / 3) % 2 == 0 ? 0.3F : 0.002F;
  }
  // One without a world position, in its lane: never looked at.
  observations[0].liftStatus = LiftStatus::NoPose;
  const std::vector<VehicleObservation> before = observations;

  vp::test::AllocationCounter counter;
  const LaneScreening result = prior.apply(observations, w.scene.lifter, w.cameraPose);
  counter.stop();
  EXPECT_EQ(counter.count(), 0U);

  std::size_t inLane = 0, against = 0, turned = 0;
  for (std::size_t i = 0; i < observations.size(); ++i) {
    const VehicleObservation& o = observations[i];
    const bool sure = (i / 3) % 2 != 0;
    if (i == 0 || laneCaseOf(i) == LaneCase::None) {
      EXPECT_EQ(o.detection.box.angle, before[i].detection.box.angle) << i;
      expectSameWorld(o, before[i], i);
      continue;
    }
    ++inLane;
    if (laneCaseOf(i) == LaneCase::Against) {
      // Shown reversed in a lane against the vehicle: the shown front is the lane's way.
      expectSameWorld(o, before[i], i);
      continue;
    }
    ++against;
    if (sure) {
      expectSameWorld(o, before[i], i);
      EXPECT_FLOAT_EQ(o.detection.flipProbability, 0.002F) << i;
    } else {
      ++turned;
      expectSameWorld(o, w.reference[i], i);
      EXPECT_NEAR(geometry::absAngleDifference(o.detection.box.angle, w.truth[i].box.angle), 0.0,
                  1e-9)
          << i;
      EXPECT_FLOAT_EQ(o.detection.flipProbability, 0.7F) << i;
      EXPECT_EQ(o.timestamp_ns, 77) << i;
    }
  }
  EXPECT_EQ(result.inLane, inLane);
  EXPECT_EQ(result.against, against);
  EXPECT_EQ(result.turned, turned);
  EXPECT_GT(turned, 10U);
}

TEST(LanePrior, ThePriorBoundsWhatItTurns) {
  LaneWorld w;
  std::vector<VehicleObservation> observations = w.reversed;
  for (VehicleObservation& o : observations) {
    o.detection.flipProbability = 0.002F;  // every crop sure, confidence 0.998
  }
  std::size_t along = 0;
  for (std::size_t i = 0; i < observations.size(); ++i) {
    along += laneCaseOf(i) == LaneCase::Along ? 1 : 0;
  }
  LanePrior prior;
  // 0.99: below every detection's confidence, nothing turns.
  ASSERT_TRUE(prior.init(&w.site, 0.99, &w.scene.detectionLifter));
  std::vector<VehicleObservation> copy = observations;
  EXPECT_EQ(prior.apply(copy, w.scene.lifter, w.cameraPose).turned, 0U);
  // 1: the lanes decide every front a crop is not certain of.
  ASSERT_TRUE(prior.init(&w.site, 1.0, &w.scene.detectionLifter));
  copy = observations;
  EXPECT_EQ(prior.apply(copy, w.scene.lifter, w.cameraPose).turned, along);
  // 0.5: the lanes say nothing; inactive.
  ASSERT_TRUE(prior.init(&w.site, 0.5, &w.scene.detectionLifter));
  EXPECT_FALSE(prior.active());
  copy = observations;
  EXPECT_EQ(prior.apply(copy, w.scene.lifter, w.cameraPose).inLane, 0U);
  // No lifter or no site: inactive.
  ASSERT_TRUE(prior.init(&w.site, 0.99, nullptr));
  EXPECT_FALSE(prior.active());
  ASSERT_TRUE(prior.init(nullptr, 0.99, &w.scene.detectionLifter));
  EXPECT_FALSE(prior.active());
}

TEST(LanePrior, RefusesAPriorOutsideItsRange) {
  LanePrior prior;
  std::string why;
  EXPECT_FALSE(prior.init(nullptr, 0.4, nullptr, &why));
  EXPECT_NE(why.find("site.lane_direction_prior"), std::string::npos) << why;
  EXPECT_FALSE(prior.init(nullptr, 1.01, nullptr, &why));
  EXPECT_FALSE(prior.init(nullptr, std::nan(""), nullptr, &why));
}

}  // namespace
}  // namespace vp::perception
