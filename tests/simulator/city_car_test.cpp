// Tests of the simulator's city cars (--city-car-share): a share of the compact cars is shortened
// to 2.5-3.6 m and narrowed, its ground truth leaves gamma unknown, and every other car is the one
// the seed gives without the option.
#include <gtest/gtest.h>

#include <string>

#include "default_asm.hpp"
#include "shape/vehicle_model.hpp"
#include "twin_cars.hpp"
#include "vehicles.hpp"

namespace {

TEST(CityCar, CompactCarsAreShortenedAndOtherCarsStayTheSame) {
  const vp::shape::ActiveShapeModel asmModel = vp::sim::test::loadDefaultAsm();
  const vp::sim::VehicleFactory plain(asmModel);
  const vp::sim::VehicleFactory city(asmModel, 0.0, 1.0);
  int compact = 0;
  vp::sim::test::forEachTwinCar(plain, city, 7, 120, [&](auto type, const auto& a, const auto& b) {
    ASSERT_EQ(a.vertices.size(), b.vertices.size());
    if (type != vp::shape::VehicleType::Compact) {
      EXPECT_TRUE(a.vertices.front().isApprox(b.vertices.front()));
      EXPECT_TRUE(a.dimensions_m.isApprox(b.dimensions_m));
      EXPECT_EQ(b.gamma.count, a.gamma.count);
      return;
    }
    ++compact;
    EXPECT_GE(a.dimensions_m.x(), 3.5);  // the ASM's compact cars start above a city car
    EXPECT_GE(b.dimensions_m.x(), vp::sim::kCityCarLength_m.min_m - 1e-9);
    EXPECT_LE(b.dimensions_m.x(), vp::sim::kCityCarLength_m.max_m + 1e-9);
    EXPECT_LE(b.dimensions_m.y(), a.dimensions_m.y() + 1e-9);
    EXPECT_GE(b.dimensions_m.y(), vp::sim::kCityCarWidthScaleMin * a.dimensions_m.y() - 1e-9);
    EXPECT_DOUBLE_EQ(b.dimensions_m.z(), a.dimensions_m.z());  // as tall as before
    EXPECT_LT(b.wheelbase_m, a.wheelbase_m);
    EXPECT_GT(b.wheelbase_m, 1.2);
    EXPECT_EQ(b.gamma.count, 0) << "a scaled car has no gamma";
    EXPECT_GT(a.gamma.count, 0);
  });
  EXPECT_GT(compact, 15);
}

TEST(CityCar, AShareOfTheCompactCars) {
  const vp::shape::ActiveShapeModel asmModel = vp::sim::test::loadDefaultAsm();
  const vp::sim::VehicleFactory half(asmModel, 0.0, 0.5);
  vp::sim::Rng rng(3);
  int compact = 0;
  int shortened = 0;
  for (int i = 0; i < 400; ++i) {
    const auto car = half.makeCar(rng, vp::shape::VehicleType::Compact);
    ++compact;
    shortened += car->gamma.count == 0 ? 1 : 0;
  }
  EXPECT_GT(shortened, compact * 4 / 10);
  EXPECT_LT(shortened, compact * 6 / 10);
}

}  // namespace
