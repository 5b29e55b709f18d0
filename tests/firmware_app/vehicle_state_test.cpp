// firmware_app/vehicle_state: a tracker state becomes the published message with the
// tracker's own uncertainty, fused score and age (docs/dds.md field table).
#include <gtest/gtest.h>

#include <cmath>

#include "geometry/rotated_box.hpp"
#include "shape/vehicle_geometry.hpp"
#include "vehicle_state.hpp"

namespace vp::app {
namespace {

constexpr std::int64_t kNsPerS = 1'000'000'000;

TEST(VehicleState, CarriesTheTrackersCovarianceScoreAndAge) {
  tracking::TrackState track;
  track.id = 42;
  track.status = tracking::TrackStatus::Confirmed;
  track.birth_ns = 5 * kNsPerS;
  track.timestamp_ns = 7 * kNsPerS + kNsPerS / 2;
  track.centreEnu = {10.0, -4.0};
  track.headingEnu_rad = 0.5 * geometry::kPi;  // north
  track.speed_mps = 8.0;
  track.speedSigma_mps = 0.5;
  track.yawRate_radps = 0.1;
  track.yawRateSigma_radps = 0.02;
  track.poseCovariance << 0.04, 0.01, 0.002, 0.01, 0.09, -0.003, 0.002, -0.003, 0.0025;
  track.score = 0.73;
  track.type = shape::VehicleType::Large;  // no ASM needed
  const geodesy::LocalFrame frame(geodesy::GeodeticPoint{43.0731, -89.4012, 260.0});
  const std::int64_t toUtc = 1'700'000'000LL * kNsPerS;

  const messages::VehicleState s = toVehicleState(track, 3, toUtc, frame, nullptr, nullptr);
  EXPECT_EQ(s.trackId, 42u);
  EXPECT_EQ(s.droneId, 3u);
  EXPECT_EQ(s.measurementTime_ns, track.timestamp_ns + toUtc);
  EXPECT_FLOAT_EQ(s.trackAge_s, 2.5F);
  // Upper triangle of (east, north, heading), row by row.
  const std::array<float, 6> expected{0.04F, 0.01F, 0.002F, 0.09F, -0.003F, 0.0025F};
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_FLOAT_EQ(s.poseCovariance[i], expected[i]) << i;
  }
  EXPECT_FLOAT_EQ(s.speedVariance_m2ps2, 0.25F);
  EXPECT_FLOAT_EQ(s.yawRateVariance_rad2ps2, 0.0004F);
  EXPECT_FLOAT_EQ(s.detectionConfidence, 0.73F);
  EXPECT_NEAR(s.headingTrueNorth_deg, 0.0, 0.01);
  EXPECT_NEAR(s.velocityEnu_mps[1], 8.0F, 1e-5F);
  EXPECT_FLOAT_EQ(s.height_m, 0.0F);  // large vehicles have no ASM height
}

// A large vehicle (no ASM shape): no keypoints, the rear axle 0.28 of its length behind the
// centre on the ground, UTM of the reference point, the tracker's size variances.
TEST(VehicleState, LargeVehicleRearAxleByTheLengthRuleAndUtmOfTheCentre) {
  tracking::TrackState track;
  track.status = tracking::TrackStatus::Confirmed;
  track.centreEnu = {20.0, 5.0};
  track.headingEnu_rad = 0.25 * geometry::kPi;
  track.length_m = 12.0;
  track.width_m = 2.5;
  track.lengthVariance_m2 = 0.09;
  track.widthVariance_m2 = 0.01;
  track.type = shape::VehicleType::Large;
  const geodesy::LocalFrame frame(geodesy::GeodeticPoint{43.0731, -89.4012, 260.0});
  const messages::VehicleState s = toVehicleState(track, 1, 0, frame, nullptr, nullptr);
  EXPECT_EQ(s.keypointCount, 0);
  const double back = shape::kRearAxleBehindCentrePerLength * 12.0;
  EXPECT_NEAR(s.rearAxleEnu_m[0], 20.0 - back * std::cos(0.25 * geometry::kPi), 1e-9);
  EXPECT_NEAR(s.rearAxleEnu_m[1], 5.0 - back * std::sin(0.25 * geometry::kPi), 1e-9);
  EXPECT_NEAR(s.rearAxleEnu_m[2], s.enu_m[2], 1e-9);  // no DTM: flat at the centre's height
  const Eigen::Vector3d axle = frame.toEnu(s.rearAxlePosition);
  EXPECT_NEAR(axle.x(), s.rearAxleEnu_m[0], 1e-6);
  EXPECT_NEAR(axle.y(), s.rearAxleEnu_m[1], 1e-6);
  const geodesy::UtmPoint utm = geodesy::toUtm(s.position);
  EXPECT_EQ(s.utmZone, 16);
  EXPECT_TRUE(s.utmNorthernHemisphere);
  EXPECT_NEAR(s.utmEasting_m, utm.easting_m, 1e-6);
  EXPECT_NEAR(s.utmNorthing_m, utm.northing_m, 1e-6);
  EXPECT_FLOAT_EQ(s.lengthVariance_m2, 0.09F);
  EXPECT_FLOAT_EQ(s.widthVariance_m2, 0.01F);
  EXPECT_EQ(messages::validate(s), messages::ValidationError::None);

  // No size yet: the rear axle at the reference point.
  track.length_m = 0.0;
  const messages::VehicleState none = toVehicleState(track, 1, 0, frame, nullptr, nullptr);
  EXPECT_EQ(none.rearAxleEnu_m, none.enu_m);
}

}  // namespace
}  // namespace vp::app
