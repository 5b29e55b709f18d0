#include "lifting/lifting.hpp"

#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "plane_dtm.hpp"

namespace vp::lifting {
namespace {

const geodesy::GeodeticPoint kOrigin{43.0731, -89.4012, 260.0};
constexpr double kGround_m = 260.0;    // DTM height at the origin (ellipsoidal)
constexpr double kAltitude_m = 100.0;  // drone above the ground at the origin
constexpr double kHalfExtent_m = 400.0;
constexpr double kCell_m = 2.0;

// A UTM 16N grid around the origin: height = 260 + slopeEast * dE + slopeNorth * dN.
terrain::TerrainGrid makeGrid(double slopeEast, double slopeNorth) {
  return test::planeDtm(kOrigin, kGround_m, slopeEast, slopeNorth, kHalfExtent_m, kCell_m);
}

camera::CameraModel makeCamera(camera::LensModel model) {
  camera::Intrinsics in{2592, 2048, 2900.0, 2900.0, 1295.5, 1023.5};
  camera::Distortion d;
  d.model = model;
  if (model == camera::LensModel::BrownConrady) {
    d.k1 = -0.12;
    d.k2 = 0.08;
    d.p1 = 1e-4;
    d.p2 = -2e-4;
    d.k3 = -0.01;
  }
  camera::CameraModel cam;
  std::string why;
  EXPECT_TRUE(cam.init(in, d, &why)) << why;
  return cam;
}

struct Scene {
  geodesy::LocalFrame frame{kOrigin};
  terrain::TerrainModel terrain;
  camera::CameraModel camera;
  geodesy::CameraMount mount;
  Lifter lifter;

