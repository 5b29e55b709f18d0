#include "perception/detection_lifter.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "geometry/rotated_box.hpp"
#include "shape/vehicle_geometry.hpp"
#include "telemetry/pose_buffer.hpp"
#include "test_scene.hpp"

namespace vp::perception {
namespace {

using testworld::Scene;
using testworld::TruthVehicle;

struct LiftCase {
  const char* name;
  bool fixture;  // the shipped sloped DTM with its bump, else a plane
  double slopeEast;
  double slopeNorth;
  camera::LensModel lens;
  double gimbalPitch_deg;
};

class GroundTruthLift : public ::testing::TestWithParam<LiftCase> {};

// Acceptance: a perfect detection of a ground-truth vehicle (its footprint
// projected through the Lifter) lifts back to the vehicle's world position within 1 cm, on
// flat and sloped terrain, nadir and tilted, pinhole and distorted lens.
TEST_P(GroundTruthLift, PositionWithinOneCentimetre) {
  const LiftCase& tc = GetParam();
  Scene scene(tc.fixture ? testworld::fixtureDtm() : testworld::plane(tc.slopeEast, tc.slopeNorth),
              tc.lens);
  const lifting::DronePose pose = testworld::hoveringPose(30.0, tc.gimbalPitch_deg);
  const auto cameraPose = scene.lifter.cameraPose(pose);
  ASSERT_TRUE(cameraPose);

  const std::vector<TruthVehicle> truths = testworld::truthVehicles(scene.terrain, 90.0, 7.5);
  std::vector<detection::Detection> detections;
  std::vector<TruthVehicle> seen;
  for (const TruthVehicle& t : truths) {
    detection::Detection d;
    if (testworld::perfectDetection(scene, *cameraPose, t, &d)) {
      detections.push_back(d);
      seen.push_back(t);
    }
  }
  ASSERT_GT(detections.size(), 40U);
  std::vector<VehicleObservation> out(detections.size() + 3);
  const FrameLiftSummary summary = scene.detectionLifter.liftFrame(
      scene.lifter, 1234, telemetry::PoseStatus::Ok, pose, detections, out);
  ASSERT_EQ(summary.poseStatus, LiftStatus::Ok);
  ASSERT_EQ(summary.written, detections.size());
  ASSERT_EQ(summary.lifted, detections.size());
  EXPECT_EQ(summary.dropped, 0U);

  double maxPosition_m = 0.0, maxHeading_deg = 0.0, maxLength_m = 0.0, maxWidth_m = 0.0;
  double maxRearAxle_m = 0.0;
  for (std::size_t i = 0; i < detections.size(); ++i) {
    const VehicleObservation& o = out[i];
    const shape::GroundFootprint& truth = seen[i].footprint;
    ASSERT_EQ(o.liftStatus, LiftStatus::Ok) << toString(o.liftStatus);
    EXPECT_EQ(o.timestamp_ns, 1234);
    EXPECT_EQ(o.detection.box.cx, detections[i].box.cx);
    EXPECT_EQ(o.type, seen[i].type);
    maxPosition_m = std::max(maxPosition_m, (o.ground.centreEnu - truth.centreEnu).norm());
    maxHeading_deg = std::max(maxHeading_deg, geometry::absAngleDifference(o.ground.headingEnu_rad,
                                                                           truth.headingEnu_rad) *
                                                  180.0 / geometry::kPi);
    // GroundBox sizes run along the ground: the true ones are the distances between the
    // edge midpoints standing on the DTM.
    const Eigen::Vector2d fw(std::cos(truth.headingEnu_rad), std::sin(truth.headingEnu_rad));
    const Eigen::Vector2d nw(-fw.y(), fw.x());
    const auto onGround = [&](const Eigen::Vector2d& xy) {
      return *scene.terrain.groundPointEnu(xy.x(), xy.y());
    };
    const Eigen::Vector2d c = truth.centreEnu.head<2>();
    const double trueLength =
        (onGround(c + 0.5 * truth.length_m * fw) - onGround(c - 0.5 * truth.length_m * fw)).norm();
    const double trueWidth =
        (onGround(c + 0.5 * truth.width_m * nw) - onGround(c - 0.5 * truth.width_m * nw)).norm();
    maxLength_m = std::max(maxLength_m, std::abs(o.ground.length_m - trueLength));
    maxWidth_m = std::max(maxWidth_m, std::abs(o.ground.width_m - trueWidth));
    // The WGS84 centre is the ENU centre's.
    EXPECT_LT((scene.frame.toEnu(o.ground.centreWgs84) - o.ground.centreEnu).norm(), 1e-6);

    // Shape: keypoints on the DTM, footprint extent = lifted size; rear axle from the ASM.
    ASSERT_TRUE(o.hasKeypoints);
    ASSERT_TRUE(o.hasRearAxle);
    const shape::VehicleGeometry g =
        shape::vehicleGeometry(scene.asmModel, seen[i].type, detections[i].gamma);
    EXPECT_NEAR(o.height_m, g.size_m.z(), 1e-12);
    const Eigen::Vector2d f(std::cos(truth.headingEnu_rad), std::sin(truth.headingEnu_rad));
    const Eigen::Vector2d axleWant =
        truth.centreEnu.head<2>() + f * (g.rearAxle_m.x() * truth.length_m / g.size_m.x());
    maxRearAxle_m = std::max(maxRearAxle_m, (o.rearAxleEnu.head<2>() - axleWant).norm());
    const auto axleGround = scene.terrain.groundPointEnu(o.rearAxleEnu.x(), o.rearAxleEnu.y());
    ASSERT_TRUE(axleGround);
    EXPECT_NEAR(o.rearAxleEnu.z(), axleGround->z(), 2e-3);
    EXPECT_LT((scene.frame.toEnu(o.rearAxleWgs84) - o.rearAxleEnu).norm(), 1e-6);
    const int roofFrontLeft = 10;
    const auto roofGround = scene.terrain.groundPointEnu(o.keypointsEnu(0, roofFrontLeft),
                                                         o.keypointsEnu(1, roofFrontLeft));
    ASSERT_TRUE(roofGround);
    EXPECT_NEAR(o.keypointsEnu(2, roofFrontLeft) - roofGround->z(), g.keypoints_m(2, roofFrontLeft),
                2e-3);
  }
  std::printf(
      "[ %s ] %zu vehicles: max position error %.3g m, heading %.3g deg, length %.3g m, width "
      "%.3g m, rear axle %.3g m\n",
      tc.name, detections.size(), maxPosition_m, maxHeading_deg, maxLength_m, maxWidth_m,
      maxRearAxle_m);
  EXPECT_LT(maxPosition_m, 0.01);
  EXPECT_LT(maxHeading_deg, 0.01);
  EXPECT_LT(maxLength_m, 0.005);
  EXPECT_LT(maxWidth_m, 0.01);
  EXPECT_LT(maxRearAxle_m, 0.005);
}

INSTANTIATE_TEST_SUITE_P(
    Terrains, GroundTruthLift,
    ::testing::Values(
        LiftCase{"flat_nadir_pinhole", false, 0.0, 0.0, camera::LensModel::Pinhole, -90.0},
        LiftCase{"flat_tilted_brown", false, 0.0, 0.0, camera::LensModel::BrownConrady, -70.0},
        LiftCase{"sloped_tilted_brown", false, 0.12, -0.07, camera::LensModel::BrownConrady, -70.0},
        LiftCase{"steep_tilted_pinhole", false, 0.35, 0.2, camera::LensModel::Pinhole, -75.0},
        LiftCase{"fixture_dtm_tilted_brown", true, 0.0, 0.0, camera::LensModel::BrownConrady,
                 -80.0}),
    [](const auto& testInfo) { return std::string(testInfo.param.name); });

// The box a detector is trained on (the simulator's ground truth, tools/simulator/
// ground_truth.cpp) encloses the whole vehicle, roof included, in the image, aligned with its
// projected driving direction. Here: the hull of the vehicle's ASM keypoints.
std::optional<geometry::RotatedBox> hullBox(const Scene& scene,
                                            const lifting::CameraPoseWorld& pose,
                                            const TruthVehicle& truth,
                                            const detection::Detection& d) {
  const shape::VehicleGeometry g = shape::vehicleGeometry(scene.asmModel, truth.type, d.gamma);
  shape::PlacedVehicle placed;
  const auto groundZ = [&](const Eigen::Vector2d& xy) -> std::optional<double> {
    const auto p = scene.terrain.groundPointEnu(xy.x(), xy.y());
    return p ? std::optional<double>(p->z()) : std::nullopt;
  };
  if (!shape::placeOnGround(g, truth.footprint, groundZ, &placed) || !placed.hasKeypoints) {
    return std::nullopt;
  }
  const Eigen::Vector3d c = truth.footprint.centreEnu;
  const Eigen::Vector3d ahead = c + Eigen::Vector3d(std::cos(truth.footprint.headingEnu_rad),
                                                    std::sin(truth.footprint.headingEnu_rad), 0.0);
  std::vector<Eigen::Vector3d> points;
  for (int k = 0; k < placed.keypointsEnu.cols(); ++k) {
    points.push_back(placed.keypointsEnu.col(k));
  }
  const auto box = scene.lifter.enclosingImageBox(pose, c, ahead, points);
  return box ? std::optional<geometry::RotatedBox>(*box) : std::nullopt;
}

// A box that encloses the whole vehicle shows, on a tilted view, the vehicle's middle about
// half its height up: lifted at ground level its centre lands off the footprint by the
// parallax (~ h/2 tan(off-nadir angle)); lifted at half the shape's height it lands on it.
TEST(DetectionLifter, WholeVehicleBoxesLiftAtHalfTheirHeight) {
  Scene scene(testworld::plane(0.04, -0.02), camera::LensModel::BrownConrady);
  const lifting::DronePose pose = testworld::hoveringPose(30.0, -60.0);  // 30 deg off nadir
  const auto cameraPose = scene.lifter.cameraPose(pose);
  ASSERT_TRUE(cameraPose);
  std::vector<TruthVehicle> seen;
  std::vector<detection::Detection> detections;
  for (const TruthVehicle& t : testworld::truthVehicles(scene.terrain, 90.0, 7.5)) {
    detection::Detection d;
    if (!testworld::perfectDetection(scene, *cameraPose, t, &d)) {
      continue;
    }
    const auto box = hullBox(scene, *cameraPose, t, d);
    if (box && scene.camera.inImage({box->cx, box->cy}, 50.0)) {
      d.box = *box;
      detections.push_back(d);
      seen.push_back(t);
    }
  }
  ASSERT_GT(detections.size(), 40U);

  const auto medianError = [&](double share) {
    DetectionLifter lifter;
    DetectionLifterOptions options;
    options.boxHeightShare = share;
    std::string why;
    EXPECT_TRUE(lifter.init(scene.terrain, scene.frame, scene.asmModel, options, &why)) << why;
    std::vector<VehicleObservation> out(detections.size());
    const FrameLiftSummary summary =
        lifter.liftFrame(scene.lifter, 1, telemetry::PoseStatus::Ok, pose, detections, out);
    EXPECT_EQ(summary.lifted, detections.size());
    std::vector<double> errors;
    for (std::size_t i = 0; i < detections.size(); ++i) {
      errors.push_back(
          (out[i].ground.centreEnu.head<2>() - seen[i].footprint.centreEnu.head<2>()).norm());
    }
    std::nth_element(errors.begin(), errors.begin() + static_cast<long>(errors.size() / 2),
                     errors.end());
    return errors[errors.size() / 2];
  };
  const double atGround = medianError(0.0);
  const double atHalfHeight = medianError(0.5);
  std::printf(
      "[ hull boxes, 30 deg off nadir ] %zu vehicles: median position error %.3f m at "
      "ground level, %.3f m at half height\n",
      detections.size(), atGround, atHalfHeight);
  EXPECT_GT(atGround, 0.25);  // ~0.75 m * tan(30 deg) and more off-centre
  EXPECT_LT(atHalfHeight, 0.10);
  EXPECT_LT(atHalfHeight, 0.3 * atGround);

  DetectionLifter bad;
  DetectionLifterOptions wrong;
  wrong.boxHeightShare = 1.5;
  std::string why;
  EXPECT_FALSE(bad.init(scene.terrain, scene.frame, scene.asmModel, wrong, &why));
  EXPECT_NE(why.find("box height share"), std::string::npos) << why;
}

// Returns true when the observation carries no world value (all zero, flags off).
bool noWorldValues(const VehicleObservation& o) {
  return o.ground.centreEnu == Eigen::Vector3d::Zero() && o.ground.length_m == 0.0 &&
         o.ground.centreWgs84.latitude_deg == 0.0 && !o.hasKeypoints && !o.hasRearAxle &&
         o.rearAxleEnu == Eigen::Vector3d::Zero() && o.keypointsEnu.isZero();
}

TEST(DetectionLifter, MissingStaleOrInvalidPoseKeepsDetectionsWithoutWorldPosition) {
  Scene scene(testworld::plane(0.0, 0.0), camera::LensModel::Pinhole);
  const lifting::DronePose pose = testworld::hoveringPose(0.0, -90.0);
  const auto cameraPose = scene.lifter.cameraPose(pose);
  ASSERT_TRUE(cameraPose);
  std::vector<detection::Detection> detections;
  for (const TruthVehicle& t : testworld::truthVehicles(scene.terrain, 20.0, 10.0)) {
    detection::Detection d;
    if (testworld::perfectDetection(scene, *cameraPose, t, &d)) {
      detections.push_back(d);
    }
  }
  ASSERT_GE(detections.size(), 9U);
  std::vector<VehicleObservation> out(detections.size());

  telemetry::PoseBuffer buffer;
  ASSERT_TRUE(buffer.init({}));
  constexpr std::int64_t kMs = 1'000'000;
  const auto lift = [&](std::int64_t t) {
    return scene.detectionLifter.liftFrame(scene.lifter, t, buffer.poseAt(t), detections, out);
  };
  const auto expectAll = [&](const FrameLiftSummary& s, LiftStatus want) {
    EXPECT_EQ(s.poseStatus, want);
    EXPECT_EQ(s.lifted, 0U);
    ASSERT_EQ(s.written, detections.size());
    for (std::size_t i = 0; i < s.written; ++i) {
      EXPECT_EQ(out[i].liftStatus, want);
      EXPECT_EQ(out[i].detection.box.cx, detections[i].box.cx);  // kept in image space
      EXPECT_TRUE(noWorldValues(out[i])) << i;
    }
  };
  // No telemetry at all.
  expectAll(lift(1000 * kMs), LiftStatus::NoPose);

  telemetry::PoseSample sample;
  sample.timestamp_ns = 1000 * kMs;
  sample.position = pose.position;
  sample.bodyToNed = pose.bodyToNed;
  sample.gimbal = pose.gimbal;
  ASSERT_EQ(buffer.push(sample), telemetry::PushResult::Accepted);
  EXPECT_EQ(lift(1000 * kMs).lifted, detections.size());
  // Telemetry stopped 300 ms before the frame.
  expectAll(lift(1300 * kMs), LiftStatus::StalePose);
  // The frame is before any telemetry.
  expectAll(lift(500 * kMs), LiftStatus::NoPose);
  // The link now sends NaN: rejected, counted, and the next frame has an invalid pose.
  sample.timestamp_ns = 1050 * kMs;
  sample.position.latitude_deg = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(buffer.push(sample), telemetry::PushResult::NotFinite);
  EXPECT_EQ(buffer.counters().notFinite, 1U);
  expectAll(lift(1060 * kMs), LiftStatus::InvalidPose);

  // A pose handed over directly as Ok but unusable (NaN, zero quaternion) is caught too.
  lifting::DronePose bad = pose;
  bad.position.height_m = std::numeric_limits<double>::infinity();
  expectAll(scene.detectionLifter.liftFrame(scene.lifter, 0, telemetry::PoseStatus::Ok, bad,
                                            detections, out),
            LiftStatus::InvalidPose);
  bad = pose;
  bad.bodyToNed.coeffs().setZero();
  expectAll(scene.detectionLifter.liftFrame(scene.lifter, 0, telemetry::PoseStatus::Ok, bad,
                                            detections, out),
            LiftStatus::InvalidPose);
}

TEST(DetectionLifter, RaysLeavingTheDtmOrMeetingNoDataGiveAStatus) {
  // The fixture DTM covers +-100 m; a camera 35 deg below the horizon sees past its edge.
  Scene scene(testworld::fixtureDtm(), camera::LensModel::Pinhole);
  const lifting::DronePose pose = testworld::hoveringPose(0.0, -35.0);
  const auto cameraPose = scene.lifter.cameraPose(pose);
  ASSERT_TRUE(cameraPose);
  std::vector<detection::Detection> detections(4);
  for (auto& d : detections) {
    d.box = {1295.5, 1023.5, 60.0, 25.0, 0.5};
    d.directionKnown = true;
    d.typeProbabilities.fill(1.0F / shape::kVehicleTypeCount);
  }
  detections[0].box.cy = 5.0;     // top row: far beyond the DTM's north edge
  detections[1].box.cy = 2040.0;  // bottom row: on the DTM
  detections[2].box.length = std::numeric_limits<double>::quiet_NaN();
  detections[3].box.width = 0.0;
  // NoData: the south-east corner sample of the fixture (col 40, row 40) is missing.
  const geodesy::UtmPoint centre = geodesy::toUtm(testworld::kOrigin);
  geodesy::UtmPoint corner = centre;
  corner.easting_m = 304510.0 + 99.0;
  corner.northing_m = 4771731.0 - 99.0;
  corner.height_m = 260.0 + 0.03 * 99.0;
  const Eigen::Vector3d cornerEnu = scene.frame.toEnu(geodesy::fromUtm(corner));
  // A nadir view from 100 m above that corner.
  lifting::DronePose nadir = testworld::hoveringPose(0.0, -90.0);
  nadir.position = geodesy::fromUtm(corner);
  nadir.position.height_m += testworld::kAltitude_m;
  const auto nadirPose = scene.lifter.cameraPose(nadir);
  ASSERT_TRUE(nadirPose);
  const auto cornerPixel = scene.lifter.worldToPixel(*nadirPose, cornerEnu);
  ASSERT_TRUE(cornerPixel);
  ASSERT_TRUE(scene.camera.inImage(*cornerPixel));

  std::vector<VehicleObservation> out(detections.size());
  const FrameLiftSummary s = scene.detectionLifter.liftFrame(
      scene.lifter, 7, telemetry::PoseStatus::Ok, pose, detections, out);
  EXPECT_EQ(s.poseStatus, LiftStatus::Ok);
  EXPECT_EQ(s.lifted, 1U);
  EXPECT_TRUE(out[0].liftStatus == LiftStatus::OutsideDtm ||
              out[0].liftStatus == LiftStatus::NoIntersection)
      << toString(out[0].liftStatus);
  EXPECT_TRUE(noWorldValues(out[0]));
  EXPECT_EQ(out[1].liftStatus, LiftStatus::Ok) << toString(out[1].liftStatus);
  EXPECT_EQ(out[2].liftStatus, LiftStatus::InvalidBox);
  EXPECT_EQ(out[3].liftStatus, LiftStatus::InvalidBox);
  EXPECT_TRUE(noWorldValues(out[2]));

  detection::Detection noData = detections[1];
  noData.box.cx = cornerPixel->x();
  noData.box.cy = cornerPixel->y();
  noData.box.length = 20.0;
  noData.box.width = 10.0;
  VehicleObservation one;
  scene.detectionLifter.liftFrame(scene.lifter, 7, telemetry::PoseStatus::Ok, nadir,
                                  std::span(&noData, 1), std::span(&one, 1));
  EXPECT_EQ(one.liftStatus, LiftStatus::NoData) << toString(one.liftStatus);
  EXPECT_TRUE(noWorldValues(one));
}

TEST(DetectionLifter, CapacityAndOrderAreKept) {
  Scene scene(testworld::plane(0.0, 0.0), camera::LensModel::Pinhole);
  const lifting::DronePose pose = testworld::hoveringPose(0.0, -90.0);
  std::vector<detection::Detection> detections(5);
  for (std::size_t i = 0; i < detections.size(); ++i) {
    detections[i].box = {1000.0 + 100.0 * static_cast<double>(i), 1000.0, 60.0, 25.0, 0.0};
    detections[i].typeProbabilities[static_cast<std::size_t>(shape::VehicleType::Large)] = 1.0F;
  }
  std::vector<VehicleObservation> out(3);
  const FrameLiftSummary s = scene.detectionLifter.liftFrame(
      scene.lifter, 1, telemetry::PoseStatus::Ok, pose, detections, out);
  EXPECT_EQ(s.written, 3U);
  EXPECT_EQ(s.dropped, 2U);
  EXPECT_EQ(s.lifted, 3U);
  for (std::size_t i = 0; i < out.size(); ++i) {
    EXPECT_EQ(out[i].detection.box.cx, detections[i].box.cx);
    EXPECT_EQ(out[i].type, shape::VehicleType::Large);
    EXPECT_FALSE(out[i].hasKeypoints);  // no ASM for large vehicles
    EXPECT_TRUE(out[i].hasRearAxle);    // the length rule
    EXPECT_EQ(out[i].height_m, 0.0);
  }
}

TEST(DetectionLifter, LiftingAFrameDoesNotAllocate) {
  Scene scene(testworld::plane(0.12, -0.07), camera::LensModel::BrownConrady);
  const lifting::DronePose pose = testworld::hoveringPose(30.0, -70.0);
  const auto cameraPose = scene.lifter.cameraPose(pose);
  ASSERT_TRUE(cameraPose);
  std::vector<detection::Detection> detections;
  for (const TruthVehicle& t : testworld::truthVehicles(scene.terrain, 60.0, 10.0)) {
    detection::Detection d;
    if (testworld::perfectDetection(scene, *cameraPose, t, &d)) {
      detections.push_back(d);
    }
  }
  detections.push_back(detections.front());
  detections.back().box.cy = -5000.0;  // a failing one too
  ASSERT_GT(detections.size(), 40U);
  std::vector<VehicleObservation> out(detection::kMaxDetectionsPerFrame);
  telemetry::PoseBuffer buffer;
  ASSERT_TRUE(buffer.init({}));
  telemetry::PoseSample sample;
  sample.position = pose.position;
  sample.bodyToNed = pose.bodyToNed;
  sample.gimbal = pose.gimbal;

  vp::test::AllocationCounter counter;
  std::size_t lifted = 0;
  for (int frame = 0; frame < 5; ++frame) {
    sample.timestamp_ns = frame * 100'000'000LL;
    buffer.push(sample);
    const FrameLiftSummary s = scene.detectionLifter.liftFrame(
        scene.lifter, sample.timestamp_ns, buffer.poseAt(sample.timestamp_ns), detections, out);
    lifted += s.lifted;
  }
  counter.stop();
  std::printf("%zu detections x 5 frames lifted, %zu allocations\n", detections.size(),
              counter.count());
  EXPECT_EQ(lifted, 5 * (detections.size() - 1));
  EXPECT_EQ(counter.count(), 0U);
}

}  // namespace
}  // namespace vp::perception
