#include "telemetry/pose_check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace vp::telemetry {

namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
// Mean Earth radius: the jump check needs metres to a few per cent, not geodesy.
constexpr double kMetresPerDegree = 6'371'000.0 * std::numbers::pi / 180.0;
// A repeat must match to far below any sensor's resolution: the same sample sent twice.
constexpr double kRepeatAngle_rad = 1e-9;
constexpr double kRepeatDegrees = 1e-9;
constexpr double kRepeatHeight_m = 1e-6;

PoseCheck fail(PushResult result, const char* field, double value, double low, double high,
               std::int64_t timestamp_ns) {
  return PoseCheck{result, field, value, low, high, timestamp_ns};
}

bool outside(double value, double low, double high) {
  return !(value >= low && value <= high);
}

double wrappedDelta_deg(double a, double b) {
  return std::remainder(b - a, 360.0);
}

// Angle of the rotation between two gimbal heads, deg (no gimbal-lock trouble at nadir).
double gimbalStep_deg(const geodesy::EulerAnglesDeg& a, const geodesy::EulerAnglesDeg& b) {
  const Eigen::Matrix3d relative =
      geodesy::rotationFromEuler(a).transpose() * geodesy::rotationFromEuler(b);
  const double c = std::clamp((relative.trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c) * kRadToDeg;
}

}  // namespace

const char* toString(PushResult result) {
  switch (result) {
    case PushResult::Accepted:
      return "accepted";
    case PushResult::NotFinite:
      return "not finite";
    case PushResult::OutOfRange:
      return "position out of range";
    case PushResult::ZeroQuaternion:
      return "zero attitude quaternion";
    case PushResult::OutOfLimits:
      return "outside the pose limits";
    case PushResult::OutOfOrder:
      return "timestamp before the newest sample";
    case PushResult::Duplicate:
      return "repeat of the newest sample";
    case PushResult::Inconsistent:
      return "inconsistent with the newest sample";
    case PushResult::NotInitialised:
      return "pose buffer not initialised";
  }
  return "unknown push result";
}

bool validateLimits(const PoseLimits& l, std::string* why) {
  const auto bad = [why](const std::string& message) {
    if (why != nullptr) {
      *why = "pose limits: " + message;
    }
    return false;
  };
  const auto interval = [&](const char* name, double low, double high) {
    return std::isfinite(low) && std::isfinite(high) && low < high
               ? true
               : bad(std::string(name) + ": minimum must be below maximum, got [" +
                     std::to_string(low) + ", " + std::to_string(high) + "]");
  };
  const auto positive = [&](const char* name, double value) {
    return value > 0.0 && std::isfinite(value)
               ? true
               : bad(std::string(name) + ": must be > 0, got " + std::to_string(value));
  };
  const auto nonNegative = [&](const char* name, double value) {
    return value >= 0.0 && std::isfinite(value)
               ? true
               : bad(std::string(name) + ": must be >= 0, got " + std::to_string(value));
  };
  return interval("height_m", l.minHeight_m, l.maxHeight_m) &&
         interval("gimbal_roll_deg", l.minGimbalRoll_deg, l.maxGimbalRoll_deg) &&
         interval("gimbal_pitch_deg", l.minGimbalPitch_deg, l.maxGimbalPitch_deg) &&
         interval("gimbal_yaw_deg", l.minGimbalYaw_deg, l.maxGimbalYaw_deg) &&
         positive("quaternionNormTolerance", l.quaternionNormTolerance) &&
         positive("maxTilt_deg", l.maxTilt_deg) &&
         positive("maxHorizontalSpeed_mps", l.maxHorizontalSpeed_mps) &&
         positive("maxVerticalSpeed_mps", l.maxVerticalSpeed_mps) &&
         positive("maxAngularRate_degps", l.maxAngularRate_degps) &&
         nonNegative("jumpTolerance_m", l.jumpTolerance_m) &&
         nonNegative("jumpTolerance_deg", l.jumpTolerance_deg) &&
         nonNegative("consistencyWindow_ns", static_cast<double>(l.consistencyWindow_ns));
}

