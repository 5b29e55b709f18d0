// Parts of one bus or truck become one box: both most likely Large, on one axis, overlapping
// or touching; cars, gaps, side-by-side vehicles, crossing axes and over-long results stay apart;
// a kept bus part takes the extent of the longer duplicate the last suppression drops.
#include "detection/large_vehicle_merge.hpp"

#include <array>
#include <cmath>

#include <gtest/gtest.h>

#include "geometry/rotated_box.hpp"

namespace vp::detection {
namespace {

Detection vehicle(double cx, double cy, double length, double width, double angle, float score,
                  shape::VehicleType type = shape::VehicleType::Large) {
  Detection d;
  d.box = {cx, cy, length, width, angle};
  d.score = score;
  d.typeProbabilities.fill(0.02F);
  d.typeProbabilities[static_cast<std::size_t>(type)] = 0.88F;
  return d;
}

// The case from a simulated straight road: a 13.8 m box truck (385 px at 3.6 cm/px) boxed as
// two overlapping parts of 272 and 297 px, their headings opposite.
TEST(LargeVehicleMerge, TwoOverlappingPartsBecomeTheWholeTruck) {
  std::array<Detection, 3> d{
      vehicle(1228.4, 1144.3, 272.0, 84.9, 1.553, 0.43F),
      vehicle(1146.4, 970.2, 141.0, 61.6, 1.540, 0.82F, shape::VehicleType::Compact),
      vehicle(1230.5, 1320.6, 296.8, 78.8, 4.705, 0.42F)};
  const std::size_t kept = mergeLargeVehicleParts(d, 0.036, LargeVehicleMergeOptions{});
  ASSERT_EQ(kept, 2U);
  const geometry::RotatedBox& b = d[0].box;
  // Extent along the first part's axis: from its rear (-136 px) to the second's far end.
  const double c = std::cos(1.553);
  const double s = std::sin(1.553);
  const double along = c * (1230.5 - 1228.4) + s * (1320.6 - 1144.3);
  const double low = -136.0;
  const double high = along + 0.5 * 296.8;
  EXPECT_NEAR(b.length, high - low, 1e-9);
  EXPECT_NEAR(b.cx, 1228.4 + c * 0.5 * (low + high), 1e-9);
  EXPECT_NEAR(b.cy, 1144.3 + s * 0.5 * (low + high), 1e-9);
  EXPECT_DOUBLE_EQ(b.width, 84.9);
  EXPECT_DOUBLE_EQ(b.angle, 1.553);  // the better part's heading (it comes first)
  EXPECT_FLOAT_EQ(d[0].score, 0.43F);
  EXPECT_DOUBLE_EQ(d[1].box.cx, 1146.4);  // the car moved up, untouched
}

TEST(LargeVehicleMerge, ThreePartsInAChainBecomeOne) {
  std::array<Detection, 3> d{vehicle(100.0, 50.0, 100.0, 40.0, 0.0, 0.9F),
                             vehicle(190.0, 52.0, 100.0, 40.0, 0.02, 0.8F),
                             vehicle(280.0, 50.0, 100.0, 40.0, geometry::kPi, 0.7F)};
  ASSERT_EQ(mergeLargeVehicleParts(d, 0.0, LargeVehicleMergeOptions{}), 1U);
  EXPECT_NEAR(d[0].box.length, 280.0, 0.1);
  EXPECT_NEAR(d[0].box.cx, 190.0, 0.1);
}

TEST(LargeVehicleMerge, WhatIsNotOneVehicleStaysApart) {
  const LargeVehicleMergeOptions options;
  auto count = [&](Detection a, Detection b, double gsd_m = 0.05) {
    std::array<Detection, 2> d{a, b};
    return mergeLargeVehicleParts(d, gsd_m, options);
  };
  const Detection bus = vehicle(100.0, 50.0, 240.0, 50.0, 0.0, 0.9F);
  // Two buses queued with a gap of 10 px.
  EXPECT_EQ(count(bus, vehicle(350.0, 50.0, 240.0, 50.0, 0.0, 0.8F)), 2U);
  // Side by side, overlapping along the axis (one lane apart).
  EXPECT_EQ(count(bus, vehicle(150.0, 110.0, 240.0, 50.0, 0.0, 0.8F)), 2U);
  // Crossing axes.
  EXPECT_EQ(count(bus, vehicle(200.0, 50.0, 240.0, 50.0, 0.5, 0.8F)), 2U);
  // A car overlapping the bus's end.
  EXPECT_EQ(count(bus, vehicle(250.0, 50.0, 90.0, 40.0, 0.0, 0.8F, shape::VehicleType::Van)), 2U);
  // The merged box would be 610 px = 30.5 m at 5 cm/px (the limit is 25 m) ...
  EXPECT_EQ(count(bus, vehicle(400.0, 50.0, 380.0, 50.0, 0.0, 0.8F)), 2U);
  // ... which merges without a GSD.
  EXPECT_EQ(count(bus, vehicle(400.0, 50.0, 380.0, 50.0, 0.0, 0.8F), 0.0), 1U);
  // Switched off.
  LargeVehicleMergeOptions off;
  off.enabled = false;
  std::array<Detection, 2> d{bus, vehicle(200.0, 50.0, 240.0, 50.0, 0.0, 0.8F)};
  EXPECT_EQ(mergeLargeVehicleParts(d, 0.05, off), 2U);
  EXPECT_DOUBLE_EQ(d[0].box.length, 240.0);
}

// The case of a real bus (CATS Madison 7_13, 4.7 cm/px): the first stage boxed its front part
// (170 px, the better score, typed Large) and nearly all of it (207 px); the suppression of
// duplicates keeps the part, which now takes the longer box's extent along its own axis.
TEST(LargeVehicleMerge, AKeptBusPartAbsorbsItsLongerDuplicate) {
  Detection part = vehicle(453.8, 265.2, 170.0, 54.2, 4.7147, 0.60F);
  const Detection longer =
      vehicle(453.2, 325.5, 206.8, 50.3, 1.4464, 0.56F, shape::VehicleType::Sedan);
  ASSERT_TRUE(absorbLongerDuplicate(part, longer, 0.047, LargeVehicleMergeOptions{}));
  // Along the part's axis (pointing up the image): the part spans 265.2 -/+ 85 px in v, the
  // longer box 325.5 -/+ 103.4: the union is about v 180 .. 429 (the label: 179 .. 434).
  EXPECT_NEAR(part.box.length, 248.6, 0.5);
  EXPECT_NEAR(part.box.cy, 304.5, 0.5);
  EXPECT_DOUBLE_EQ(part.box.angle, 4.7147);  // heading and type stay the part's
  EXPECT_DOUBLE_EQ(part.box.width, 54.2);
  EXPECT_FLOAT_EQ(part.score, 0.60F);

  // Only a Large-typed kept box, only a longer duplicate, within the merge's limits.
  Detection car = vehicle(453.8, 265.2, 170.0, 54.2, 4.7147, 0.60F, shape::VehicleType::Van);
  EXPECT_FALSE(absorbLongerDuplicate(car, longer, 0.047, LargeVehicleMergeOptions{}));
  EXPECT_DOUBLE_EQ(car.box.length, 170.0);
  Detection whole = vehicle(453.2, 325.5, 206.8, 50.3, 1.4464, 0.60F);
  const Detection shorter = vehicle(453.8, 265.2, 170.0, 54.2, 4.7147, 0.56F);
  EXPECT_FALSE(absorbLongerDuplicate(whole, shorter, 0.047, LargeVehicleMergeOptions{}));
  EXPECT_DOUBLE_EQ(whole.box.length, 206.8);
  Detection tooLong = vehicle(453.8, 265.2, 170.0, 54.2, 4.7147, 0.60F);
  EXPECT_FALSE(absorbLongerDuplicate(tooLong, longer, 0.2, LargeVehicleMergeOptions{}));  // 50 m
  LargeVehicleMergeOptions off;
  off.enabled = false;
  Detection kept = vehicle(453.8, 265.2, 170.0, 54.2, 4.7147, 0.60F);
  EXPECT_FALSE(absorbLongerDuplicate(kept, longer, 0.047, off));
  EXPECT_DOUBLE_EQ(kept.box.length, 170.0);
}

}  // namespace
}  // namespace vp::detection
