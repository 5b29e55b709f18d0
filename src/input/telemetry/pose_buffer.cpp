#include "telemetry/pose_buffer.hpp"

#include <cmath>

namespace vp::telemetry {

namespace {

// Signed smallest difference b - a of two angles in degrees, in (-180, 180].
double delta_deg(double a, double b) {
  double d = std::fmod(b - a, 360.0);
  if (d <= -180.0) {
    d += 360.0;
  } else if (d > 180.0) {
    d -= 360.0;
  }
  return d;
}

double wrapDeg180(double angle) {
  double a = std::fmod(angle, 360.0);
  if (a <= -180.0) {
    a += 360.0;
  } else if (a > 180.0) {
    a -= 360.0;
  }
  return a;
}

// a * (a^-1 b)^s along the shorter arc; s outside [0, 1] extrapolates at the same rate.
Eigen::Quaterniond slerp(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b, double s) {
  Eigen::Quaterniond delta = a.conjugate() * b;
  if (delta.w() < 0.0) {
    delta.coeffs() = -delta.coeffs();  // q and -q are the same rotation: take the short way
  }
  const Eigen::AngleAxisd step(delta);
  Eigen::Quaterniond out = a * Eigen::Quaterniond(Eigen::AngleAxisd(s * step.angle(), step.axis()));
  out.normalize();
  return out;
}

PoseSample blend(const PoseSample& a, const PoseSample& b, std::int64_t t) {
  const double s = static_cast<double>(t - a.timestamp_ns) /
                   static_cast<double>(b.timestamp_ns - a.timestamp_ns);
  PoseSample out;
  out.timestamp_ns = t;
  out.position = interpolatePosition(a.position, b.position, s);
  out.bodyToNed = slerp(a.bodyToNed, b.bodyToNed, s);
  // Gimbal angles are only comparable in one reference; across a switch take the nearer one.
  if (a.gimbal.reference == b.gimbal.reference) {
    out.gimbal.reference = a.gimbal.reference;
    out.gimbal.angles = interpolateAngles_deg(a.gimbal.angles, b.gimbal.angles, s);
  } else {
    out.gimbal = s < 0.5 ? a.gimbal : b.gimbal;
  }
  return out;
}

}  // namespace

const char* toString(PoseStatus status) {
  switch (status) {
    case PoseStatus::Ok:
      return "ok";
    case PoseStatus::NoPose:
      return "no pose";
    case PoseStatus::Stale:
      return "stale pose";
    case PoseStatus::Invalid:
      return "invalid pose";
  }
  return "unknown pose status";
}

geodesy::GeodeticPoint interpolatePosition(const geodesy::GeodeticPoint& a,
                                           const geodesy::GeodeticPoint& b, double s) {
  geodesy::GeodeticPoint out;
  out.latitude_deg = a.latitude_deg + s * (b.latitude_deg - a.latitude_deg);
  out.longitude_deg = wrapDeg180(a.longitude_deg + s * delta_deg(a.longitude_deg, b.longitude_deg));
  out.height_m = a.height_m + s * (b.height_m - a.height_m);
  return out;
}

geodesy::EulerAnglesDeg interpolateAngles_deg(const geodesy::EulerAnglesDeg& a,
                                              const geodesy::EulerAnglesDeg& b, double s) {
  return {wrapDeg180(a.roll_deg + s * delta_deg(a.roll_deg, b.roll_deg)),
          wrapDeg180(a.pitch_deg + s * delta_deg(a.pitch_deg, b.pitch_deg)),
          wrapDeg180(a.yaw_deg + s * delta_deg(a.yaw_deg, b.yaw_deg))};
}

bool PoseBuffer::init(const PoseBufferConfig& config, std::string* why) {
  const auto fail = [why](const std::string& message) {
    if (why != nullptr) {
      *why = "pose buffer: " + message;
    }
    return false;
  };
  if (config.capacity < 2) {
    return fail("capacity must be at least 2 samples, got " + std::to_string(config.capacity));
  }
  if (config.maxAge_ns <= 0) {
    return fail("maxAge_ns must be > 0, got " + std::to_string(config.maxAge_ns));
  }
  if (config.startTolerance_ns < 0) {
    return fail("startTolerance_ns must be >= 0, got " + std::to_string(config.startTolerance_ns));
  }
  std::string problem;
  if (!validateLimits(config.limits, &problem)) {
    return fail(problem);
  }
  config_ = config;
  ring_.assign(config.capacity, PoseSample{});
  oldest_ = 0;
  count_ = 0;
  rejectedSinceNewest_ = false;
  judgeNextStep_ = true;
  counters_ = {};
  lastRejection_ = {};
  return true;
}

void PoseBuffer::clear() {
  oldest_ = 0;
  count_ = 0;
  rejectedSinceNewest_ = false;
}

const PoseSample& PoseBuffer::at(std::size_t i) const {
  return ring_[(oldest_ + i) % ring_.size()];
}

PushResult PoseBuffer::push(const PoseSample& sample) {
  if (ring_.empty()) {
    return PushResult::NotInitialised;
  }
  PoseCheck check = checkSample(sample, config_.limits);
  if (check.ok() && count_ > 0) {
    check = checkStep(at(count_ - 1), sample, config_.limits, judgeNextStep_);
  }
  switch (check.result) {
    case PushResult::Accepted:
    case PushResult::NotInitialised:
      break;
    case PushResult::NotFinite:
      ++counters_.notFinite;
      break;
    case PushResult::OutOfRange:
      ++counters_.outOfRange;
      break;
    case PushResult::ZeroQuaternion:
      ++counters_.zeroQuaternion;
      break;
    case PushResult::OutOfLimits:
      ++counters_.outOfLimits;
      break;
    case PushResult::Inconsistent:
      ++counters_.inconsistent;
      break;
    case PushResult::OutOfOrder:
      ++counters_.outOfOrder;
      break;
    case PushResult::Duplicate:
      ++counters_.duplicates;
      break;
  }
  if (!check.ok()) {
    lastRejection_ = check;
    // A late or repeated sample (e.g. two links) says nothing about the link's health; every
    // other refusal means the telemetry is currently wrong: extrapolating past the newest
    // good sample is not trusted until a good one arrives.
    if (check.result != PushResult::OutOfOrder && check.result != PushResult::Duplicate) {
      rejectedSinceNewest_ = true;
    }
    return check.result;
  }
  std::size_t slot = 0;
  if (count_ == ring_.size()) {
    slot = oldest_;
    oldest_ = (oldest_ + 1) % ring_.size();
    ++counters_.overwritten;
  } else {
    slot = (oldest_ + count_) % ring_.size();
    ++count_;
  }
  ring_[slot] = sample;
  ring_[slot].bodyToNed.normalize();
  rejectedSinceNewest_ = false;
  judgeNextStep_ = true;
  ++counters_.accepted;
  return PushResult::Accepted;
}

PoseEstimate PoseBuffer::poseAt(std::int64_t timestamp_ns) const {
  PoseEstimate out;
  if (count_ == 0) {
    return out;  // NoPose, age_ns -1
  }
  const PoseSample& oldest = at(0);
  const PoseSample& newest = at(count_ - 1);

  if (timestamp_ns < oldest.timestamp_ns) {
    out.pose = oldest;
    out.age_ns = oldest.timestamp_ns - timestamp_ns;
    out.status = out.age_ns <= config_.startTolerance_ns ? PoseStatus::Ok : PoseStatus::NoPose;
    if (out.status == PoseStatus::Ok) {
      out.pose.timestamp_ns = timestamp_ns;  // held: the drone barely moves in a few ms
    }
    return out;
  }

  if (timestamp_ns >= newest.timestamp_ns) {
    out.age_ns = timestamp_ns - newest.timestamp_ns;
    out.pose = newest;
    if (timestamp_ns > newest.timestamp_ns && rejectedSinceNewest_) {
      out.status = PoseStatus::Invalid;
      return out;
    }
    if (out.age_ns > config_.maxAge_ns) {
      out.status = PoseStatus::Stale;
      return out;
    }
    out.status = PoseStatus::Ok;
    if (out.age_ns == 0) {
      return out;
    }
    // Extrapolate with the last interval's rates when it is recent enough to speak for now.
    if (count_ >= 2) {
      const PoseSample& previous = at(count_ - 2);
      if (newest.timestamp_ns - previous.timestamp_ns <= config_.maxAge_ns) {
        out.pose = blend(previous, newest, timestamp_ns);
        return out;
      }
    }
    out.pose.timestamp_ns = timestamp_ns;  // hold
    return out;
  }

  // oldest <= t < newest: binary search for the first sample after t.
  std::size_t lo = 0;
  std::size_t hi = count_ - 1;  // at(hi) > t, at(lo) <= t
  while (hi - lo > 1) {
    const std::size_t mid = lo + (hi - lo) / 2;
    if (at(mid).timestamp_ns <= timestamp_ns) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  const PoseSample& a = at(lo);
  const PoseSample& b = at(hi);
  const std::int64_t toA = timestamp_ns - a.timestamp_ns;
  const std::int64_t toB = b.timestamp_ns - timestamp_ns;
  out.age_ns = std::min(toA, toB);
  if (out.age_ns > config_.maxAge_ns) {
    out.pose = toA <= toB ? a : b;
    out.status = PoseStatus::Stale;
    return out;
  }
  out.pose = toA == 0 ? a : blend(a, b, timestamp_ns);
  out.status = PoseStatus::Ok;
  return out;
}

}  // namespace vp::telemetry
