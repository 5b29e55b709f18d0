// config/pose_section: `pose:` into the pose buffer's own options (telemetry::PoseBufferConfig),
// `pose.limits:` into its sample checks (telemetry::PoseLimits). The file gives seconds, the
// buffer keeps nanoseconds.
#include <cstddef>
#include <cstdint>
#include <string>

#include "config/sections.hpp"
#include "rig_config/section_reader.hpp"

namespace vp::config::detail {
namespace {

// A pose further than 10 s from the frame is useless for a moving drone.
const Range kPoseMaxAgeRangeS = Range{0.0, 10.0, true};
const Range kPoseCapacityRange = Range::closed(2.0, 100000.0);
// Limits: wide enough for any place and any airframe, narrow enough to catch a unit mistake
// (feet for metres, radians for degrees) in the limit itself.
const Range kHeightLimitRange_m = Range::closed(-1000.0, 100000.0);
const Range kNormToleranceRange = Range{0.0, 0.5, true};
const Range kTiltLimitRange_deg = Range{0.0, 180.0, true};
const Range kGimbalLimitRange_deg = Range::closed(-360.0, 360.0);
const Range kSpeedLimitRange_mps = Range{0.0, 1000.0, true};
const Range kRateLimitRange_degps = Range{0.0, 100000.0, true};
const Range kJumpToleranceRange_m = Range::closed(0.0, 10000.0);
const Range kJumpToleranceRange_deg = Range::closed(0.0, 360.0);
const Range kWindowRange_s = Range::closed(0.0, 60.0);

// min_<key> < max_<key>, or an error naming both keys.
void expectOrdered(MapReader& section, const char* minKey, double min, const char* maxKey,
                   double max) {
  if (!(min < max)) {
    section.fail(maxKey, "must be greater than " + std::string(minKey) + " (" + formatNumber(min) +
                             "), got " + formatNumber(max));
  }
}

telemetry::PoseLimits readLimits(MapReader section) {
  const telemetry::PoseLimits d;
  telemetry::PoseLimits l;
  l.minHeight_m = section.number("min_height_m", kHeightLimitRange_m, d.minHeight_m);
  l.maxHeight_m = section.number("max_height_m", kHeightLimitRange_m, d.maxHeight_m);
  expectOrdered(section, "min_height_m", l.minHeight_m, "max_height_m", l.maxHeight_m);
  l.quaternionNormTolerance =
      section.number("quaternion_norm_tolerance", kNormToleranceRange, d.quaternionNormTolerance);
  l.maxTilt_deg = section.number("max_tilt_deg", kTiltLimitRange_deg, d.maxTilt_deg);
  l.minGimbalRoll_deg =
      section.number("min_gimbal_roll_deg", kGimbalLimitRange_deg, d.minGimbalRoll_deg);
  l.maxGimbalRoll_deg =
      section.number("max_gimbal_roll_deg", kGimbalLimitRange_deg, d.maxGimbalRoll_deg);
  expectOrdered(section, "min_gimbal_roll_deg", l.minGimbalRoll_deg, "max_gimbal_roll_deg",
                l.maxGimbalRoll_deg);
  l.minGimbalPitch_deg =
      section.number("min_gimbal_pitch_deg", kGimbalLimitRange_deg, d.minGimbalPitch_deg);
  l.maxGimbalPitch_deg =
      section.number("max_gimbal_pitch_deg", kGimbalLimitRange_deg, d.maxGimbalPitch_deg);
  expectOrdered(section, "min_gimbal_pitch_deg", l.minGimbalPitch_deg, "max_gimbal_pitch_deg",
                l.maxGimbalPitch_deg);
  l.minGimbalYaw_deg =
      section.number("min_gimbal_yaw_deg", kGimbalLimitRange_deg, d.minGimbalYaw_deg);
  l.maxGimbalYaw_deg =
      section.number("max_gimbal_yaw_deg", kGimbalLimitRange_deg, d.maxGimbalYaw_deg);
  expectOrdered(section, "min_gimbal_yaw_deg", l.minGimbalYaw_deg, "max_gimbal_yaw_deg",
                l.maxGimbalYaw_deg);
  l.maxHorizontalSpeed_mps =
      section.number("max_horizontal_speed_mps", kSpeedLimitRange_mps, d.maxHorizontalSpeed_mps);
  l.maxVerticalSpeed_mps =
      section.number("max_vertical_speed_mps", kSpeedLimitRange_mps, d.maxVerticalSpeed_mps);
  l.maxAngularRate_degps =
      section.number("max_angular_rate_degps", kRateLimitRange_degps, d.maxAngularRate_degps);
  l.jumpTolerance_m = section.number("jump_tolerance_m", kJumpToleranceRange_m, d.jumpTolerance_m);
  l.jumpTolerance_deg =
      section.number("jump_tolerance_deg", kJumpToleranceRange_deg, d.jumpTolerance_deg);
  // Converted only when given: the default stays the module's own nanoseconds.
  if (section.has("consistency_window_s")) {
    l.consistencyWindow_ns = static_cast<std::int64_t>(
        section.number("consistency_window_s", kWindowRange_s, kRequired) * 1e9);
  }
  section.warnUnknownKeys();
  return l;
}

}  // namespace

telemetry::PoseBufferConfig readPose(MapReader section) {
  const telemetry::PoseBufferConfig d;
  telemetry::PoseBufferConfig p;
  // Converted only when given: the default stays the buffer's own nanoseconds.
  if (section.has("max_age_s")) {
    p.maxAge_ns =
        static_cast<std::int64_t>(section.number("max_age_s", kPoseMaxAgeRangeS, kRequired) * 1e9);
  }
  p.capacity = static_cast<std::size_t>(
      section.integer("buffer_capacity", kPoseCapacityRange, static_cast<int>(d.capacity)));
  p.limits = readLimits(section.section("limits"));
  section.warnUnknownKeys();
  return p;
}

}  // namespace vp::config::detail
