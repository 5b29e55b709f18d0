// mavlink/pose_assembler: decoded MAVLink messages -> pose samples of the drone (WGS84
// position, body attitude q_nb, gimbal attitude) stamped on the local monotonic clock.
//
// Contract: pure and allocation-free; add() takes one decoded message with the sender's
// system id and the local monotonic time it was received, and says whether a new pose
// sample is ready. A sample is produced for every attitude message once a position is
// known; it carries the latest position and gimbal with their own timestamps, so the
// consumer can judge staleness and interpolate to a frame's time (the lifting stage's
// job, not this one's). Bad values (NaN, a quaternion far from unit norm, latitude out of
// range, contradictory gimbal flags) are rejected and counted; they never reach a sample.
//
// Time: MAVLink stamps messages with time_boot_ms of the sender's own boot clock (the
// autopilot and a gimbal device each have one). BootClockMapper estimates
// offset = local - boot as the minimum of (receive time - boot time) over a sliding window:
// transport only ever delays a message, so the least-delayed one in the window is the best
// estimate; the window lets it follow the drift between the two crystals (tens of ppm).
// The estimate is late by the link's minimum latency, which the configuration may subtract
// (linkLatency_ns). A boot time going backwards (the sender rebooted) restarts the estimate.
//
// Frames: ATTITUDE_QUATERNION q is q_nb (body FRD -> NED) as docs/conventions.md uses; when an
// autopilot sends only ATTITUDE, its ZYX Euler angles are turned into q_nb (once a quaternion
// has been seen, ATTITUDE is ignored so each attitude update yields one sample).
// GLOBAL_POSITION_INT altitude is above mean sea level; heights here are ellipsoidal, so the
// geoid separation N of the flying area is added (h = H_msl + N; configuration).
// GIMBAL_DEVICE_ATTITUDE_STATUS q has roll and pitch relative to the horizon and yaw relative
// to north (earth frame) or to the vehicle's heading (vehicle frame), as its flags say. Both are
// reported as an earth-referenced GimbalState: a vehicle-frame yaw is turned to north by
// delta_yaw when the gimbal sends it, else by the drone's latest yaw.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "geodesy/attitude.hpp"
#include "geodesy/geodesy.hpp"
#include "mavlink/messages.hpp"

namespace vp::mavlink {

class BootClockMapper {
 public:
  static constexpr std::size_t kWindow = 64;  // observations the minimum is taken over
  // A boot time this far behind the last one means the sender rebooted.
  static constexpr std::uint32_t kRebootJump_ms = 1000;

  // One message stamped `boot_ms` on the sender, received at local `receive_ns`.
  void observe(std::uint32_t boot_ms, std::int64_t receive_ns);
  bool valid() const { return count_ > 0; }
  std::int64_t offset_ns() const { return offsetNs_; }  // local = boot + offset
  std::int64_t toLocal_ns(std::uint32_t boot_ms) const {
    return static_cast<std::int64_t>(boot_ms) * 1'000'000 + offsetNs_;
  }
  std::uint64_t restarts() const { return restarts_; }  // reboots seen

 private:
  std::array<std::int64_t, kWindow> offsets_{};
  std::size_t count_ = 0;  // observations in the window (<= kWindow)
  std::size_t next_ = 0;   // ring position of the next observation
  std::int64_t offsetNs_ = 0;
  std::uint32_t lastBootMs_ = 0;
  std::uint64_t restarts_ = 0;
};

struct PoseAssemblerConfig {
  double geoidSeparation_m = 0.0;         // N of the flying area: ellipsoidal h = MSL height + N
  std::int64_t linkLatency_ns = 0;        // minimum transport delay, subtracted from the offset
  std::uint8_t systemId = 0;              // only messages of this system; 0 = any system
  double quaternionNormTolerance = 1e-2;  // |1 - |q|| beyond this rejects the message
};

struct PoseSample {
  std::int64_t timestamp_ns = 0;  // local monotonic time of the attitude
  Eigen::Quaterniond bodyToNed{Eigen::Quaterniond::Identity()};  // q_nb, normalised
  geodesy::GeodeticPoint position{};                             // ellipsoidal height
  std::int64_t positionTimestamp_ns = 0;
  bool hasGimbal = false;
  geodesy::GimbalState gimbal{};  // reference Earth when hasGimbal
  std::int64_t gimbalTimestamp_ns = 0;
};

struct AssemblerCounters {
  std::uint64_t samples = 0;
  std::uint64_t otherSystem = 0;    // ignored: another system id
  std::uint64_t rejected = 0;       // bad values
  std::uint64_t noPositionYet = 0;  // attitude before the first position
};

class MavlinkPoseAssembler {
 public:
  explicit MavlinkPoseAssembler(const PoseAssemblerConfig& config = {}) : config_(config) {}

  // True when sample() holds a new pose sample.
  bool add(const Message& message, std::uint8_t systemId, std::int64_t receive_ns);

  const PoseSample& sample() const { return sample_; }
  const AssemblerCounters& counters() const { return counters_; }
  const BootClockMapper& autopilotClock() const { return autopilotClock_; }
  const BootClockMapper& gimbalClock() const { return gimbalClock_; }

 private:
  bool addAttitude(std::uint32_t timeBoot_ms, const Eigen::Quaterniond& bodyToNed,
                   std::int64_t receive_ns);
  bool addPosition(const GlobalPositionInt& message, std::int64_t receive_ns);
  bool addGimbal(const GimbalDeviceAttitudeStatus& message, std::int64_t receive_ns);
  bool quaternionOk(const std::array<float, 4>& q) const;

  PoseAssemblerConfig config_;
  BootClockMapper autopilotClock_;
  BootClockMapper gimbalClock_;
  PoseSample sample_{};
  bool hasPosition_ = false;
  bool hasAttitude_ = false;
  bool sawQuaternion_ = false;
  double latestYawRad_ = 0.0;  // of the body in NED, for vehicle-frame gimbal yaw
  AssemblerCounters counters_{};
};

}  // namespace vp::mavlink
