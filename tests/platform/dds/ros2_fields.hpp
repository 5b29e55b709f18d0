// tests/platform/dds/ros2_fields: what vp_test_ros2_reader prints, expected from our own types.
//
// The reader (tests/platform/dds/ros2_reader/) prints every field of every ROS 2 sample it takes
// as "<topic>.<field path>=<value>" between "BEGIN <topic>" and "END <topic>" lines (doubles with
// 17, floats with 9 significant digits, integers in decimal). These helpers write the same lines
// for the values the sender holds, converted by hand from the documented mapping (docs/dds.md,
// "ROS 2 and Autoware": VehicleStateArray and Autoware's TrackedObjects), so that a test compares
// field by field what went out with what a ROS 2-style reader received. Shared by the publisher's
// test (tests/platform/dds) and the app's (tests/firmware_app).
#pragma once

#include <cstdint>
#include <cstdio>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "geodesy/geodesy.hpp"
#include "messages/messages.hpp"

namespace vp::test::ros2 {

// One message: field path -> printed value.
using Fields = std::map<std::string, std::string>;

// The reader's printing rules: doubles %.17g, floats %.9g, integers in decimal.
std::string text(double value);
std::string textF(float value);
std::string textI(long long value);

void putTime(Fields& f, const std::string& key, std::int64_t time_ns);
void putHeader(Fields& f, const std::string& topic, std::int64_t time_ns, const std::string& frame);
void putGeodetic(Fields& f, const std::string& key, const geodesy::GeodeticPoint& p);
void putPoint(Fields& f, const std::string& key, double x, double y, double z);
// One vp_msgs/VehicleState (every field) under key, e.g. "vehicle_states.vehicles.0".
void putState(Fields& f, const std::string& key, const messages::VehicleState& s);
// One Autoware TrackedObject under key, from the mapping table of docs/dds.md.
void putObject(Fields& f, const std::string& key, const messages::VehicleState& s);

// A whole frame's VehicleStateArray ("vehicle_states") and TrackedObjects ("tracked_objects").
Fields vehicleStateArray(std::int64_t time_ns, const std::string& frameId, std::uint32_t droneId,
                         std::span<const messages::VehicleState> states,
                         std::span<const std::uint32_t> removedTrackIds);
Fields trackedObjects(std::int64_t time_ns, const std::string& frameId,
                      std::span<const messages::VehicleState> states);

// The reader's output as one field map per message, in arrival order per topic.
std::map<std::string, std::vector<Fields>> parseReader(FILE* pipe);

// Every expected field is received with the same text, and nothing else is (gtest failures
// naming the field).
void expectSame(const Fields& received, const Fields& expected);

}  // namespace vp::test::ros2
