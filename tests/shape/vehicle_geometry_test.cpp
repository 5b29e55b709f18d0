#include "shape/vehicle_geometry.hpp"

#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"

namespace vp::shape {
namespace {

const std::string kDefaultAsm = std::string(VP_SOURCE_DIR) + "/models/asm/default_asm.yaml";

ActiveShapeModel loadDefault() {
  ActiveShapeModel model;
  std::string why;
  EXPECT_TRUE(model.load(kDefaultAsm, &why)) << why;
  return model;
}

ShapeParams gammaOf(float g1, float g2, float g3) {
  ShapeParams p;
  p.count = 3;
  p.gamma = {g1, g2, g3};
  return p;
}

TEST(VehicleGeometry, MeanShapeSizeAtGammaZero) {
  const ActiveShapeModel model = loadDefault();
  const VehicleGeometry g = vehicleGeometry(model, VehicleType::Sedan, gammaOf(0, 0, 0));
  ASSERT_TRUE(g.hasKeypoints);
  const Eigen::Vector3d meanSize = boundingBoxSize(model.mean());
  std::printf("mean shape L W H = %.3f %.3f %.3f m\n", meanSize.x(), meanSize.y(), meanSize.z());
  EXPECT_NEAR(g.size_m.x(), meanSize.x(), 1e-12);
  EXPECT_NEAR(g.size_m.y(), meanSize.y(), 1e-12);
  EXPECT_NEAR(g.size_m.z(), meanSize.z(), 1e-12);
  EXPECT_EQ(g.keypoints_m, model.mean());
  // A plausible car, footprint centred on the vehicle-frame origin (docs/asm.md).
  EXPECT_GT(g.size_m.x(), 4.0);
  EXPECT_LT(g.size_m.x(), 5.2);
  EXPECT_NEAR(g.footprintCentre_m.norm(), 0.0, 1e-9);
}

TEST(VehicleGeometry, RearAxleLiesBetweenTheRearWheelsOnTheRoad) {
  const ActiveShapeModel model = loadDefault();
  for (const ShapeParams& p : {gammaOf(0, 0, 0), gammaOf(1.5F, -1.0F, 0.5F), gammaOf(-2, 1, -1)}) {
    const VehicleGeometry g = vehicleGeometry(model, VehicleType::Compact, p);
    ASSERT_TRUE(g.hasKeypoints);
    const auto& wheels = wheelCentreKeypoints();
    const Eigen::Vector3d left = g.keypoints_m.col(wheels[2]);
    const Eigen::Vector3d right = g.keypoints_m.col(wheels[3]);
    EXPECT_NEAR(g.rearAxle_m.x(), 0.5 * (left.x() + right.x()), 1e-12);
    EXPECT_NEAR(g.rearAxle_m.y(), 0.5 * (left.y() + right.y()), 1e-12);
    EXPECT_EQ(g.rearAxle_m.z(), 0.0);  // seed 002: the point at street level
    EXPECT_LT(g.rearAxle_m.y(), left.y());
    EXPECT_GT(g.rearAxle_m.y(), right.y());
    // Behind the centre, ahead of the rear bumper.
    EXPECT_LT(g.rearAxle_m.x(), -0.5);
    EXPECT_GT(g.rearAxle_m.x(), -0.5 * g.size_m.x());
  }
}

TEST(VehicleGeometry, MissingGammaUsesTheTypePriorAndLargeVehiclesHaveNoKeypoints) {
  const ActiveShapeModel model = loadDefault();
  const TypePrior& prior = model.typePrior(VehicleType::Van);
  ASSERT_GT(prior.sampleCount, 0);
  const VehicleGeometry none = vehicleGeometry(model, VehicleType::Van, ShapeParams{});
  const VehicleGeometry mean =
      vehicleGeometry(model, VehicleType::Van,
                      gammaOf(static_cast<float>(prior.mean[0]), static_cast<float>(prior.mean[1]),
                              static_cast<float>(prior.mean[2])));
  ASSERT_TRUE(none.hasKeypoints);
  EXPECT_TRUE(none.keypoints_m.isApprox(mean.keypoints_m, 1e-12));
  // Vans are taller than sports cars under their priors.
  const VehicleGeometry sports = vehicleGeometry(model, VehicleType::Sports, ShapeParams{});
  EXPECT_GT(none.size_m.z(), sports.size_m.z() + 0.2);

  const VehicleGeometry large = vehicleGeometry(model, VehicleType::Large, gammaOf(1, 1, 1));
  EXPECT_FALSE(large.hasKeypoints);
  EXPECT_EQ(large.size_m, Eigen::Vector3d::Zero());
}

// Placement: the footprint of the placed keypoints is the detected one (centre, heading,
// length, width), heights are the ASM's above the ground under each keypoint.
TEST(VehicleGeometry, PlacementMatchesTheFootprintAndStandsOnTheGround) {
  const ActiveShapeModel model = loadDefault();
  const VehicleGeometry g = vehicleGeometry(model, VehicleType::Suv, gammaOf(0.8F, -0.2F, -0.5F));
  ASSERT_TRUE(g.hasKeypoints);
  GroundFootprint footprint;
  footprint.centreEnu = {12.0, -7.0, 3.0};
  footprint.headingEnu_rad = 2.3;
  footprint.length_m = g.size_m.x() * 1.05;  // the detector saw it 5 % longer
  footprint.width_m = g.size_m.y() * 0.97;
  // Ground: a 10 % slope towards north-east.
  const auto groundZ = [](const Eigen::Vector2d& xy) -> std::optional<double> {
    return 3.0 + 0.1 * ((xy.x() - 12.0) + (xy.y() + 7.0));
  };
  PlacedVehicle placed;
  ASSERT_TRUE(placeOnGround(g, footprint, groundZ, &placed));
  ASSERT_TRUE(placed.hasKeypoints);
  EXPECT_NEAR(placed.lengthScale, 1.05, 1e-12);
  EXPECT_NEAR(placed.widthScale, 0.97, 1e-12);
  // Back into the footprint's frame.
  const Eigen::Vector2d f(std::cos(footprint.headingEnu_rad), std::sin(footprint.headingEnu_rad));
  const Eigen::Vector2d n(-f.y(), f.x());
  double minA = 1e9, maxA = -1e9, minC = 1e9, maxC = -1e9;
  for (int k = 0; k < kKeypointCount; ++k) {
    const Eigen::Vector3d p = placed.keypointsEnu.col(k);
    const Eigen::Vector2d r = p.head<2>() - footprint.centreEnu.head<2>();
    minA = std::min(minA, r.dot(f));
    maxA = std::max(maxA, r.dot(f));
    minC = std::min(minC, r.dot(n));
    maxC = std::max(maxC, r.dot(n));
    EXPECT_NEAR(p.z() - *groundZ(p.head<2>()), g.keypoints_m(2, k), 1e-12) << k;
  }
  EXPECT_NEAR(maxA - minA, footprint.length_m, 1e-9);
  EXPECT_NEAR(maxC - minC, footprint.width_m, 1e-9);
  EXPECT_NEAR(maxA + minA, 0.0, 1e-9);
  EXPECT_NEAR(maxC + minC, 0.0, 1e-9);
  // Front bumper corners are ahead (driving direction kept).
  const Eigen::Vector2d frontLeft = placed.keypointsEnu.col(4).head<2>();
  EXPECT_NEAR((frontLeft - footprint.centreEnu.head<2>()).dot(f), maxA, 1e-9);
  // Rear axle on the ground, behind the centre by the scaled ASM offset.
  EXPECT_NEAR(placed.rearAxleEnu.z(), *groundZ(placed.rearAxleEnu.head<2>()), 1e-12);
  EXPECT_NEAR((placed.rearAxleEnu.head<2>() - footprint.centreEnu.head<2>()).dot(f),
              g.rearAxle_m.x() * 1.05, 1e-9);

  // A vehicle without keypoints gets the rear axle from the length rule.
  const VehicleGeometry large = vehicleGeometry(model, VehicleType::Large, ShapeParams{});
  footprint.length_m = 12.0;
  footprint.width_m = 2.5;
  PlacedVehicle bus;
  ASSERT_TRUE(placeOnGround(large, footprint, groundZ, &bus));
  EXPECT_FALSE(bus.hasKeypoints);
  EXPECT_NEAR((bus.rearAxleEnu.head<2>() - footprint.centreEnu.head<2>()).dot(f),
              -kRearAxleBehindCentrePerLength * 12.0, 1e-9);

  // Ground missing under any point, or a bad footprint: refused.
  const auto noGround = [](const Eigen::Vector2d& xy) -> std::optional<double> {
    if (xy.x() > 12.0) {
      return std::nullopt;
    }
    return 0.0;
  };
  footprint.length_m = 4.6;
  footprint.width_m = 1.9;
  EXPECT_FALSE(placeOnGround(g, footprint, noGround, &placed));
  EXPECT_FALSE(placed.hasKeypoints);
  footprint.length_m = 0.0;
  EXPECT_FALSE(placeOnGround(g, footprint, groundZ, &placed));
}

TEST(VehicleGeometry, GeometryAndPlacementDoNotAllocate) {
  const ActiveShapeModel model = loadDefault();
  GroundFootprint footprint{{1.0, 2.0, 0.0}, 0.4, 4.5, 1.8};
  const auto groundZ = [](const Eigen::Vector2d&) -> std::optional<double> { return 0.0; };
  test::AllocationCounter counter;
  double sum = 0.0;
  for (int i = 0; i < 100; ++i) {
    const VehicleGeometry g =
        vehicleGeometry(model, static_cast<VehicleType>(i % kVehicleTypeCount), ShapeParams{});
    PlacedVehicle placed;
    if (placeOnGround(g, footprint, groundZ, &placed)) {
      sum += placed.rearAxleEnu.x();
    }
  }
  counter.stop();
  EXPECT_NE(sum, 0.0);
  EXPECT_EQ(counter.count(), 0U);
}

}  // namespace
}  // namespace vp::shape
