// platform/dds/telemetry_conversion: the flight stacks' ROS 2 telemetry samples
// (idl/ros_telemetry.idl) -> one plain pose sample in our conventions (docs/conventions.md).
//
// Contract: pure functions, no DDS entity, no allocation, no exception. A sample that cannot be
// a pose (a non-finite value, a quaternion far from unit length, a latitude/longitude out of
// range) is rejected with the reason and `out` is left unspecified; nothing is guessed.
// Attitude leaves here as q_nb: the unit quaternion (w >= 0) that rotates body FRD vectors into
// local NED, which PX4 publishes as is and ArduPilot publishes as REP-103's body FLU -> ENU
// (converted here). Positions are WGS84 with ellipsoidal heights: PX4's alt_ellipsoid, and
// ArduPilot's GeoPose altitude plus a configured offset (ArduPilot fills it with its AMSL
// altitude, see docs/telemetry.md). Times are kept in the autopilot's own time base, said in
// PoseSample::timeBase; mapping them to the loop's clock is the consumer's job.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <limits>

#include "geodesy/geodesy.hpp"
#include "ros_telemetry.h"

namespace vp::platform::dds {

enum class PoseSource : std::uint8_t {
  ArduPilotGeoPose,   // geographic_msgs/GeoPoseStamped: position and attitude
  Px4Attitude,        // px4_msgs/VehicleAttitude: attitude only
  Px4GlobalPosition,  // px4_msgs/VehicleGlobalPosition: position only
};
const char* toString(PoseSource source);

enum class TelemetryTimeBase : std::uint8_t {
  AutopilotBoot,  // since the autopilot booted (PX4 timestamp; ArduPilot without GNSS time)
  Utc,            // since the Unix epoch (ArduPilot's header stamp once it has GNSS time)
};

struct PoseSample {
  PoseSource source = PoseSource::ArduPilotGeoPose;
  bool hasPosition = false;
  bool hasAttitude = false;
  std::int64_t time_ns = 0;  // when the autopilot's estimate was valid, in timeBase
  TelemetryTimeBase timeBase = TelemetryTimeBase::AutopilotBoot;
  std::int64_t sourceTimestamp_ns = 0;  // DDS source timestamp: the bridge's UTC clock at write
  geodesy::GeodeticPoint position{};    // WGS84, ellipsoidal height (when hasPosition)
  Eigen::Quaterniond bodyToNed = Eigen::Quaterniond::Identity();  // q_nb (when hasAttitude)
  // 1-sigma position uncertainty when the source gives it (PX4 eph/epv), NaN otherwise.
  float horizontalStd_m = std::numeric_limits<float>::quiet_NaN();
  float verticalStd_m = std::numeric_limits<float>::quiet_NaN();
};

enum class TelemetryRejection : std::uint8_t {
  None,
  NonFinite,           // NaN or infinity in a used field
  NotUnitQuaternion,   // |q| differs from 1 by more than kUnitQuaternionTolerance (e.g. all 0)
  PositionOutOfRange,  // latitude outside [-90, 90] or longitude outside [-180, 180]
};
const char* toString(TelemetryRejection rejection);

// A quaternion whose norm is within this of 1 is renormalised; float32 quaternions (PX4) are
// unit to about 1e-7, so anything beyond 1 % is a broken sample, not rounding.
constexpr double kUnitQuaternionTolerance = 0.01;
// Header stamps with at least this many seconds are taken as UTC (2001-09-09), smaller ones as
// time since boot: ArduPilot stamps with UTC once it has GNSS time, with boot time before.
constexpr std::int64_t kUtcStampThreshold_s = 1'000'000'000;

// REP-103 orientation (body FLU -> ENU) <-> ours (body FRD -> NED); each is the other's inverse.
Eigen::Quaterniond nedFrdFromEnuFlu(const Eigen::Quaterniond& enuFlu);
Eigen::Quaterniond enuFluFromNedFrd(const Eigen::Quaterniond& nedFrd);

TelemetryRejection fromGeoPose(const geographic_msgs_msg_dds__GeoPoseStamped_& message,
                               double altitudeOffset_m, PoseSample& out);
TelemetryRejection fromPx4Attitude(const px4_msgs_msg_dds__VehicleAttitude_& message,
                                   PoseSample& out);
TelemetryRejection fromPx4GlobalPosition(const px4_msgs_msg_dds__VehicleGlobalPosition_& message,
                                         PoseSample& out);

}  // namespace vp::platform::dds
