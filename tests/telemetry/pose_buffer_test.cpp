#include "telemetry/pose_buffer.hpp"

#include <cmath>
#include <cstdio>
#include <limits>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"

namespace vp::telemetry {
namespace {

constexpr std::int64_t kMs = 1'000'000;  // ns per ms

PoseSample sampleAt(std::int64_t t, double lat, double lon, double h, double yawDeg) {
  PoseSample s;
  s.timestampNs = t;
  s.position = {lat, lon, h};
  s.bodyToNed = Eigen::Quaterniond(geodesy::rotationFromEuler({0.0, 0.0, yawDeg}));
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
  config.maxAgeNs = 0;
  EXPECT_FALSE(buffer.init(config, &why));
  EXPECT_NE(why.find("maxAgeNs"), std::string::npos) << why;
  EXPECT_EQ(buffer.push(sampleAt(0, 43.0, -89.0, 300.0, 0.0)), PushResult::NotInitialised);
}

TEST(PoseBuffer, EmptyBufferHasNoPose) {
  const PoseBuffer buffer = makeBuffer();
  const PoseEstimate e = buffer.poseAt(123);
  EXPECT_EQ(e.status, PoseStatus::NoPose);
  EXPECT_EQ(e.ageNs, -1);
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
  double maxErrorDeg = 0.0;
  double maxErrorM = 0.0;
  for (std::int64_t t = 0; t <= 1150 * kMs; t += 7 * kMs) {
    const PoseEstimate e = buffer.poseAt(t);
    ASSERT_EQ(e.status, PoseStatus::Ok) << t;
    const geodesy::GeodeticPoint want = truth(t);
    maxErrorDeg = std::max({maxErrorDeg, std::abs(e.pose.position.latitudeDeg - want.latitudeDeg),
                            std::abs(e.pose.position.longitudeDeg - want.longitudeDeg)});
    maxErrorM = std::max(maxErrorM, std::abs(e.pose.position.heightM - want.heightM));
    EXPECT_EQ(e.pose.timestampNs, t);
    EXPECT_LE(e.ageNs, 50 * kMs + 150 * kMs);
  }
  std::printf("linear motion: max lat/lon error %.3g deg, height %.3g m\n", maxErrorDeg, maxErrorM);
  EXPECT_LT(maxErrorDeg, 1e-11);
  EXPECT_LT(maxErrorM, 1e-9);
}

// The attitude between two samples is the slerp: a constant-rate yaw gives the linear angle.
TEST(PoseBuffer, AttitudeIsSlerpedAndGimbalYawWrapsAround) {
  PoseBuffer buffer = makeBuffer();
  PoseSample a = sampleAt(0, 43.0, -89.0, 300.0, 170.0);
  PoseSample b = sampleAt(100 * kMs, 43.0, -89.0, 300.0, -170.0);  // +20 deg across 180
  a.gimbal.angles.yawDeg = 175.0;
  b.gimbal.angles.yawDeg = -165.0;  // +20 deg across the wrap
  b.bodyToNed.coeffs() *= -1.0;     // the same rotation with the other sign: still short way
  ASSERT_EQ(buffer.push(a), PushResult::Accepted);
  ASSERT_EQ(buffer.push(b), PushResult::Accepted);
  for (int i = 0; i <= 10; ++i) {
    const std::int64_t t = i * 10 * kMs;
    const PoseEstimate e = buffer.poseAt(t);
    ASSERT_EQ(e.status, PoseStatus::Ok);
    const double wantYaw = 170.0 + 2.0 * i;  // through 180
    const geodesy::EulerAnglesDeg got =
        geodesy::eulerFromRotation(e.pose.bodyToNed.toRotationMatrix());
    EXPECT_NEAR(std::remainder(got.yawDeg - wantYaw, 360.0), 0.0, 1e-9) << i;
    EXPECT_NEAR(got.rollDeg, 0.0, 1e-9);
    EXPECT_NEAR(got.pitchDeg, 0.0, 1e-9);
    const double wantGimbalYaw = std::remainder(175.0 + 2.0 * i, 360.0);
    EXPECT_NEAR(e.pose.gimbal.angles.yawDeg, wantGimbalYaw, 1e-9) << i;
    EXPECT_GT(e.pose.gimbal.angles.yawDeg, -180.0);
    EXPECT_LE(e.pose.gimbal.angles.yawDeg, 180.0);
    EXPECT_NEAR(e.pose.gimbal.angles.pitchDeg, -80.0, 1e-12);
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
  EXPECT_EQ(gap.ageNs, 500 * kMs);
  // After the newest: extrapolated up to the max age, Stale beyond.
  EXPECT_EQ(buffer.poseAt(2300 * kMs).status, PoseStatus::Ok);
  const PoseEstimate late = buffer.poseAt(2301 * kMs);
  EXPECT_EQ(late.status, PoseStatus::Stale);
  EXPECT_EQ(late.ageNs, 201 * kMs);
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
  badGimbal.gimbal.angles.pitchDeg = nan;
  EXPECT_EQ(buffer.push(badGimbal), PushResult::NotFinite);
  PoseSample zero = sampleAt(170 * kMs, 43.0, -89.0, 300.0, 0.0);
  zero.bodyToNed.coeffs().setZero();
  EXPECT_EQ(buffer.push(zero), PushResult::ZeroQuaternion);
  EXPECT_EQ(buffer.push(sampleAt(180 * kMs, 91.0, -89.0, 300.0, 0.0)), PushResult::OutOfRange);
  EXPECT_EQ(buffer.push(sampleAt(100 * kMs, 43.0, -89.0, 300.0, 0.0)), PushResult::OutOfOrder);
  EXPECT_EQ(buffer.push(sampleAt(50 * kMs, 43.0, -89.0, 300.0, 0.0)), PushResult::OutOfOrder);

  const PoseBufferCounters& c = buffer.counters();
  EXPECT_EQ(c.accepted, 2U);
  EXPECT_EQ(c.notFinite, 3U);
  EXPECT_EQ(c.zeroQuaternion, 1U);
  EXPECT_EQ(c.outOfRange, 1U);
  EXPECT_EQ(c.outOfOrder, 2U);
  EXPECT_EQ(c.rejected(), 7U);
  EXPECT_EQ(buffer.size(), 2U);

  // Between the good samples nothing changed; after the newest, the link is broken: Invalid.
  const PoseEstimate between = buffer.poseAt(50 * kMs);
  EXPECT_EQ(between.status, PoseStatus::Ok);
  EXPECT_NEAR(between.pose.position.heightM, 305.0, 1e-9);
  const PoseEstimate after = buffer.poseAt(150 * kMs);
  EXPECT_EQ(after.status, PoseStatus::Invalid);
  EXPECT_TRUE(after.pose.position.latitudeDeg == 43.0);  // the last good sample, never the NaN
  // A good sample heals it.
  ASSERT_EQ(buffer.push(sampleAt(200 * kMs, 43.0, -89.0, 320.0, 0.0)), PushResult::Accepted);
  const PoseEstimate healed = buffer.poseAt(150 * kMs);
  EXPECT_EQ(healed.status, PoseStatus::Ok);
  EXPECT_NEAR(healed.pose.position.heightM, 315.0, 1e-9);
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
  EXPECT_NEAR(e.pose.position.heightM, 307.5, 1e-9);
}

TEST(PoseBuffer, LongitudeInterpolatesAcrossTheAntimeridian) {
  const geodesy::GeodeticPoint a{-17.0, 179.9, 100.0};
  const geodesy::GeodeticPoint b{-17.0, -179.9, 100.0};
  const geodesy::GeodeticPoint mid = interpolatePosition(a, b, 0.75);
  EXPECT_NEAR(mid.longitudeDeg, -179.95, 1e-9);
}

TEST(PoseBuffer, PushAndQueryDoNotAllocate) {
  PoseBuffer buffer = makeBuffer(64);
  test::AllocationCounter counter;
  double sum = 0.0;
  for (int i = 0; i < 500; ++i) {
    buffer.push(sampleAt(i * 20 * kMs, 43.0, -89.0, 300.0, i * 0.5));
    sum += buffer.poseAt(i * 20 * kMs - 7 * kMs).pose.position.heightM;
  }
  counter.stop();
  EXPECT_GT(sum, 0.0);
  EXPECT_EQ(counter.count(), 0U);
}

}  // namespace
}  // namespace vp::telemetry
