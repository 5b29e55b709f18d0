// ROS 2 telemetry samples -> PoseSample, without DDS: REP-103 (FLU/ENU) and PX4 (FRD/NED)
// attitudes of known Euler angles give our q_nb; bad samples are rejected with their reason;
// conversion allocates nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "alloc_counter.hpp"
#include "platform/dds/telemetry_conversion.hpp"
#include "telemetry_cases.hpp"

namespace vp::platform::dds {
namespace {

constexpr double kDoubleAngleTol_rad = 1e-9;
// float32 quaternion components carry ~6e-8 relative error: ~1e-7 rad of rotation.
constexpr double kFloatAngleTol_rad = 1e-6;
constexpr double kDegToRad = M_PI / 180.0;

Eigen::Vector3d inNed(const Eigen::Quaterniond& bodyToNed, const Eigen::Vector3d& bodyFrd) {
  return bodyToNed * bodyFrd;
}
Eigen::Vector3d inNed(const PoseSample& pose, const Eigen::Vector3d& bodyFrd) {
  return inNed(pose.bodyToNed, bodyFrd);
}

char gFrameId[] = "base_link";

TEST(TelemetryConversion, Rep103FrameChangeByHandForSimpleAttitudes) {
  // Level, nose north: FLU x (forward) is ENU y (north): a +90 degree turn about ENU z.
  const double h = std::sqrt(0.5);
  EXPECT_LT(nedFrdFromEnuFlu(Eigen::Quaterniond(h, 0, 0, h))
                .angularDistance(Eigen::Quaterniond::Identity()),
            kDoubleAngleTol_rad);
  // Level, nose east: FLU coincides with ENU; in NED that is a yaw of +90 degrees.
  const Eigen::Quaterniond east = nedFrdFromEnuFlu(Eigen::Quaterniond::Identity());
  EXPECT_LT(east.angularDistance(Eigen::Quaterniond(h, 0, 0, h)), kDoubleAngleTol_rad);
  EXPECT_TRUE(inNed(east, Eigen::Vector3d::UnitX())
                  .isApprox(Eigen::Vector3d(0, 1, 0), 1e-12));  // nose -> east
  // The two directions are inverse.
  for (const test::AttitudeCase& c : test::kAttitudeCases) {
    const Eigen::Quaterniond q = test::expectedBodyToNed(c);
    EXPECT_LT(nedFrdFromEnuFlu(enuFluFromNedFrd(q)).angularDistance(q), kDoubleAngleTol_rad);
  }
}

TEST(TelemetryConversion, ArduPilotGeoPoseGivesOurAttitudeAndPosition) {
  for (std::size_t i = 0; i < test::kAttitudeCases.size(); ++i) {
    const test::AttitudeCase& c = test::kAttitudeCases[i];
    SCOPED_TRACE(i);
    PoseSample pose;
    ASSERT_EQ(fromGeoPose(test::makeGeoPose(i, gFrameId), 0.0, pose), TelemetryRejection::None);
    EXPECT_EQ(pose.source, PoseSource::ArduPilotGeoPose);
    EXPECT_TRUE(pose.hasAttitude);
    EXPECT_TRUE(pose.hasPosition);
    EXPECT_LT(test::angleBetween(pose.bodyToNed, test::expectedBodyToNed(c)), kDoubleAngleTol_rad);
    EXPECT_GE(pose.bodyToNed.w(), 0.0);
    EXPECT_EQ(pose.position.latitude_deg, c.latitude_deg);
    EXPECT_EQ(pose.position.longitude_deg, c.longitude_deg);
    EXPECT_EQ(pose.position.height_m, c.height_m);
    EXPECT_EQ(pose.timeBase, TelemetryTimeBase::Utc);
    EXPECT_EQ(pose.time_ns, (test::kStampBase_s + static_cast<std::int64_t>(i)) * 1'000'000'000 +
                                test::kStampNanosec);
    EXPECT_TRUE(std::isnan(pose.horizontalStd_m));
  }
}

TEST(TelemetryConversion, KnownAttitudesPointTheBodyAxesWhereTheyShould) {
  // Banked 30 degrees right, nose north: the right wing (FRD y) points east and down.
  PoseSample bank;
  ASSERT_EQ(fromGeoPose(test::makeGeoPose(2, gFrameId), 0.0, bank), TelemetryRejection::None);
  const double r = 30.0 * kDegToRad;
  EXPECT_TRUE(inNed(bank, Eigen::Vector3d::UnitY())
                  .isApprox(Eigen::Vector3d(0, std::cos(r), std::sin(r)), 1e-12));
  EXPECT_TRUE(inNed(bank, Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d(1, 0, 0), 1e-12));
  // Nose 20 degrees up, heading east: the nose points east and up (negative down).
  PoseSample climb;
  ASSERT_EQ(fromGeoPose(test::makeGeoPose(3, gFrameId), 0.0, climb), TelemetryRejection::None);
  const double p = 20.0 * kDegToRad;
  EXPECT_TRUE(inNed(climb, Eigen::Vector3d::UnitX())
                  .isApprox(Eigen::Vector3d(0, std::cos(p), -std::sin(p)), 1e-12));
}

TEST(TelemetryConversion, ArduPilotAltitudeOffsetAndBootTimeStamps) {
  auto message = test::makeGeoPose(0, gFrameId);
  message.header.stamp.sec = 1234;  // no GNSS time yet: seconds since boot
  PoseSample pose;
  ASSERT_EQ(fromGeoPose(message, -33.5, pose), TelemetryRejection::None);
  EXPECT_EQ(pose.position.height_m, test::kAttitudeCases[0].height_m - 33.5);
  EXPECT_EQ(pose.timeBase, TelemetryTimeBase::AutopilotBoot);
  EXPECT_EQ(pose.time_ns, 1234 * 1'000'000'000LL + test::kStampNanosec);
}

TEST(TelemetryConversion, Px4AttitudeAndGlobalPosition) {
  for (std::size_t i = 0; i < test::kAttitudeCases.size(); ++i) {
    const test::AttitudeCase& c = test::kAttitudeCases[i];
    SCOPED_TRACE(i);
    PoseSample attitude;
    ASSERT_EQ(fromPx4Attitude(test::makePx4Attitude(i), attitude), TelemetryRejection::None);
    EXPECT_EQ(attitude.source, PoseSource::Px4Attitude);
    EXPECT_TRUE(attitude.hasAttitude);
    EXPECT_FALSE(attitude.hasPosition);
    EXPECT_LT(test::angleBetween(attitude.bodyToNed, test::expectedBodyToNed(c)),
              kFloatAngleTol_rad);
    EXPECT_NEAR(attitude.bodyToNed.norm(), 1.0, 1e-15);
    EXPECT_EQ(attitude.timeBase, TelemetryTimeBase::AutopilotBoot);
    EXPECT_EQ(attitude.time_ns, static_cast<std::int64_t>(test::kPx4SampleBase_us * (i + 1) + 5) *
                                    1000);  // timestamp_sample, not timestamp

    PoseSample position;
    ASSERT_EQ(fromPx4GlobalPosition(test::makePx4GlobalPosition(i), position),
              TelemetryRejection::None);
    EXPECT_EQ(position.source, PoseSource::Px4GlobalPosition);
    EXPECT_TRUE(position.hasPosition);
    EXPECT_FALSE(position.hasAttitude);
    EXPECT_EQ(position.position.latitude_deg, c.latitude_deg);
    EXPECT_EQ(position.position.longitude_deg, c.longitude_deg);
    EXPECT_EQ(position.position.height_m, static_cast<double>(static_cast<float>(c.height_m)));
    EXPECT_EQ(position.horizontalStd_m, 0.8F);
    EXPECT_EQ(position.verticalStd_m, 1.5F);
  }
  // A publisher leaving timestamp_sample at 0: timestamp is used.
  auto message = test::makePx4Attitude(0);
  message.timestamp_sample = 0;
  PoseSample pose;
  ASSERT_EQ(fromPx4Attitude(message, pose), TelemetryRejection::None);
  EXPECT_EQ(pose.time_ns, static_cast<std::int64_t>(message.timestamp) * 1000);
}

TEST(TelemetryConversion, BadSamplesAreRejectedWithTheirReason) {
  PoseSample pose;
  auto attitude = test::makePx4Attitude(1);
  attitude.q[0] = attitude.q[1] = attitude.q[2] = attitude.q[3] = 0.0F;  // PX4 before init
  EXPECT_EQ(fromPx4Attitude(attitude, pose), TelemetryRejection::NotUnitQuaternion);
  attitude.q[0] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(fromPx4Attitude(attitude, pose), TelemetryRejection::NonFinite);
  // Slightly off unit length (float rounding): renormalised, not rejected.
  attitude = test::makePx4Attitude(1);
  for (float& component : attitude.q) {
    component *= 1.004F;
  }
  ASSERT_EQ(fromPx4Attitude(attitude, pose), TelemetryRejection::None);
  EXPECT_NEAR(pose.bodyToNed.norm(), 1.0, 1e-15);

  auto position = test::makePx4GlobalPosition(0);
  position.lat = 91.0;
  EXPECT_EQ(fromPx4GlobalPosition(position, pose), TelemetryRejection::PositionOutOfRange);
  position = test::makePx4GlobalPosition(0);
  position.alt_ellipsoid = std::numeric_limits<float>::infinity();
  EXPECT_EQ(fromPx4GlobalPosition(position, pose), TelemetryRejection::NonFinite);

  auto geo = test::makeGeoPose(0, gFrameId);
  geo.pose.position.longitude = -180.5;
  EXPECT_EQ(fromGeoPose(geo, 0.0, pose), TelemetryRejection::PositionOutOfRange);
  geo = test::makeGeoPose(0, gFrameId);
  geo.pose.orientation.w = 2.0;
  EXPECT_EQ(fromGeoPose(geo, 0.0, pose), TelemetryRejection::NotUnitQuaternion);
  EXPECT_STREQ(toString(TelemetryRejection::NotUnitQuaternion), "quaternion not of unit length");
}

TEST(TelemetryConversion, ConvertingAllocatesNothing) {
  const auto geo = test::makeGeoPose(4, gFrameId);
  const auto attitude = test::makePx4Attitude(4);
  const auto position = test::makePx4GlobalPosition(4);
  PoseSample pose;
  int ok = 0;
  test::AllocationCounter counter;
  for (int k = 0; k < 1000; ++k) {
    ok += fromGeoPose(geo, 0.0, pose) == TelemetryRejection::None;
    ok += fromPx4Attitude(attitude, pose) == TelemetryRejection::None;
    ok += fromPx4GlobalPosition(position, pose) == TelemetryRejection::None;
  }
  counter.stop();
  EXPECT_EQ(ok, 3000);
  EXPECT_EQ(counter.count(), 0U);
}

}  // namespace
}  // namespace vp::platform::dds