PoseCheck checkSample(const PoseSample& s, const PoseLimits& l) {
  const geodesy::GeodeticPoint& p = s.position;
  const geodesy::EulerAnglesDeg& g = s.gimbal.angles;
  const std::int64_t t = s.timestamp_ns;
  const Eigen::Vector4d q = s.bodyToNed.coeffs();
  if (!std::isfinite(p.latitude_deg)) {
    return fail(PushResult::NotFinite, "latitude_deg", p.latitude_deg, -90.0, 90.0, t);
  }
  if (!std::isfinite(p.longitude_deg)) {
    return fail(PushResult::NotFinite, "longitude_deg", p.longitude_deg, -180.0, 180.0, t);
  }
  if (!std::isfinite(p.height_m)) {
    return fail(PushResult::NotFinite, "height_m", p.height_m, l.minHeight_m, l.maxHeight_m, t);
  }
  if (!q.allFinite()) {
    return fail(PushResult::NotFinite, "attitude quaternion", q.norm(), 1.0, 1.0, t);
  }
  if (!std::isfinite(g.roll_deg) || !std::isfinite(g.pitch_deg) || !std::isfinite(g.yaw_deg)) {
    const double bad = !std::isfinite(g.roll_deg)    ? g.roll_deg
                       : !std::isfinite(g.pitch_deg) ? g.pitch_deg
                                                     : g.yaw_deg;
    return fail(PushResult::NotFinite, "gimbal angles", bad, -180.0, 180.0, t);
  }
  if (outside(p.latitude_deg, -90.0, 90.0)) {
    return fail(PushResult::OutOfRange, "latitude_deg", p.latitude_deg, -90.0, 90.0, t);
  }
  if (outside(p.longitude_deg, -180.0, 180.0)) {
    return fail(PushResult::OutOfRange, "longitude_deg", p.longitude_deg, -180.0, 180.0, t);
  }
  const double norm = q.norm();
  if (norm < kMinQuaternionNorm) {
    return fail(PushResult::ZeroQuaternion, "attitude quaternion norm", norm, 1.0, 1.0, t);
  }
  if (outside(p.height_m, l.minHeight_m, l.maxHeight_m)) {
    return fail(PushResult::OutOfLimits, "height_m", p.height_m, l.minHeight_m, l.maxHeight_m, t);
  }
  if (std::abs(norm - 1.0) > l.quaternionNormTolerance) {
    return fail(PushResult::OutOfLimits, "attitude quaternion norm", norm,
                1.0 - l.quaternionNormTolerance, 1.0 + l.quaternionNormTolerance, t);
  }
  // Body down (z) in NED: the last column of R_nb; its down component is cos(tilt).
  const Eigen::Quaterniond unit = s.bodyToNed.normalized();
  const double tilt_deg =
      std::acos(std::clamp(unit.toRotationMatrix()(2, 2), -1.0, 1.0)) * kRadToDeg;
  if (tilt_deg > l.maxTilt_deg) {
    return fail(PushResult::OutOfLimits, "tilt_deg", tilt_deg, 0.0, l.maxTilt_deg, t);
  }
  if (outside(g.roll_deg, l.minGimbalRoll_deg, l.maxGimbalRoll_deg)) {
    return fail(PushResult::OutOfLimits, "gimbal_roll_deg", g.roll_deg, l.minGimbalRoll_deg,
                l.maxGimbalRoll_deg, t);
  }
  if (outside(g.pitch_deg, l.minGimbalPitch_deg, l.maxGimbalPitch_deg)) {
    return fail(PushResult::OutOfLimits, "gimbal_pitch_deg", g.pitch_deg, l.minGimbalPitch_deg,
                l.maxGimbalPitch_deg, t);
  }
  if (outside(g.yaw_deg, l.minGimbalYaw_deg, l.maxGimbalYaw_deg)) {
    return fail(PushResult::OutOfLimits, "gimbal_yaw_deg", g.yaw_deg, l.minGimbalYaw_deg,
                l.maxGimbalYaw_deg, t);
  }
  return PoseCheck{PushResult::Accepted, "", 0.0, 0.0, 0.0, t};
}

