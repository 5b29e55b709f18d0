// telemetry/pose_check: is a pose sample plausible, on its own and next to the sample before it?
//
// Contract: PoseLimits is the telemetry module's options struct for these checks (units in
// the names, defaults here, ranges in docs/telemetry.md and config/default.yaml `pose.limits`).
// checkSample() checks one sample's fields: finite, latitude/longitude in their WGS84 ranges,
// height, attitude quaternion norm and tilt, and each gimbal angle within its limits.
// checkStep() checks a sample against the newest accepted one: a later timestamp, the same
// values when the timestamp is the same (a repeat), and, while the two are at most
// consistencyWindow_ns apart, no jump faster than the limits allow (horizontal and vertical
// speed, body and gimbal rotation rate, each with a fixed tolerance for sensor noise). Beyond
// the window the step is not judged, so that a real jump (an estimator reset, a link back
// after a gap) is accepted once the window has passed instead of locking the telemetry out.
// The result names the check, the field, the value and the bound that failed, so that a log
// line can say exactly what was wrong (formatRejection()). Pure: no allocation, no throw.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "geodesy/attitude.hpp"
#include "geodesy/geodesy.hpp"

namespace vp::telemetry {

struct PoseSample {
  std::int64_t timestamp_ns = 0;      // capture clock of the frames
  geodesy::GeodeticPoint position{};  // body origin, WGS84, ellipsoidal height
  Eigen::Quaterniond bodyToNed{Eigen::Quaterniond::Identity()};  // autopilot attitude q_nb
  geodesy::GimbalState gimbal{};
};

enum class PushResult : std::uint8_t {
  Accepted,
  NotFinite,       // NaN/inf in the position, attitude or gimbal angles
  OutOfRange,      // latitude beyond +-90 deg or longitude beyond +-180 deg
  ZeroQuaternion,  // attitude norm below kMinQuaternionNorm
  OutOfLimits,     // height, quaternion norm, tilt or a gimbal angle outside PoseLimits
  OutOfOrder,      // timestamp before the newest accepted sample
  Duplicate,       // the newest accepted sample again (same timestamp, same values)
  Inconsistent,    // same timestamp with other values, or a jump faster than PoseLimits allow
  NotInitialised,  // push() before a successful init()
};
const char* toString(PushResult result);

// Attitudes are normalised at push; a quaternion shorter than this carries no rotation.
constexpr double kMinQuaternionNorm = 1e-6;

struct PoseLimits {
  // WGS84 ellipsoidal height of the drone, m: the Dead Sea shore to high mountains (the same
  // span as the configuration's origin.height_m).
  double minHeight_m = -500.0;
  double maxHeight_m = 9000.0;
  // |norm - 1| of the attitude quaternion as sent: the MAVLink and DDS links refuse beyond 1 %,
  // a recording beyond 0.1 %; more means wrong units or a wrong component order.
  double quaternionNormTolerance = 0.01;
  // Angle between the body's down axis and the local down, deg: beyond 90 the drone is upside
  // down, which no flight of this product does (a crash or a broken estimator).
  double maxTilt_deg = 90.0;
  // Gimbal Euler angles as reported (docs/conventions.md), deg. Pitch spans the same range as
  // the configuration's mount.gimbal.pitch_deg (-90 looks straight down); yaw may be written
  // 0..360 as well as +-180.
  double minGimbalRoll_deg = -180.0;
  double maxGimbalRoll_deg = 180.0;
  double minGimbalPitch_deg = -120.0;
  double maxGimbalPitch_deg = 30.0;
  double minGimbalYaw_deg = -360.0;
  double maxGimbalYaw_deg = 360.0;
  // Between two samples at most consistencyWindow_ns apart: the implied motion must stay within
  // these (plus the tolerances, which absorb GNSS and estimator noise at high sample rates).
  double maxHorizontalSpeed_mps = 100.0;
  double maxVerticalSpeed_mps = 50.0;
  double maxAngularRate_degps = 720.0;  // body attitude and gimbal head, each
  double jumpTolerance_m = 10.0;
  double jumpTolerance_deg = 10.0;
  std::int64_t consistencyWindow_ns = 1'000'000'000;  // 1 s
};

// Fails (with *why naming the field) on an empty or inverted interval or a non-positive rate.
bool validateLimits(const PoseLimits& limits, std::string* why);

// What a check found. For a failure: which field, its value and the bound it broke (for a
// jump: the implied rate and the allowed one; for a repeat: the timestamp).
struct PoseCheck {
  PushResult result = PushResult::Accepted;
  const char* field = "";  // "gimbal_pitch_deg", "height_m", "horizontal_speed_mps", ...
  double value = 0.0;
  double low = 0.0;   // the interval the value had to lie in (jumps: low = 0)
  double high = 0.0;  // (jumps: the allowed rate for that step)
  std::int64_t timestamp_ns = 0;
  bool ok() const { return result == PushResult::Accepted; }
};

PoseCheck checkSample(const PoseSample& sample, const PoseLimits& limits);
// `previous` is the newest accepted sample (normalised attitude), `sample` a checked one.
// judgeMotion false (after a known discontinuity) checks only the timestamp order and repeats.
PoseCheck checkStep(const PoseSample& previous, const PoseSample& sample, const PoseLimits& limits,
                    bool judgeMotion = true);

// "gimbal_pitch_deg 999 outside [-120, 30]" into out (NUL-terminated, cut when too long).
int formatRejection(std::span<char> out, const PoseCheck& check);

}  // namespace vp::telemetry
