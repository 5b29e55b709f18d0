// Tests of the simulator's pickup trucks (--pickup-share): a closed mesh inside the pickup's
// ranges whose open bed lies behind the cab (the front/back cue seen from above), drawn
// only in place of SUVs, and every other car the one the seed gives without the option.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <utility>

#include <Eigen/Geometry>

#include "car_generator.hpp"
#include "default_asm.hpp"
#include "shape/vehicle_model.hpp"
#include "twin_cars.hpp"
#include "vehicles.hpp"

namespace {

using vp::shape::PickupMesh;
using vp::shape::SurfacePart;
using vp::shape::Triangle;

Eigen::Vector3d normalOf(const PickupMesh& m, const Triangle& t) {
  const Eigen::Vector3d& a = m.vertices[t.v[0]];
  return (m.vertices[t.v[1]] - a).cross(m.vertices[t.v[2]] - a).normalized();
}

TEST(Pickup, ClosedMeshWithTheOpenBedBehindTheCab) {
  std::mt19937_64 rng(21);
  const vp::shape::PickupSpec& spec = vp::shape::kPickupSpec;
  for (int i = 0; i < 40; ++i) {
    const PickupMesh m = vp::shape::generatePickup(rng);
    EXPECT_TRUE(spec.length_m.contains(m.length_m));
    EXPECT_TRUE(spec.width_m.contains(m.width_m));
    EXPECT_TRUE(spec.height_m.contains(m.height_m));
    std::map<std::pair<int, int>, int> directed;
    double maxZ = 0.0;
    double minX = 1e9;
    double maxX = -1e9;
    for (const Eigen::Vector3d& v : m.vertices) {
      maxZ = std::max(maxZ, v.z());
      minX = std::min(minX, v.x());
      maxX = std::max(maxX, v.x());
    }
    EXPECT_NEAR(maxZ, m.height_m, 1e-9);
    EXPECT_NEAR(maxX - minX, m.length_m, 1e-9);
    double bedArea = 0.0;
    int windscreen = 0;
    for (const Triangle& t : m.triangles) {
      for (int j = 0; j < 3; ++j) {
        ++directed[{t.v[static_cast<std::size_t>(j)], t.v[static_cast<std::size_t>((j + 1) % 3)]}];
      }
      const Eigen::Vector3d n = normalOf(m, t);
      const Eigen::Vector3d centre =
          (m.vertices[t.v[0]] + m.vertices[t.v[1]] + m.vertices[t.v[2]]) / 3.0;
      if (n.z() > 0.99 && std::abs(centre.z() - m.bedFloorZ_m) < 1e-9) {
        // The bed floor: behind the cab, below the rim.
        EXPECT_LT(centre.x(), m.bedFrontX_m);
        EXPECT_TRUE(t.part == SurfacePart::Underbody || t.part == SurfacePart::Paint);
        const Eigen::Vector3d& a = m.vertices[t.v[0]];
        bedArea += 0.5 * (m.vertices[t.v[1]] - a).cross(m.vertices[t.v[2]] - a).norm();
      }
      if (t.part == SurfacePart::Windscreen) {
        ++windscreen;
        EXPECT_GT(centre.x(), m.bedFrontX_m);  // the glass is ahead of the bed
        EXPECT_GT(n.x(), 0.2);                 // and faces forward
      }
    }
    for (const auto& [edge, count] : directed) {
      ASSERT_EQ(count, 1);
      ASSERT_EQ(directed.count({edge.second, edge.first}), 1u);
    }
    EXPECT_GT(windscreen, 0);
    // A bed floor of at least a metre behind the cab, most of the width (walls over it counted).
    EXPECT_GT(bedArea, 1.0 * 0.9 * m.width_m);
    EXPECT_LT(m.bedFrontX_m, 0.0);
    EXPECT_GT(m.bedFrontX_m, -0.5 * m.length_m + 1.0);
    EXPECT_LT(m.bedTopZ_m, m.height_m - 0.4);  // below the cab roof: open, not a box
    EXPECT_LT(m.bedFloorZ_m, m.bedTopZ_m - 0.4);
    EXPECT_GT(m.bedFloorZ_m, 0.5);
    EXPECT_GT(vp::shape::meshVolume(m.vertices, m.triangles), 0.3 * m.length_m * m.width_m * 1.0);
    ASSERT_EQ(m.wheelCentres.size(), 4u);
    for (const Eigen::Vector3d& w : m.wheelCentres) {
      EXPECT_LT(std::abs(w.x()), 0.5 * m.length_m - m.wheelRadius_m);
      EXPECT_DOUBLE_EQ(w.z(), m.wheelRadius_m);
    }
  }
}

TEST(Pickup, OnlySuvsBecomePickupsAndTheStreamIsUntouched) {
  const vp::shape::ActiveShapeModel asmModel = vp::sim::test::loadDefaultAsm();
  const vp::sim::VehicleFactory plain(asmModel);
  const vp::sim::VehicleFactory pickups(asmModel, 0.0, 0.0, 1.0);
  int suv = 0;
  vp::sim::test::forEachTwinCar(
      plain, pickups, 11, 150, [&](auto type, const auto& a, const auto& b) {
        EXPECT_EQ(b.type, type);
        if (type != vp::shape::VehicleType::Suv) {
          EXPECT_TRUE(a.dimensions_m.isApprox(b.dimensions_m));
          EXPECT_TRUE(b.hasKeypoints);
          return;
        }
        ++suv;
        EXPECT_FALSE(b.hasKeypoints) << "a pickup has no ASM keypoints";
        EXPECT_EQ(b.gamma.count, 0);
        EXPECT_GE(b.dimensions_m.x(), vp::shape::kPickupSpec.length_m.min);
        EXPECT_GT(b.wheelbase_m, 2.5);
        EXPECT_LT(b.rearAxleXM, 0.0);
      });
  EXPECT_GT(suv, 10);
}

TEST(Pickup, AShareOfTheSuvs) {
  const vp::shape::ActiveShapeModel asmModel = vp::sim::test::loadDefaultAsm();
  const vp::sim::VehicleFactory third(asmModel, 0.0, 0.0, 0.3);
  vp::sim::Rng rng(5);
  int pickups = 0;
  constexpr int kCars = 400;
  for (int i = 0; i < kCars; ++i) {
    pickups += third.makeCar(rng, vp::shape::VehicleType::Suv)->hasKeypoints ? 0 : 1;
  }
  EXPECT_GT(pickups, kCars * 2 / 10);
  EXPECT_LT(pickups, kCars * 4 / 10);
}

}  // namespace