  Scene(double slopeEast, double slopeNorth, camera::LensModel lens) {
    std::string why;
    EXPECT_TRUE(terrain.init(makeGrid(slopeEast, slopeNorth), frame, &why)) << why;
    camera = makeCamera(lens);
    mount.leverArm_m = {0.10, 0.0, 0.20};
    EXPECT_TRUE(lifter.init(camera, mount, terrain, frame, &why)) << why;
  }
};

DronePose hoveringPose(double yaw_deg, double gimbalPitch_deg) {
  DronePose pose;
  pose.position = {kOrigin.latitude_deg, kOrigin.longitude_deg, kGround_m + kAltitude_m};
  pose.bodyToNed = Eigen::Quaterniond(geodesy::rotationFromEuler({1.5, -2.0, yaw_deg}));
  pose.gimbal.angles = {0.0, gimbalPitch_deg, 0.0};
  return pose;
}

struct RoundTripCase {
  const char* name;
  double slopeEast;
  double slopeNorth;
  camera::LensModel lens;
};

class RoundTrip : public ::testing::TestWithParam<RoundTripCase> {};

// Acceptance: world -> pixel -> world from 100 m with a camera tilted 20 deg off nadir,
// on a flat and on a sloped DTM, returns within 1 mm.
TEST_P(RoundTrip, WorldToPixelToWorldWithinOneMillimetre) {
  const RoundTripCase& tc = GetParam();
  Scene scene(tc.slopeEast, tc.slopeNorth, tc.lens);
  const auto pose = scene.lifter.cameraPose(hoveringPose(30.0, -70.0));
  ASSERT_TRUE(pose);
  double maxError_m = 0.0;
  int checked = 0;
  for (double x = -150.0; x <= 150.0; x += 2.5) {
    for (double y = -150.0; y <= 150.0; y += 2.5) {
      const auto world = scene.terrain.groundPointEnu(x, y);
      ASSERT_TRUE(world);
      const auto pixel = scene.lifter.worldToPixel(*pose, *world);
      if (!pixel || !scene.camera.inImage(*pixel)) {
        continue;
      }
      const auto back = scene.lifter.pixelToWorld(*pose, *pixel);
      ASSERT_TRUE(back) << toString(back.error()) << " at " << pixel->transpose();
      maxError_m = std::max(maxError_m, (*back - *world).norm());
      ++checked;
    }
  }
  std::printf("[ %s ] %d points in view, max world->pixel->world error %.3g m\n", tc.name, checked,
              maxError_m);
  EXPECT_GT(checked, 500);  // the view covers hundreds of sample points
  EXPECT_LT(maxError_m, 1e-3);
}

INSTANTIATE_TEST_SUITE_P(
    Terrains, RoundTrip,
    ::testing::Values(RoundTripCase{"flat_pinhole", 0.0, 0.0, camera::LensModel::Pinhole},
                      RoundTripCase{"flat_brown", 0.0, 0.0, camera::LensModel::BrownConrady},
                      RoundTripCase{"sloped_brown", 0.12, -0.07, camera::LensModel::BrownConrady},
                      RoundTripCase{"steep_brown", 0.45, 0.25, camera::LensModel::BrownConrady},
                      RoundTripCase{"sloped_spherical", 0.12, -0.07,
                                    camera::LensModel::EquivalentSpherical}),
    [](const auto& testInfo) { return std::string(testInfo.param.name); });

TEST(Lifting, PixelToWorldToPixelOverTheWholeImage) {
  Scene scene(0.12, -0.07, camera::LensModel::BrownConrady);
  const auto pose = scene.lifter.cameraPose(hoveringPose(-45.0, -70.0));
  ASSERT_TRUE(pose);
  double maxError_px = 0.0;
  for (double u = 0.0; u < 2592.0; u += 64.0) {
    for (double v = 0.0; v < 2048.0; v += 64.0) {
      const auto world = scene.lifter.pixelToWorld(*pose, {u, v});
      ASSERT_TRUE(world) << u << ", " << v << ": " << toString(world.error());
      const auto pixel = scene.lifter.worldToPixel(*pose, *world);
      ASSERT_TRUE(pixel);
      maxError_px = std::max(maxError_px, (*pixel - Eigen::Vector2d(u, v)).norm());
    }
  }
  EXPECT_LT(maxError_px, 1e-3);
}

TEST(Lifting, RaysLeavingTheDtmGiveAStatus) {
  Scene scene(0.0, 0.0, camera::LensModel::Pinhole);
  // Nearly horizontal camera: the upper image rows look past the DTM's edge or the horizon.
  const auto pose = scene.lifter.cameraPose(hoveringPose(0.0, -5.0));
  ASSERT_TRUE(pose);
  const auto sky = scene.lifter.pixelToWorld(*pose, {1295.5, 0.0});
  ASSERT_FALSE(sky);
  EXPECT_TRUE(sky.error() == LiftError::NoIntersection || sky.error() == LiftError::OutsideDtm)
      << toString(sky.error());

  // A drone far outside the DTM looking straight down.
  DronePose away = hoveringPose(0.0, -90.0);
  away.position.latitude_deg += 0.02;  // about 2.2 km north
  const auto awayPose = scene.lifter.cameraPose(away);
  ASSERT_TRUE(awayPose);
  const auto miss = scene.lifter.pixelToWorld(*awayPose, {1295.5, 1023.5});
  ASSERT_FALSE(miss);
  EXPECT_EQ(miss.error(), LiftError::OutsideDtm);
}

TEST(Lifting, InvalidPoseIsRejected) {
  Scene scene(0.0, 0.0, camera::LensModel::Pinhole);
  DronePose nan = hoveringPose(0.0, -90.0);
  nan.position.latitude_deg = std::nan("");
  EXPECT_EQ(scene.lifter.cameraPose(nan).error(), LiftError::InvalidPose);
  DronePose zeroQ = hoveringPose(0.0, -90.0);
  zeroQ.bodyToNed = Eigen::Quaterniond(0.0, 0.0, 0.0, 0.0);
  EXPECT_EQ(scene.lifter.cameraPose(zeroQ).error(), LiftError::InvalidPose);
}

TEST(Lifting, BoxToGroundGivesHeadingAndSize) {
  Scene scene(0.0, 0.0, camera::LensModel::Pinhole);
  DronePose pose = hoveringPose(0.0, -90.0);
  pose.bodyToNed = Eigen::Quaterniond::Identity();  // level, heading north: north-up image
  const auto camPose = scene.lifter.cameraPose(pose);
  ASSERT_TRUE(camPose);
  // Ground sample distance at nadir: (altitude - lever arm) / f.
  const double gsd = (kAltitude_m - 0.20) / 2900.0;
  const geometry::RotatedBox east{1295.5, 1023.5, 4.5 / gsd, 1.8 / gsd, 0.0};
  const auto g = scene.lifter.boxToGround(*camPose, east);
  ASSERT_TRUE(g) << toString(g.error());
  EXPECT_NEAR(g->length_m, 4.5, 1e-3);
  EXPECT_NEAR(g->width_m, 1.8, 1e-3);
  EXPECT_NEAR(g->headingEnu_rad, 0.0, 1e-4);  // +u is east
  EXPECT_NEAR(g->headingTrueNorth_deg, 90.0, 1e-2);
  EXPECT_NEAR(g->centreWgs84.height_m, kGround_m, 1e-3);

  geometry::RotatedBox south = east;
  south.angle = geometry::kPi / 2.0;  // +v is down the image: south
  const auto s = scene.lifter.boxToGround(*camPose, south);
  ASSERT_TRUE(s);
  EXPECT_NEAR(s->headingEnu_rad, 1.5 * geometry::kPi, 1e-4);
  EXPECT_NEAR(s->headingTrueNorth_deg, 180.0, 1e-2);

  geometry::RotatedBox west = east;
  west.angle = geometry::kPi;  // the same outline driving the other way
  const auto w = scene.lifter.boxToGround(*camPose, west);
  ASSERT_TRUE(w);
  EXPECT_NEAR(w->headingTrueNorth_deg, 270.0, 1e-2);
  EXPECT_NEAR(w->length_m, g->length_m, 1e-9);
}

}  // namespace
}  // namespace vp::lifting
