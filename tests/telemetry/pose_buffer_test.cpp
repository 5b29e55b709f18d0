#include "telemetry/pose_buffer.hpp"

#include <cmath>
#include <cstdio>
#include <limits>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"

namespace vp::telemetry {
namespace {

constexpr std::int64_t kMs = 1'000'000;  // ns per ms

PoseSample sampleAt(std::int64_t t, double lat, double lon, double h, double yaw_deg) {
  PoseSample s;
  s.timestamp_ns = t;
  s.position = {lat, lon, h};
  s.bodyToNed = Eigen::Quaterniond(geodesy::rotationFromEuler({0.0, 0.0, yaw_deg}));
  s.gimbal.angles = {0.0, -80.0, 0.0};
  return s;
}

PoseBuffer makeBuffer(std::size_t capacity = 16) {
  PoseBuffer buffer;
  PoseBufferConfig config;
  config.capacity = capacity;
  std::string why;
  EXPECT_TRUE(buffer.init(config, &why)) << why;
  return buffer;
}

TEST(PoseBuffer, InitRejectsBadConfigurationNamingTheField) {
  PoseBuffer buffer;
  std::string why;
  PoseBufferConfig config;
  config.capacity = 1;
  EXPECT_FALSE(buffer.init(config, &why));
  EXPECT_NE(why.find("capacity"), std::string::npos) << why;
  config = {};
  config.maxAge_ns = 0;
  EXPECT_FALSE(buffer.init(config, &why));
  EXPECT_NE(why.find("maxAge_ns"), std::string::npos) << why;
  EXPECT_EQ(buffer.push(sampleAt(0, 43.0, -89.0, 300.0, 0.0)), PushResult::NotInitialised);
}

TEST(PoseBuffer, EmptyBufferHasNoPose) {
  const PoseBuffer buffer = makeBuffer();
  const PoseEstimate e = buffer.poseAt(123);
  EXPECT_EQ(e.status, PoseStatus::NoPose);
  EXPECT_EQ(e.age_ns, -1);
}

// Linear motion in latitude, longitude and height is reproduced exactly between samples
// (and by extrapolation within the max age), at any query time.
TEST(PoseBuffer, InterpolationIsExactOnLinearMotion) {
  PoseBuffer buffer = makeBuffer();
  const auto truth = [](std::int64_t t) {
    const double s = static_cast<double>(t) / 1e9;  // seconds
    return geodesy::GeodeticPoint{43.0731 + 1e-5 * s, -89.4012 - 2e-5 * s, 300.0 + 1.5 * s};
  };
  for (std::int64_t t = 0; t <= 1000 * kMs; t += 100 * kMs) {
    PoseSample s = sampleAt(t, 0, 0, 0, 10.0);
    s.position = truth(t);
    ASSERT_EQ(buffer.push(s), PushResult::Accepted);
  }
  double maxError_deg = 0.0;
  double maxError_m = 0.0;
  for (std::int64_t t = 0; t <= 1150 * kMs; t += 7 * kMs) {
    const PoseEstimate e = buffer.poseAt(t);
    ASSERT_EQ(e.status, PoseStatus::Ok) << t;
    const geodesy::GeodeticPoint want = truth(t);
    maxError_deg =
        std::max({maxError_deg, std::abs(e.pose.position.latitude_deg - want.latitude_deg),
                  std::abs(e.pose.position.longitude_deg - want.longitude_deg)});
    maxError_m = std::max(maxError_m, std::abs(e.pose.position.height_m - want.height_m));
    EXPECT_EQ(e.pose.timestamp_ns, t);
    EXPECT_LE(e.age_ns, 50 * kMs + 150 * kMs);
  }
  std::printf("linear motion: max lat/lon error %.3g deg, height %.3g m\n", maxError_deg,
              maxError_m);
  EXPECT_LT(maxError_deg, 1e-11);
  EXPECT_LT(maxError_m, 1e-9);
}

// The attitude between two samples is the slerp: a constant-rate yaw gives the linear angle.
TEST(PoseBuffer, AttitudeIsSlerpedAndGimbalYawWrapsAround) {
  PoseBuffer buffer = makeBuffer();
  PoseSample a = sampleAt(0, 43.0, -89.0, 300.0, 170.0);
  PoseSample b = sampleAt(100 * kMs, 43.0, -89.0, 300.0, -170.0);  // +20 deg across 180
  a.gimbal.angles.yaw_deg = 175.0;
  b.gimbal.angles.yaw_deg = -165.0;  // +20 deg across the wrap
  b.bodyToNed.coeffs() *= -1.0;      // the same rotation with the other sign: still short way
  ASSERT_EQ(buffer.push(a), PushResult::Accepted);
  ASSERT_EQ(buffer.push(b), PushResult::Accepted);
  for (int i = 0; i <= 10; ++i) {
    const std::int64_t t = i * 10 * kMs;
    const PoseEstimate e = buffer.poseAt(t);
    ASSERT_EQ(e.status, PoseStatus::Ok);
    const double wantYaw = 170.0 + 2.0 * i;  // through 180
    const geodesy::EulerAnglesDeg got =
        geodesy::eulerFromRotation(e.pose.bodyToNed.toRotationMatrix());
    EXPECT_NEAR(std::remainder(got.yaw_deg - wantYaw, 360.0), 0.0, 1e-9) << i;
    EXPECT_NEAR(got.roll_deg, 0.0, 1e-9);
    EXPECT_NEAR(got.pitch_deg, 0.0, 1e-9);
    const double wantGimbalYaw = std::remainder(175.0 + 2.0 * i, 360.0);
    EXPECT_NEAR(e.pose.gimbal.angles.yaw_deg, wantGimbalYaw, 1e-9) << i;
    EXPECT_GT(e.pose.gimbal.angles.yaw_deg, -180.0);
    EXPECT_LE(e.pose.gimbal.angles.yaw_deg, 180.0);
    EXPECT_NEAR(e.pose.gimbal.angles.pitch_deg, -80.0, 1e-12);
  }
  // A general rotation pair: the midpoint is the geodesic midpoint (equal angles to both ends).
  PoseBuffer general = makeBuffer();
  PoseSample c = sampleAt(0, 43.0, -89.0, 300.0, 0.0);
  PoseSample d = sampleAt(200 * kMs, 43.0, -89.0, 300.0, 0.0);
  c.bodyToNed = Eigen::Quaterniond(geodesy::rotationFromEuler({5.0, -3.0, 40.0}));
  d.bodyToNed = Eigen::Quaterniond(geodesy::rotationFromEuler({-4.0, 6.0, 75.0}));
  ASSERT_EQ(general.push(c), PushResult::Accepted);
  ASSERT_EQ(general.push(d), PushResult::Accepted);
  const PoseEstimate mid = general.poseAt(50 * kMs);  // s = 0.25
  ASSERT_EQ(mid.status, PoseStatus::Ok);
  const double toC = mid.pose.bodyToNed.angularDistance(c.bodyToNed);
  const double toD = mid.pose.bodyToNed.angularDistance(d.bodyToNed);
  EXPECT_NEAR(toC, 0.25 * c.bodyToNed.angularDistance(d.bodyToNed), 1e-12);
  EXPECT_NEAR(toD, 0.75 * c.bodyToNed.angularDistance(d.bodyToNed), 1e-12);
  EXPECT_NEAR(mid.pose.bodyToNed.norm(), 1.0, 1e-12);
}

TEST(PoseBuffer, StaleAndMissingPoses) {
  PoseBuffer buffer = makeBuffer();
  ASSERT_EQ(buffer.push(sampleAt(1000 * kMs, 43.0, -89.0, 300.0, 0.0)), PushResult::Accepted);
  ASSERT_EQ(buffer.push(sampleAt(1100 * kMs, 43.0, -89.0, 300.0, 0.0)), PushResult::Accepted);
  // A telemetry gap of 1 s.
  ASSERT_EQ(buffer.push(sampleAt(2100 * kMs, 43.0, -89.0, 300.0, 0.0)), PushResult::Accepted);

  // Before the first sample: held within the start tolerance, NoPose beyond it.
  EXPECT_EQ(buffer.poseAt(997 * kMs).status, PoseStatus::Ok);
  EXPECT_EQ(buffer.poseAt(990 * kMs).status, PoseStatus::NoPose);
  // Inside the gap: fine near either end, Stale in its middle.
  EXPECT_EQ(buffer.poseAt(1250 * kMs).status, PoseStatus::Ok);
  EXPECT_EQ(buffer.poseAt(1950 * kMs).status, PoseStatus::Ok);
  const PoseEstimate gap = buffer.poseAt(1600 * kMs);
  EXPECT_EQ(gap.status, PoseStatus::Stale);
  EXPECT_EQ(gap.age_ns, 500 * kMs);
  // After the newest: extrapolated up to the max age, Stale beyond.
  EXPECT_EQ(buffer.poseAt(2300 * kMs).status, PoseStatus::Ok);
  const PoseEstimate late = buffer.poseAt(2301 * kMs);
  EXPECT_EQ(late.status, PoseStatus::Stale);
  EXPECT_EQ(late.age_ns, 201 * kMs);
}

TEST(PoseBuffer, InvalidSamplesAreRejectedCountedAndNeverUsed) {
  PoseBuffer buffer = makeBuffer();
  ASSERT_EQ(buffer.push(sampleAt(0, 43.0, -89.0, 300.0, 0.0)), PushResult::Accepted);
  ASSERT_EQ(buffer.push(sampleAt(100 * kMs, 43.0, -89.0, 310.0, 0.0)), PushResult::Accepted);

  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(buffer.push(sampleAt(150 * kMs, nan, -89.0, 300.0, 0.0)), PushResult::NotFinite);
  EXPECT_EQ(buffer.push(sampleAt(160 * kMs, 43.0, -89.0, inf, 0.0)), PushResult::NotFinite);
  PoseSample badGimbal = sampleAt(165 * kMs, 43.0, -89.0, 300.0, 0.0);
  badGimbal.gimbal.angles.pitch_deg = nan;
  EXPECT_EQ(buffer.push(badGimbal), PushResult::NotFinite);
  PoseSample zero = sampleAt(170 * kMs, 43.0, -89.0, 300.0, 0.0);
  zero.bodyToNed.coeffs().setZero();
  EXPECT_EQ(buffer.push(zero), PushResult::ZeroQuaternion);
  EXPECT_EQ(buffer.push(sampleAt(180 * kMs, 91.0, -89.0, 300.0, 0.0)), PushResult::OutOfRange);
  // The newest sample's time with another height contradicts it; an earlier time is late.
  EXPECT_EQ(buffer.push(sampleAt(100 * kMs, 43.0, -89.0, 300.0, 0.0)), PushResult::Inconsistent);
  EXPECT_EQ(buffer.push(sampleAt(50 * kMs, 43.0, -89.0, 300.0, 0.0)), PushResult::OutOfOrder);

  const PoseBufferCounters& c = buffer.counters();
  EXPECT_EQ(c.accepted, 2U);
  EXPECT_EQ(c.notFinite, 3U);
  EXPECT_EQ(c.zeroQuaternion, 1U);
  EXPECT_EQ(c.outOfRange, 1U);
  EXPECT_EQ(c.inconsistent, 1U);
  EXPECT_EQ(c.outOfOrder, 1U);
  EXPECT_EQ(c.rejected(), 7U);
  EXPECT_EQ(buffer.size(), 2U);

  // Between the good samples nothing changed; after the newest, the link is broken: Invalid.
  const PoseEstimate between = buffer.poseAt(50 * kMs);
  EXPECT_EQ(between.status, PoseStatus::Ok);
  EXPECT_NEAR(between.pose.position.height_m, 305.0, 1e-9);
  const PoseEstimate after = buffer.poseAt(150 * kMs);
  EXPECT_EQ(after.status, PoseStatus::Invalid);
  EXPECT_TRUE(after.pose.position.latitude_deg == 43.0);  // the last good sample, never the NaN
  // A good sample heals it.
  ASSERT_EQ(buffer.push(sampleAt(200 * kMs, 43.0, -89.0, 320.0, 0.0)), PushResult::Accepted);
  const PoseEstimate healed = buffer.poseAt(150 * kMs);
  EXPECT_EQ(healed.status, PoseStatus::Ok);
  EXPECT_NEAR(healed.pose.position.height_m, 315.0, 1e-9);
}

TEST(PoseBuffer, RingKeepsTheNewestSamplesAndCountsOverwrites) {
  PoseBuffer buffer = makeBuffer(4);
  for (int i = 0; i < 10; ++i) {
    ASSERT_EQ(buffer.push(sampleAt(i * 100 * kMs, 43.0, -89.0, 300.0 + i, 0.0)),
              PushResult::Accepted);
  }
  EXPECT_EQ(buffer.size(), 4U);
  EXPECT_EQ(buffer.counters().overwritten, 6U);
  EXPECT_EQ(buffer.poseAt(500 * kMs).status, PoseStatus::NoPose);  // forgotten
  const PoseEstimate e = buffer.poseAt(750 * kMs);
  ASSERT_EQ(e.status, PoseStatus::Ok);
  EXPECT_NEAR(e.pose.position.height_m, 307.5, 1e-9);
}

TEST(PoseBuffer, LongitudeInterpolatesAcrossTheAntimeridian) {
  const geodesy::GeodeticPoint a{-17.0, 179.9, 100.0};
  const geodesy::GeodeticPoint b{-17.0, -179.9, 100.0};
  const geodesy::GeodeticPoint mid = interpolatePosition(a, b, 0.75);
  EXPECT_NEAR(mid.longitude_deg, -179.95, 1e-9);
}

TEST(PoseBuffer, PushAndQueryDoNotAllocate) {
  PoseBuffer buffer = makeBuffer(64);
  test::AllocationCounter counter;
  double sum = 0.0;
  for (int i = 0; i < 500; ++i) {
    buffer.push(sampleAt(i * 20 * kMs, 43.0, -89.0, 300.0, i * 0.5));
    sum += buffer.poseAt(i * 20 * kMs - 7 * kMs).pose.position.height_m;
  }
  counter.stop();
  EXPECT_GT(sum, 0.0);
  EXPECT_EQ(counter.count(), 0U);
}

}  // namespace
}  // namespace vp::telemetry
