// tests/platform/dds/telemetry_cases: known drone attitudes and positions, and how each flight
// stack puts them on the wire, shared by the conversion tests and the ROS-typed writer process.
//
// The wire forms are built independently of platform/dds/telemetry_conversion: PX4 sends q_nb
// as float32 (w, x, y, z); ArduPilot's AP_DDS builds its REP-103 GeoPose orientation from its
// NED quaternion by swapping x and y, negating z, and right-multiplying a +90 degree rotation
// about z (AP_DDS_Client.cpp, update_topic for GeoPoseStamped). The expected q_nb comes from
// the Euler angles through geodesy::rotationFromEuler (docs/conventions.md).
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdint>

#include "geodesy/attitude.hpp"
#include "ros_telemetry.h"

namespace vp::test {

struct AttitudeCase {
  double roll_deg;
  double pitch_deg;
  double yaw_deg;
  double latitude_deg;
  double longitude_deg;
  double height_m;  // ellipsoidal
};

// Level north, level east, banked, pitched, and general attitudes, including |yaw| > 90 and a
// steep pitch, at different places (southern and western hemispheres too).
inline constexpr std::array<AttitudeCase, 8> kAttitudeCases = {{
    {0.0, 0.0, 0.0, 43.0731, -89.4012, 260.5},
    {0.0, 0.0, 90.0, 43.0732, -89.4013, 261.0},
    {30.0, 0.0, 0.0, -33.8688, 151.2093, 58.25},
    {0.0, 20.0, 90.0, 48.1374, 11.5755, 519.75},
    {-15.0, 5.0, -135.0, 35.6895, 139.6917, 40.0},
    {10.0, -25.0, 170.0, -22.9068, -43.1729, 12.5},
    {3.0, 60.0, 45.0, 64.1466, -21.9426, 95.0},
    {-170.0, 10.0, -60.0, 0.0001, 0.0001, -20.0},
}};

inline Eigen::Quaterniond expectedBodyToNed(const AttitudeCase& c) {
  Eigen::Quaterniond q(geodesy::rotationFromEuler({c.roll_deg, c.pitch_deg, c.yaw_deg}));
  q.normalize();
  return q.w() < 0.0 ? Eigen::Quaterniond(-q.coeffs()) : q;
}

// ArduPilot's REP-103 orientation from its NED quaternion (see the file comment).
inline Eigen::Quaterniond ardupilotGeoPoseOrientation(const Eigen::Quaterniond& nedFrd) {
  const Eigen::Quaterniond swapped(nedFrd.w(), nedFrd.y(), nedFrd.x(), -nedFrd.z());
  const double half = std::sqrt(2.0) * 0.5;
  return swapped * Eigen::Quaterniond(half, 0.0, 0.0, half);
}

// Header stamp of case i: UTC seconds (after the UTC threshold) plus a fixed fraction.
constexpr std::int32_t kStampBase_s = 1'700'000'000;
constexpr std::uint32_t kStampNanosec = 250'000'000;
// PX4 times of case i: timestamp_sample = (i + 1) s + 5 us since boot, timestamp 100 us later.
constexpr std::uint64_t kPx4SampleBase_us = 1'000'000;

inline geographic_msgs_msg_dds__GeoPoseStamped_ makeGeoPose(std::size_t i, char* frameId) {
  const AttitudeCase& c = kAttitudeCases[i];
  geographic_msgs_msg_dds__GeoPoseStamped_ m{};
  m.header.stamp.sec = kStampBase_s + static_cast<std::int32_t>(i);
  m.header.stamp.nanosec = kStampNanosec;
  m.header.frame_id = frameId;
  m.pose.position.latitude = c.latitude_deg;
  m.pose.position.longitude = c.longitude_deg;
  m.pose.position.altitude = c.height_m;
  const Eigen::Quaterniond o = ardupilotGeoPoseOrientation(expectedBodyToNed(c));
  m.pose.orientation.x = o.x();
  m.pose.orientation.y = o.y();
  m.pose.orientation.z = o.z();
  m.pose.orientation.w = o.w();
  return m;
}

inline px4_msgs_msg_dds__VehicleAttitude_ makePx4Attitude(std::size_t i) {
  const Eigen::Quaterniond q = expectedBodyToNed(kAttitudeCases[i]);
  px4_msgs_msg_dds__VehicleAttitude_ m{};
  m.timestamp_sample = kPx4SampleBase_us * (i + 1) + 5;
  m.timestamp = m.timestamp_sample + 100;
  m.q[0] = static_cast<float>(q.w());
  m.q[1] = static_cast<float>(q.x());
  m.q[2] = static_cast<float>(q.y());
  m.q[3] = static_cast<float>(q.z());
  return m;
}

inline px4_msgs_msg_dds__VehicleGlobalPosition_ makePx4GlobalPosition(std::size_t i) {
  const AttitudeCase& c = kAttitudeCases[i];
  px4_msgs_msg_dds__VehicleGlobalPosition_ m{};
  m.timestamp_sample = kPx4SampleBase_us * (i + 1) + 5;
  m.timestamp = m.timestamp_sample + 100;
  m.lat = c.latitude_deg;
  m.lon = c.longitude_deg;
  m.alt = static_cast<float>(c.height_m - 30.0);  // AMSL: must not be used
  m.alt_ellipsoid = static_cast<float>(c.height_m);
  m.eph = 0.8F;
  m.epv = 1.5F;
  return m;
}

// Angle of the rotation between two unit quaternions, rad.
inline double angleBetween(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return a.angularDistance(b);
}

}  // namespace vp::test
