// telemetry/pose_buffer: the drone's recent poses, and its pose at a frame's capture time.
//
// Contract: producers (the recording reader, a MAVLink or DDS telemetry link) push
// timestamped pose samples: the WGS84 position of the body origin (ellipsoidal height), the
// autopilot attitude q_nb and the gimbal state (docs/conventions.md). The loop asks
// poseAt(t) for the pose at a frame's capture time, on the same clock. Every sample is checked
// at push() (telemetry/pose_check.hpp, limits in PoseBufferConfig::limits): a non-finite or
// out-of-range value, a (near) zero or non-unit quaternion, a height, tilt or gimbal angle
// outside the limits, a timestamp before the newest accepted one, a repeat of the newest
// timestamp (harmless when the values are the same, inconsistent otherwise) or a jump faster
// than the limits allow is rejected, counted by reason, kept as lastRejection() for the
// caller's log, and never used. This is the one place every sample goes through (recording,
// MAVLink, DDS). poseAt() interpolates
// between the two samples around t: position linearly in latitude, longitude and height
// (longitude across the antimeridian), attitude by slerp, gimbal angles each along the
// shorter way round the circle. After the newest sample it extrapolates with the rate of the
// last two samples (hold when they are further apart than maxAge_ns). The status says whether
// the pose may be used: Ok; NoPose (nothing usable at t: empty buffer, t before the oldest
// kept sample by more than startTolerance_ns); Stale (the nearest accepted sample is more than
// maxAge_ns away from t, while interpolating or extrapolating); Invalid (t is after the newest
// accepted sample and the producer has pushed only rejected samples since: the telemetry is
// currently broken). Only an Ok estimate carries a pose meant for lifting; the others carry
// the nearest sample for diagnostics.
// Memory: the ring of `capacity` samples is allocated by init(); push() and poseAt() never
// allocate and never throw. Threading: not synchronised. The app serialises access: the loop
// thread drains the telemetry link's queue into the buffer before it queries it (the
// recording reader does the same synchronously).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "geodesy/attitude.hpp"
#include "geodesy/geodesy.hpp"
#include "telemetry/pose_check.hpp"

namespace vp::telemetry {

enum class PoseStatus : std::uint8_t { Ok, NoPose, Stale, Invalid };
const char* toString(PoseStatus status);

struct PoseBufferConfig {
  std::size_t capacity = 256;                  // samples kept (25 s of 10 Hz telemetry)
  std::int64_t maxAge_ns = 200'000'000;        // 200 ms: nearest sample further -> Stale
  std::int64_t startTolerance_ns = 5'000'000;  // 5 ms: t this far before the oldest -> held
  PoseLimits limits{};                         // plausibility of each sample (pose_check.hpp)
};

struct PoseBufferCounters {
  std::uint64_t accepted = 0;
  std::uint64_t notFinite = 0;
  std::uint64_t outOfRange = 0;
  std::uint64_t zeroQuaternion = 0;
  std::uint64_t outOfLimits = 0;
  std::uint64_t outOfOrder = 0;
  std::uint64_t duplicates = 0;
  std::uint64_t inconsistent = 0;
  std::uint64_t overwritten = 0;  // oldest samples dropped because the ring was full
  std::uint64_t rejected() const {
    return notFinite + outOfRange + zeroQuaternion + outOfLimits + outOfOrder + duplicates +
           inconsistent;
  }
};

struct PoseEstimate {
  PoseStatus status = PoseStatus::NoPose;
  PoseSample pose{};         // at the queried time when Ok; nearest sample otherwise
  std::int64_t age_ns = -1;  // |t - nearest accepted sample|, ns; -1 when the buffer is empty
};

class PoseBuffer {
 public:
  PoseBuffer() = default;

  // Allocates the ring. Fails (with *why) on capacity < 2, non-positive/negative times or
  // invalid limits.
  bool init(const PoseBufferConfig& config, std::string* why = nullptr);

  // Validates and stores one sample; on the ring being full the oldest sample is dropped.
  PushResult push(const PoseSample& sample);
  // The pose at the capture time t (same clock as the samples).
  PoseEstimate poseAt(std::int64_t timestamp_ns) const;

  void clear();  // forgets every sample (e.g. after a telemetry link restart); keeps counters
  // The next sample need not continue the newest one (a looped recording starting over, an
  // estimator reset the producer knows of): its step is not judged, only its order.
  void markDiscontinuity() { judgeNextStep_ = false; }
  std::size_t size() const { return count_; }
  std::size_t capacity() const { return ring_.size(); }
  const PoseBufferConfig& config() const { return config_; }
  const PoseBufferCounters& counters() const { return counters_; }
  // What the latest rejected sample failed (result Accepted before any rejection).
  const PoseCheck& lastRejection() const { return lastRejection_; }

 private:
  const PoseSample& at(std::size_t i) const;  // i-th oldest sample, i < count_

  PoseBufferConfig config_{};
  std::vector<PoseSample> ring_;  // sized once by init()
  std::size_t oldest_ = 0;        // ring index of the oldest sample
  std::size_t count_ = 0;
  bool rejectedSinceNewest_ = false;  // a sample was rejected after the newest accepted one
  bool judgeNextStep_ = true;         // false after markDiscontinuity(), until a sample is stored
  PoseBufferCounters counters_{};
  PoseCheck lastRejection_{};
};

// Interpolation primitives, exposed for the tests and other telemetry producers.
// Position: linear in latitude, longitude (shorter way across the antimeridian) and height.
geodesy::GeodeticPoint interpolatePosition(const geodesy::GeodeticPoint& a,
                                           const geodesy::GeodeticPoint& b, double s);
// Each Euler angle along the shorter way round, result in (-180, 180] deg.
geodesy::EulerAnglesDeg interpolateAngles_deg(const geodesy::EulerAnglesDeg& a,
                                              const geodesy::EulerAnglesDeg& b, double s);

}  // namespace vp::telemetry
