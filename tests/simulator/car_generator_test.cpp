// Tests of simulator/car_generator: documented ranges, determinism, valid closed meshes for every
// drawn car, types that differ the way real ones do, and the bus/truck meshes.
#include "car_generator.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <random>
#include <utility>

namespace vp::shape {
namespace {

constexpr int kCarsPerType = 400;

struct Stats {
  double sum = 0.0;
  double sumSq = 0.0;
  int n = 0;
  void add(double v) {
    sum += v;
    sumSq += v * v;
    ++n;
  }
  double mean() const { return sum / n; }
  double sd() const { return std::sqrt(std::max(sumSq / n - mean() * mean(), 0.0)); }
};

TEST(CarGenerator, DimensionsStayInsideTheDocumentedRanges) {
  std::mt19937_64 rng(11);
  for (int t = 0; t < kCarTypeCount; ++t) {
    const auto type = static_cast<VehicleType>(t);
    const CarTypeSpec& spec = carTypeSpec(type);
    ASSERT_EQ(spec.type, type);
    Stats length;
    for (int i = 0; i < kCarsPerType; ++i) {
      const GeneratedCar car = generateCar(type, rng);
      const CarDimensions& d = car.dimensions;
      EXPECT_TRUE(spec.length_m.range.contains(d.length_m)) << toString(type) << d.length_m;
      EXPECT_TRUE(spec.width_m.range.contains(d.width_m)) << toString(type) << d.width_m;
      EXPECT_TRUE(spec.height_m.range.contains(d.height_m)) << toString(type) << d.height_m;
      EXPECT_TRUE(spec.wheelbase_m.range.contains(d.wheelbase_m)) << toString(type);
      EXPECT_TRUE(spec.wheelRadius_m.contains(d.wheelRadius_m)) << toString(type);
      EXPECT_TRUE(spec.sillHeight_m.contains(d.sillHeight_m)) << toString(type);
      EXPECT_TRUE(spec.windscreenRake_deg.contains(d.windscreenRake_deg)) << toString(type);
      EXPECT_TRUE(spec.rearWindowAngle_deg.contains(d.rearWindowAngle_deg)) << toString(type);
      EXPECT_NEAR(d.frontOverhang_m + d.wheelbase_m + d.rearOverhang_m, d.length_m, 1e-12);
      // The keypoints span exactly the sampled length, width and height.
      const Eigen::Vector3d size = boundingBoxSize(car.keypoints);
      EXPECT_NEAR(size.x(), d.length_m, 1e-9);
      EXPECT_NEAR(size.y(), d.width_m, 1e-9);
      EXPECT_NEAR(size.z(), d.height_m, 1e-9);
      length.add(d.length_m);
    }
    // A spread, not one car: the sampled sd is near the documented one (truncation shrinks it).
    EXPECT_GT(length.sd(), 0.6 * spec.length_m.sd) << toString(type);
    EXPECT_LT(length.sd(), 1.1 * spec.length_m.sd) << toString(type);
    EXPECT_NEAR(length.mean(), spec.length_m.mean, 0.4 * spec.length_m.sd) << toString(type);
  }
}

TEST(CarGenerator, EveryCarHasAValidOutwardMesh) {
  std::mt19937_64 rng(12);
  for (int t = 0; t < kCarTypeCount; ++t) {
    const auto type = static_cast<VehicleType>(t);
    for (int i = 0; i < kCarsPerType; ++i) {
      const GeneratedCar car = generateCar(type, rng);
      ASSERT_TRUE(carProfileValid(car.keypoints)) << toString(type) << " car " << i;
      const CarDimensions& d = car.dimensions;
      const double volume = meshVolume(car.keypoints);
      const double box = d.length_m * d.width_m * d.height_m;
      EXPECT_GT(volume, 0.4 * box) << toString(type);
      EXPECT_LT(volume, 0.9 * box) << toString(type);
      // Wheels stand on the road, inside the body's width, under their arches.
      for (int w = 0; w < kWheelCount; ++w) {
        const int k = wheelCentreKeypoints()[static_cast<std::size_t>(w)];
        EXPECT_NEAR(car.keypoints(2, k), d.wheelRadius_m, 1e-12);
        EXPECT_LE(std::abs(car.keypoints(1, k)), 0.5 * d.width_m + 1e-12);
      }
    }
  }
}

TEST(CarGenerator, IsDeterministicForASeed) {
  for (int t = 0; t < kCarTypeCount; ++t) {
    std::mt19937_64 a(99);
    std::mt19937_64 b(99);
    std::mt19937_64 c(100);
    const auto type = static_cast<VehicleType>(t);
    const KeypointModel first = generateCar(type, a).keypoints;
    EXPECT_EQ(first, generateCar(type, b).keypoints);
    EXPECT_NE(first, generateCar(type, c).keypoints);
  }
}

TEST(CarGenerator, TypesDifferLikeRealCars) {
  std::mt19937_64 rng(13);
  std::map<VehicleType, Stats> length;
  std::map<VehicleType, Stats> height;
  std::map<VehicleType, Stats> bonnet;  // horizontal length from the front to the windscreen
  std::map<VehicleType, Stats> tail;    // roof rear ahead of the rear end
  for (int t = 0; t < kCarTypeCount; ++t) {
    const auto type = static_cast<VehicleType>(t);
    for (int i = 0; i < 200; ++i) {
      const GeneratedCar car = generateCar(type, rng);
      length[type].add(car.dimensions.length_m);
      height[type].add(car.dimensions.height_m);
      bonnet[type].add(car.keypoints(0, *keypointIndex("front_bumper_corner_left")) -
                       car.keypoints(0, *keypointIndex("windscreen_base_left")));
      tail[type].add(car.keypoints(0, *keypointIndex("roof_rear_left")) -
                     car.keypoints(0, *keypointIndex("rear_bumper_corner_left")));
    }
  }
  using V = VehicleType;
  for (V other : {V::Estate, V::Compact, V::Sedan, V::Suv, V::Van}) {
    EXPECT_LT(height[V::Sports].mean() + 0.1, height[other].mean()) << toString(other);
    EXPECT_GT(bonnet[V::Sports].mean(), bonnet[other].mean()) << toString(other);
  }
  for (V car : {V::Estate, V::Compact, V::Sedan, V::Sports}) {
    EXPECT_GT(height[V::Suv].mean(), height[car].mean() + 0.1) << toString(car);
    EXPECT_GT(height[V::Van].mean(), height[car].mean() + 0.1) << toString(car);
  }
  EXPECT_GT(height[V::Van].mean(), height[V::Suv].mean());
  for (V other : {V::Estate, V::Sedan, V::Suv, V::Van}) {
    EXPECT_LT(length[V::Compact].mean(), length[other].mean()) << toString(other);
  }
  // Tailgates (estate, SUV, van) keep the roof to the rear; a notchback sedan does not.
  for (V hatch : {V::Estate, V::Suv, V::Van}) {
    EXPECT_LT(tail[hatch].mean() + 0.4, tail[V::Sedan].mean()) << toString(hatch);
  }
}

TEST(CarGenerator, LengthAndWheelbaseAreCorrelated) {
  std::mt19937_64 rng(14);
  for (int t = 0; t < kCarTypeCount; ++t) {
    Stats l;
    Stats wb;
    double sumLw = 0.0;
    for (int i = 0; i < kCarsPerType; ++i) {
      const CarDimensions d = generateCar(static_cast<VehicleType>(t), rng).dimensions;
      l.add(d.length_m);
      wb.add(d.wheelbase_m);
      sumLw += d.length_m * d.wheelbase_m;
    }
    const double correlation = (sumLw / kCarsPerType - l.mean() * wb.mean()) / (l.sd() * wb.sd());
    EXPECT_GT(correlation, 0.6) << toString(static_cast<VehicleType>(t));
  }
}

TEST(LargeVehicles, ClosedOutwardMeshesInsideTheRanges) {
  std::mt19937_64 rng(15);
  for (int k = 0; k < kLargeVehicleKindCount; ++k) {
    const auto kind = static_cast<LargeVehicleKind>(k);
    const LargeVehicleSpec& spec = largeVehicleSpec(kind);
    for (int i = 0; i < 20; ++i) {
      const LargeVehicleMesh m = generateLargeVehicle(kind, rng);
      EXPECT_TRUE(spec.length_m.contains(m.length_m)) << toString(kind);
      EXPECT_TRUE(spec.height_m.contains(m.height_m)) << toString(kind);
      EXPECT_GE(m.length_m, 7.0);
      EXPECT_LE(m.length_m, 18.75);
      // Closed, consistently wound, outward.
      std::map<std::pair<int, int>, int> directed;
      Eigen::Vector3d lo = m.vertices.front();
      Eigen::Vector3d hi = lo;
      for (const Eigen::Vector3d& v : m.vertices) {
        lo = lo.cwiseMin(v);
        hi = hi.cwiseMax(v);
      }
      for (const Triangle& t : m.triangles) {
        for (int j = 0; j < 3; ++j) {
          ASSERT_LT(t.v[static_cast<std::size_t>(j)], m.vertices.size());
          ++directed[{t.v[static_cast<std::size_t>(j)],
                      t.v[static_cast<std::size_t>((j + 1) % 3)]}];
        }
      }
      for (const auto& [edge, count] : directed) {
        ASSERT_EQ(count, 1) << toString(kind);
        ASSERT_EQ(directed.count({edge.second, edge.first}), 1u) << toString(kind);
      }
      EXPECT_GT(meshVolume(m.vertices, m.triangles), 0.3 * m.length_m * m.width_m * m.height_m);
      EXPECT_NEAR(hi.x() - lo.x(), m.length_m, 1e-9) << toString(kind);
      EXPECT_NEAR(hi.z(), m.height_m, 1e-9) << toString(kind);
      EXPECT_LE(hi.y() - lo.y(), m.width_m + 1e-9) << toString(kind);
      // At least two axles, wheels under the body.
      EXPECT_GE(m.wheelCentres.size(), 4u);
      EXPECT_EQ(m.wheelCentres.size() % 2, 0u);
      for (const Eigen::Vector3d& w : m.wheelCentres) {
        EXPECT_LT(std::abs(w.x()), 0.5 * m.length_m - m.wheelRadius_m);
        EXPECT_DOUBLE_EQ(w.z(), m.wheelRadius_m);
      }
    }
  }
}

}  // namespace
}  // namespace vp::shape
