// Pure parts of the DDS interface: validation and occupancy rasterisation.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "../platform/dds/dds_test_support.hpp"
#include "messages/occupancy.hpp"

namespace vp::messages {
namespace {

TEST(Messages, ValidateCatchesBadStates) {
  VehicleState s = test::makeState(3, 1);
  EXPECT_EQ(validate(s), ValidationError::None);
  s.speed_mps = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(validate(s), ValidationError::NotFinite);
  s = test::makeState(3, 1);
  s.headingTrueNorth_deg = 360.0;
  EXPECT_EQ(validate(s), ValidationError::HeadingOutOfRange);
  s = test::makeState(3, 1);
  s.position.latitude_deg = 91.0;
  EXPECT_EQ(validate(s), ValidationError::InvalidPosition);
  s = test::makeState(3, 1);
  s.typeProbability[2] = 1.5F;
  EXPECT_EQ(validate(s), ValidationError::ProbabilityOutOfRange);
}

TEST(Messages, ValidateCatchesBadUtmRearAxleKeypointsAndVariances) {
  VehicleState s = test::makeState(3, 1);
  ASSERT_EQ(validate(s), ValidationError::None);
  s.utmZone = 0;  // not computed
  EXPECT_EQ(validate(s), ValidationError::None);
  s.utmZone = 61;
  EXPECT_EQ(validate(s), ValidationError::UtmZoneOutOfRange);
  s = test::makeState(3, 1);
  s.utmNorthing_m = std::numeric_limits<double>::infinity();
  EXPECT_EQ(validate(s), ValidationError::NotFinite);
  s = test::makeState(3, 1);
  s.rearAxleEnu_m[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(validate(s), ValidationError::NotFinite);
  s = test::makeState(3, 1);
  s.rearAxlePosition.longitude_deg = 200.0;
  EXPECT_EQ(validate(s), ValidationError::InvalidPosition);
  s = test::makeState(3, 1);
  s.keypointsEnu_m[35][1] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(validate(s), ValidationError::NotFinite);
  s = test::makeState(3, 1);
  s.keypointCount = 0;  // a large vehicle
  EXPECT_EQ(validate(s), ValidationError::None);
  s.keypointCount = 12;
  EXPECT_EQ(validate(s), ValidationError::KeypointCountOutOfRange);
  s = test::makeState(3, 1);
  s.widthVariance_m2 = -0.01F;
  EXPECT_EQ(validate(s), ValidationError::NegativeVariance);
  s = test::makeState(3, 1);
  s.lengthVariance_m2 = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(validate(s), ValidationError::NotFinite);
  EXPECT_STREQ(toString(ValidationError::UtmZoneOutOfRange),
               "UTM zone outside 0 (not computed) .. 60");
}

TEST(Messages, ModelIdIsTruncatedAndTerminated) {
  DroneStatus status;
  status.setModelId(std::string(100, 'x'));
  EXPECT_EQ(std::string(status.modelId.data()).size(), DroneStatus::kModelIdCapacity);
}

TEST(Occupancy, MarksObservedAreaAndFootprints) {
  OccupancyGrid grid;
  grid.originEast_m = -10.0;
  grid.originNorth_m = -10.0;
  grid.resolution_m = 0.5F;
  grid.resize(40, 40);  // 20 m x 20 m
  const Eigen::Vector2d polygon[] = {{-8, -8}, {8, -8}, {8, 8}, {-8, 8}};
  VehicleState car = test::makeState(1, 0);
  car.enu_m = {0.0, 0.0, 0.0};
  car.headingEnu_rad = std::acos(-1.0) / 2.0;  // facing north: 4.6 m north-south, 1.8 m wide
  VehicleState tentative = car;
  tentative.enu_m = {5.0, 5.0, 0.0};
  tentative.status = TrackStatus::Tentative;
  const VehicleState cars[] = {car, tentative};
  rasterizeOccupancy(polygon, cars, grid);
  const auto cellAt = [&](double e, double n) {
    return grid.at(static_cast<std::uint32_t>((n + 10.0) / 0.5),
                   static_cast<std::uint32_t>((e + 10.0) / 0.5));
  };
  EXPECT_EQ(cellAt(0.1, 2.0), Occupancy::Occupied);    // inside the length
  EXPECT_EQ(cellAt(1.6, 0.1), Occupancy::Free);        // beyond the width
  EXPECT_EQ(cellAt(5.1, 5.1), Occupancy::Free);        // tentative track not drawn
  EXPECT_EQ(cellAt(9.0, 9.0), Occupancy::Unobserved);  // outside the observed polygon
  int occupied = 0;
  for (std::uint8_t c : grid.cells) {
    occupied += c == static_cast<std::uint8_t>(Occupancy::Occupied);
  }
  EXPECT_NEAR(occupied * 0.25, 4.6 * 1.8, 2.0);  // area within the cell quantisation
}

}  // namespace
}  // namespace vp::messages