PoseCheck checkStep(const PoseSample& previous, const PoseSample& s, const PoseLimits& l,
                    bool judgeMotion) {
  const std::int64_t t = s.timestamp_ns;
  const std::int64_t dt_ns = t - previous.timestamp_ns;
  const geodesy::GeodeticPoint& a = previous.position;
  const geodesy::GeodeticPoint& b = s.position;
  const double north_m = (b.latitude_deg - a.latitude_deg) * kMetresPerDegree;
  const double east_m = wrappedDelta_deg(a.longitude_deg, b.longitude_deg) * kMetresPerDegree *
                        std::cos(a.latitude_deg / kRadToDeg);
  const double horizontal_m = std::hypot(north_m, east_m);
  const double vertical_m = std::abs(b.height_m - a.height_m);
  const double body_deg = previous.bodyToNed.angularDistance(s.bodyToNed.normalized()) * kRadToDeg;
  const bool sameReference = previous.gimbal.reference == s.gimbal.reference;
  const double gimbal_deg =
      sameReference ? gimbalStep_deg(previous.gimbal.angles, s.gimbal.angles) : 0.0;

  if (dt_ns < 0) {
    return fail(PushResult::OutOfOrder, "timestamp_ns", static_cast<double>(dt_ns) / 1e9, 0.0, 0.0,
                t);
  }
  if (dt_ns == 0) {
    // The same instant twice: harmless when it is the same sample (a resend, two links),
    // inconsistent when the values differ, since one of the two must be wrong.
    const geodesy::EulerAnglesDeg& ga = previous.gimbal.angles;
    const geodesy::EulerAnglesDeg& gb = s.gimbal.angles;
    const bool same =
        std::abs(b.latitude_deg - a.latitude_deg) <= kRepeatDegrees &&
        std::abs(wrappedDelta_deg(a.longitude_deg, b.longitude_deg)) <= kRepeatDegrees &&
        vertical_m <= kRepeatHeight_m && body_deg / kRadToDeg <= kRepeatAngle_rad &&
        sameReference && std::abs(wrappedDelta_deg(ga.roll_deg, gb.roll_deg)) <= kRepeatDegrees &&
        std::abs(wrappedDelta_deg(ga.pitch_deg, gb.pitch_deg)) <= kRepeatDegrees &&
        std::abs(wrappedDelta_deg(ga.yaw_deg, gb.yaw_deg)) <= kRepeatDegrees;
    if (same) {
      return fail(PushResult::Duplicate, "timestamp_ns", static_cast<double>(t), 0.0, 0.0, t);
    }
    // Name the largest difference, so that the log says what disagrees.
    if (horizontal_m > kRepeatHeight_m) {
      return fail(PushResult::Inconsistent, "horizontal position differs by (m)", horizontal_m, 0.0,
                  0.0, t);
    }
    if (vertical_m > kRepeatHeight_m) {
      return fail(PushResult::Inconsistent, "height differs by (m)", vertical_m, 0.0, 0.0, t);
    }
    if (body_deg / kRadToDeg > kRepeatAngle_rad) {
      return fail(PushResult::Inconsistent, "attitude differs by (deg)", body_deg, 0.0, 0.0, t);
    }
    return fail(PushResult::Inconsistent, "gimbal differs by (deg)",
                sameReference ? gimbal_deg : 180.0, 0.0, 0.0, t);
  }
  if (!judgeMotion || dt_ns > l.consistencyWindow_ns) {
    return PoseCheck{PushResult::Accepted, "", 0.0, 0.0, 0.0, t};
  }
  const double dt_s = static_cast<double>(dt_ns) / 1e9;
  const double allowedHorizontal_m = l.maxHorizontalSpeed_mps * dt_s + l.jumpTolerance_m;
  const double allowedVertical_m = l.maxVerticalSpeed_mps * dt_s + l.jumpTolerance_m;
  const double allowedTurn_deg = l.maxAngularRate_degps * dt_s + l.jumpTolerance_deg;
  if (horizontal_m > allowedHorizontal_m) {
    return fail(PushResult::Inconsistent, "horizontal jump (m)", horizontal_m, 0.0,
                allowedHorizontal_m, t);
  }
  if (vertical_m > allowedVertical_m) {
    return fail(PushResult::Inconsistent, "vertical jump (m)", vertical_m, 0.0, allowedVertical_m,
                t);
  }
  if (body_deg > allowedTurn_deg) {
    return fail(PushResult::Inconsistent, "attitude jump (deg)", body_deg, 0.0, allowedTurn_deg, t);
  }
  if (gimbal_deg > allowedTurn_deg) {
    return fail(PushResult::Inconsistent, "gimbal jump (deg)", gimbal_deg, 0.0, allowedTurn_deg, t);
  }
  return PoseCheck{PushResult::Accepted, "", 0.0, 0.0, 0.0, t};
}

int formatRejection(std::span<char> out, const PoseCheck& c) {
  if (out.empty()) {
    return 0;
  }
  int n = 0;
  switch (c.result) {
    case PushResult::Accepted:
      n = std::snprintf(out.data(), out.size(), "accepted");
      break;
    case PushResult::NotFinite:
      n = std::snprintf(out.data(), out.size(), "%s: not finite (%g)", c.field, c.value);
      break;
    case PushResult::OutOfRange:
    case PushResult::OutOfLimits:
    case PushResult::ZeroQuaternion:
      n = std::snprintf(out.data(), out.size(), "%s %.9g outside [%.9g, %.9g]", c.field, c.value,
                        c.low, c.high);
      break;
    case PushResult::OutOfOrder:
      n = std::snprintf(out.data(), out.size(),
                        "timestamp %lld ns is %.6f s before the newest sample",
                        static_cast<long long>(c.timestamp_ns), -c.value);
      break;
    case PushResult::Duplicate:
      n = std::snprintf(out.data(), out.size(), "timestamp %lld ns repeated with the same values",
                        static_cast<long long>(c.timestamp_ns));
      break;
    case PushResult::Inconsistent:
      if (c.high > 0.0) {
        n = std::snprintf(out.data(), out.size(), "%s %.6g over the %.6g the limits allow", c.field,
                          c.value, c.high);
      } else {
        n = std::snprintf(out.data(), out.size(),
                          "timestamp %lld ns repeated with other values: %s %.6g",
                          static_cast<long long>(c.timestamp_ns), c.field, c.value);
      }
      break;
    case PushResult::NotInitialised:
      n = std::snprintf(out.data(), out.size(), "pose buffer not initialised");
      break;
  }
  return std::min(n, static_cast<int>(out.size()) - 1);
}

}  // namespace vp::telemetry
