// Range and consistency checks of pose samples (telemetry/pose_check.hpp), through the pose
// buffer that every telemetry source pushes into.
#include "telemetry/pose_check.hpp"

#include <array>
#include <cmath>
#include <numbers>
#include <string>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "telemetry/pose_buffer.hpp"

namespace vp::telemetry {
namespace {

constexpr std::int64_t kMs = 1'000'000;  // ns per ms

PoseSample level(std::int64_t t, double height_m = 300.0) {
  PoseSample s;
  s.timestamp_ns = t;
  s.position = {43.0731, -89.4012, height_m};
  s.bodyToNed = Eigen::Quaterniond(geodesy::rotationFromEuler({2.0, -3.0, 40.0}));
  s.gimbal.angles = {0.0, -90.0, 0.0};
  return s;
}

PoseBuffer makeBuffer() {
  PoseBuffer buffer;
  std::string why;
  EXPECT_TRUE(buffer.init(PoseBufferConfig{}, &why)) << why;
  return buffer;
}

std::string reason(const PoseCheck& check) {
  std::array<char, 256> text{};
  formatRejection(text, check);
  return text.data();
}

// A gimbal pitch of 999 deg used to be taken as 999 - 1080 = -81 deg: the frame was lifted
// metres off with status ok. Now it is refused, counted, named, and the frames around it are
// interpolated between the good samples on either side.
TEST(PoseCheck, GimbalAngleOutsideItsLimitsIsRefusedAndTheNeighboursAreUsed) {
  PoseBuffer buffer = makeBuffer();
  ASSERT_EQ(buffer.push(level(0)), PushResult::Accepted);
  PoseSample bad = level(100 * kMs);
  bad.gimbal.angles.pitch_deg = 999.0;
  EXPECT_EQ(buffer.push(bad), PushResult::OutOfLimits);
  EXPECT_EQ(buffer.counters().outOfLimits, 1U);
  EXPECT_EQ(buffer.counters().rejected(), 1U);
  EXPECT_STREQ(buffer.lastRejection().field, "gimbal_pitch_deg");
  EXPECT_EQ(reason(buffer.lastRejection()), "gimbal_pitch_deg 999 outside [-120, 30]");
  // Until a good sample follows, the telemetry is broken: after the newest good one, Invalid.
  EXPECT_EQ(buffer.poseAt(100 * kMs).status, PoseStatus::Invalid);
  ASSERT_EQ(buffer.push(level(200 * kMs)), PushResult::Accepted);
  const PoseEstimate e = buffer.poseAt(100 * kMs);
  ASSERT_EQ(e.status, PoseStatus::Ok);
  EXPECT_NEAR(e.pose.gimbal.angles.pitch_deg, -90.0, 1e-12);

  // Each gimbal angle and each side of its interval.
  for (const auto& [roll, pitch, yaw] : {std::array{-181.0, -90.0, 0.0},
                                         {181.0, -90.0, 0.0},
                                         {0.0, -121.0, 0.0},
                                         {0.0, 31.0, 0.0},
                                         {0.0, -90.0, -361.0},
                                         {0.0, -90.0, 361.0}}) {
    PoseSample s = level(300 * kMs);
    s.gimbal.angles = {roll, pitch, yaw};
    EXPECT_EQ(checkSample(s, PoseLimits{}).result, PushResult::OutOfLimits)
        << roll << " " << pitch << " " << yaw;
  }
  // Yaw written as a heading 0..360 is fine.
  PoseSample heading = level(300 * kMs);
  heading.gimbal.angles.yaw_deg = 350.0;
  EXPECT_TRUE(checkSample(heading, PoseLimits{}).ok());
}

TEST(PoseCheck, HeightQuaternionNormAndTiltOutsideTheLimitsAreRefused) {
  const PoseLimits limits;
  EXPECT_TRUE(checkSample(level(0, -499.0), limits).ok());
  EXPECT_TRUE(checkSample(level(0, 8999.0), limits).ok());
  const PoseCheck low = checkSample(level(0, -600.0), limits);
  EXPECT_EQ(low.result, PushResult::OutOfLimits);
  EXPECT_EQ(reason(low), "height_m -600 outside [-500, 9000]");
  // Feet written as metres (32 000 ft) is well above any drone.
  EXPECT_EQ(checkSample(level(0, 9754.0), limits).result, PushResult::OutOfLimits);

  PoseSample scaled = level(0);
  scaled.bodyToNed.coeffs() *= 1.05;  // 5 % off: wrong units or a broken sender
  const PoseCheck norm = checkSample(scaled, limits);
  EXPECT_EQ(norm.result, PushResult::OutOfLimits);
  EXPECT_STREQ(norm.field, "attitude quaternion norm");
  scaled.bodyToNed = level(0).bodyToNed;
  scaled.bodyToNed.coeffs() *= 1.005;  // rounding of a float32 sender: fine
  EXPECT_TRUE(checkSample(scaled, limits).ok());

  PoseSample inverted = level(0);
  inverted.bodyToNed = Eigen::Quaterniond(geodesy::rotationFromEuler({170.0, 0.0, 0.0}));
  const PoseCheck tilt = checkSample(inverted, limits);
  EXPECT_EQ(tilt.result, PushResult::OutOfLimits);
  EXPECT_STREQ(tilt.field, "tilt_deg");
  EXPECT_NEAR(tilt.value, 170.0, 1e-9);
  PoseSample banked = level(0);
  banked.bodyToNed = Eigen::Quaterniond(geodesy::rotationFromEuler({60.0, 20.0, -150.0}));
  EXPECT_TRUE(checkSample(banked, limits).ok());

  // The existing rules keep their own results.
  PoseSample south = level(0);
  south.position.latitude_deg = -90.5;
  EXPECT_EQ(checkSample(south, limits).result, PushResult::OutOfRange);
  PoseSample nan = level(0);
  nan.gimbal.angles.yaw_deg = std::nan("");
  EXPECT_EQ(checkSample(nan, limits).result, PushResult::NotFinite);
}

// A duplicated timestamp with another height used to be dropped silently as "out of order";
// it is a contradiction (one of the two is wrong), refused as such, and breaks the telemetry
// until a good sample comes. An exact repeat (a resend) is harmless.
TEST(PoseCheck, SameTimestampIsARepeatOrAContradiction) {
  PoseBuffer buffer = makeBuffer();
  ASSERT_EQ(buffer.push(level(0)), PushResult::Accepted);
  ASSERT_EQ(buffer.push(level(100 * kMs)), PushResult::Accepted);

  EXPECT_EQ(buffer.push(level(100 * kMs)), PushResult::Duplicate);
  EXPECT_EQ(buffer.counters().duplicates, 1U);
  EXPECT_EQ(buffer.poseAt(150 * kMs).status, PoseStatus::Ok);  // a repeat breaks nothing

  EXPECT_EQ(buffer.push(level(100 * kMs, 305.5)), PushResult::Inconsistent);
  EXPECT_EQ(buffer.counters().inconsistent, 1U);
  EXPECT_EQ(reason(buffer.lastRejection()),
            "timestamp 100000000 ns repeated with other values: height differs by (m) 5.5");
  EXPECT_EQ(buffer.poseAt(150 * kMs).status, PoseStatus::Invalid);
  EXPECT_NEAR(buffer.poseAt(100 * kMs).pose.position.height_m, 300.0, 1e-12);  // first one kept

  PoseSample turned = level(100 * kMs);
  turned.gimbal.angles.pitch_deg = -80.0;
  EXPECT_EQ(buffer.push(turned), PushResult::Inconsistent);
  EXPECT_NE(reason(buffer.lastRejection()).find("gimbal differs by (deg) 10"), std::string::npos)
      << reason(buffer.lastRejection());

  EXPECT_EQ(buffer.push(level(50 * kMs)), PushResult::OutOfOrder);
  EXPECT_EQ(buffer.counters().outOfOrder, 1U);
  EXPECT_EQ(buffer.counters().rejected(), 4U);
  EXPECT_EQ(buffer.size(), 2U);
}

TEST(PoseCheck, JumpsFasterThanTheLimitsAreRefusedUntilTheWindowHasPassed) {
  PoseBuffer buffer = makeBuffer();
  ASSERT_EQ(buffer.push(level(0)), PushResult::Accepted);
  // 1 km east in 100 ms: 10 km/s.
  PoseSample teleported = level(100 * kMs);
  teleported.position.longitude_deg +=
      1000.0 / (111'195.0 * std::cos(43.0731 * std::numbers::pi / 180.0));
  EXPECT_EQ(buffer.push(teleported), PushResult::Inconsistent);
  EXPECT_STREQ(buffer.lastRejection().field, "horizontal jump (m)");
  EXPECT_NEAR(buffer.lastRejection().value, 1000.0, 5.0);
  EXPECT_NEAR(buffer.lastRejection().high, 100.0 * 0.1 + 10.0, 1e-9);
  // Vertical: 20 m in 100 ms.
  EXPECT_EQ(buffer.push(level(150 * kMs, 320.0)), PushResult::Inconsistent);
  EXPECT_STREQ(buffer.lastRejection().field, "vertical jump (m)");
  // Attitude: 90 deg of yaw in 50 ms.
  PoseSample spun = level(50 * kMs);
  spun.bodyToNed = Eigen::Quaterniond(geodesy::rotationFromEuler({2.0, -3.0, 130.0}));
  EXPECT_EQ(buffer.push(spun), PushResult::Inconsistent);
  EXPECT_STREQ(buffer.lastRejection().field, "attitude jump (deg)");
  // Gimbal: from nadir to the horizon in 20 ms.
  PoseSample flicked = level(20 * kMs);
  flicked.gimbal.angles.pitch_deg = 0.0;
  EXPECT_EQ(buffer.push(flicked), PushResult::Inconsistent);
  EXPECT_STREQ(buffer.lastRejection().field, "gimbal jump (deg)");
  EXPECT_EQ(buffer.counters().inconsistent, 4U);

  // Normal flight at 20 Hz passes: 15 m/s, 3 m/s climb, 90 deg/s turn, gimbal 30 deg/s.
  PoseBuffer smooth = makeBuffer();
  for (int i = 0; i < 40; ++i) {
    PoseSample s = level(i * 50 * kMs, 300.0 + 0.15 * i);
    s.position.latitude_deg += 0.75 * i / 111'195.0;
    s.bodyToNed = Eigen::Quaterniond(geodesy::rotationFromEuler({0.0, 0.0, 4.5 * i}));
    s.gimbal.angles.pitch_deg = -90.0 + 1.5 * i;
    ASSERT_EQ(smooth.push(s), PushResult::Accepted) << i << ": " << reason(smooth.lastRejection());
  }

  // A real jump (an estimator reset) is accepted once the window has passed since the newest
  // good sample: the telemetry is never locked out for good.
  teleported.timestamp_ns = 1001 * kMs;
  EXPECT_EQ(buffer.push(teleported), PushResult::Accepted);
  // A jump the producer announces (a looped recording starting over) is not judged.
  PoseSample back = level(1050 * kMs);
  buffer.markDiscontinuity();
  EXPECT_EQ(buffer.push(back), PushResult::Accepted);
  teleported.timestamp_ns = 1100 * kMs;
  EXPECT_EQ(buffer.push(teleported), PushResult::Inconsistent);  // judged again after one
}

TEST(PoseCheck, LimitsAreValidatedAtInit) {
  PoseBuffer buffer;
  std::string why;
  PoseBufferConfig config;
  config.limits.minGimbalPitch_deg = 40.0;  // above the maximum
  EXPECT_FALSE(buffer.init(config, &why));
  EXPECT_NE(why.find("gimbal_pitch_deg"), std::string::npos) << why;
  config = {};
  config.limits.maxHorizontalSpeed_mps = 0.0;
  EXPECT_FALSE(buffer.init(config, &why));
  EXPECT_NE(why.find("maxHorizontalSpeed_mps"), std::string::npos) << why;
  config = {};
  config.limits.consistencyWindow_ns = -1;
  EXPECT_FALSE(buffer.init(config, &why));
  EXPECT_NE(why.find("consistencyWindow_ns"), std::string::npos) << why;
  EXPECT_TRUE(buffer.init(PoseBufferConfig{}, &why)) << why;
}

TEST(PoseCheck, RefusingSamplesDoesNotAllocate) {
  PoseBuffer buffer = makeBuffer();
  test::AllocationCounter counter;
  std::array<char, 256> text{};
  int length = 0;
  for (int i = 0; i < 300; ++i) {
    PoseSample s = level(i * 20 * kMs);
    if (i % 3 == 1) {
      s.gimbal.angles.pitch_deg = 999.0;
    } else if (i % 3 == 2) {
      s.timestamp_ns -= 20 * kMs;
      s.position.height_m += 40.0;
    }
    if (buffer.push(s) != PushResult::Accepted) {
      length += formatRejection(text, buffer.lastRejection());
    }
  }
  counter.stop();
  EXPECT_EQ(buffer.counters().outOfLimits, 100U);
  EXPECT_EQ(buffer.counters().inconsistent, 100U);
  EXPECT_GT(length, 0);
  EXPECT_EQ(counter.count(), 0U);
}

}  // namespace
}  // namespace vp::telemetry
