// config/dds_section: the `dds:` section (docs/configuration.md, docs/dds.md) into
// config::DdsConfig.
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>

#include "config/sections.hpp"
#include "rig_config/section_reader.hpp"

namespace vp::config::detail {
namespace {

namespace fs = std::filesystem;

// DDS domain ids: Cyclone accepts 0..232 (the RTPS port formula with the default port mapping).
const Range kDomainIdRange = Range::closed(0.0, 232.0);
const Range kDroneIdRange = Range::closed(0.0, 4294967295.0);
// How long a reliable write may block when the writer's history is full: beyond 10 s the loop
// would miss many frames, which is never wanted.
const Range kMaxBlockingRangeS = Range::closed(0.0, 10.0);
const Range kHistoryDepthRange = Range::closed(1.0, 1000.0);
// Deadline, lifespan, liveliness lease: 0 = off; an hour is far beyond any useful setting.
const Range kQosDurationRangeS = Range::closed(0.0, 3600.0);
const Range kStatusRateRange_hz = Range::closed(0.01, 100.0);
const Range kOccupancyRateRange_hz = Range::closed(0.0, 100.0);
const Range kGridOriginRange_m = Range::closed(-1e5, 1e5);
const Range kGridResolutionRange_m = Range::closed(0.05, 10.0);
// 2048 x 2048 cells is the IDL's bound on the grid (kMaxOccupancyCells).
const Range kGridCellsRange = Range::closed(1.0, 2048.0);

constexpr std::string_view kReliabilityNames = "reliable, best_effort";
constexpr std::string_view kDurabilityNames = "volatile, transient_local";
constexpr std::string_view kTelemetrySourceNames = "none, ardupilot, px4";

std::optional<Reliability> reliabilityFromString(const std::string& text) {
  if (text == "reliable") {
    return Reliability::Reliable;
  }
  if (text == "best_effort") {
    return Reliability::BestEffort;
  }
  return std::nullopt;
}

std::optional<Durability> durabilityFromString(const std::string& text) {
  if (text == "volatile") {
    return Durability::Volatile;
  }
  if (text == "transient_local") {
    return Durability::TransientLocal;
  }
  return std::nullopt;
}

std::optional<TelemetrySource> telemetrySourceFromString(const std::string& text) {
  for (const TelemetrySource source :
       {TelemetrySource::None, TelemetrySource::ArduPilot, TelemetrySource::Px4}) {
    if (text == toString(source)) {
      return source;
    }
  }
  return std::nullopt;
}

QosProfile readQos(MapReader section, const QosProfile& defaults) {
  QosProfile qos;
  qos.reliability = section.choice<Reliability>("reliability", reliabilityFromString,
                                                kReliabilityNames, defaults.reliability);
  qos.maxBlocking_s = section.number("max_blocking_s", kMaxBlockingRangeS, defaults.maxBlocking_s);
  qos.durability = section.choice<Durability>("durability", durabilityFromString, kDurabilityNames,
                                              defaults.durability);
  qos.historyDepth = section.integer("history_depth", kHistoryDepthRange, defaults.historyDepth);
  qos.deadline_s = section.number("deadline_s", kQosDurationRangeS, defaults.deadline_s);
  qos.lifespan_s = section.number("lifespan_s", kQosDurationRangeS, defaults.lifespan_s);
  qos.livelinessLease_s =
      section.number("liveliness_lease_s", kQosDurationRangeS, defaults.livelinessLease_s);
  section.warnUnknownKeys();
  return qos;
}

// A security document: required and checked to exist when security is enabled (Cyclone would
// only say "dds_create_participant: Error"), read for its type and resolved otherwise.
std::string readSecurityFile(MapReader& section, std::string_view key, bool enabled,
                             const std::string& baseDir) {
  if (!section.has(key)) {
    if (enabled) {
      section.fail(key, "missing (required when dds.security.enabled is true)");
    }
    return "";
  }
  const std::string path = resolvePath(section.text(key, kRequired), baseDir);
  std::error_code error;
  if (enabled && !fs::is_regular_file(path, error)) {
    section.fail(key, "file not found: " + path);
  }
  return path;
}

SecurityConfig readSecurity(MapReader section, const std::string& baseDir) {
  const SecurityConfig defaults;
  SecurityConfig security;
  security.enabled = section.boolean("enabled", defaults.enabled);
  security.pluginDir = section.text("plugin_dir", defaults.pluginDir);
  std::error_code error;
  if (security.enabled &&
      !fs::is_regular_file(fs::path(security.pluginDir) / "libdds_security_auth.so", error)) {
    section.fail("plugin_dir",
                 "no DDS Security plugins (libdds_security_auth.so) in " + security.pluginDir);
  }
  security.identityCa = readSecurityFile(section, "identity_ca", security.enabled, baseDir);
  security.identityCertificate =
      readSecurityFile(section, "identity_certificate", security.enabled, baseDir);
  security.privateKey = readSecurityFile(section, "private_key", security.enabled, baseDir);
  security.permissionsCa = readSecurityFile(section, "permissions_ca", security.enabled, baseDir);
  security.governance = readSecurityFile(section, "governance", security.enabled, baseDir);
  security.permissions = readSecurityFile(section, "permissions", security.enabled, baseDir);
  section.warnUnknownKeys();
  return security;
}

TelemetryConfig readTelemetry(MapReader section) {
  const TelemetryConfig defaults;
  TelemetryConfig telemetry;
  telemetry.source = section.choice<TelemetrySource>("source", telemetrySourceFromString,
                                                     kTelemetrySourceNames, defaults.source);
  telemetry.domainId = section.uint32("domain_id", kDomainIdRange, defaults.domainId);
  telemetry.ardupilotGeoPoseTopic =
      section.text("ardupilot_geopose_topic", defaults.ardupilotGeoPoseTopic);
  telemetry.px4AttitudeTopic = section.text("px4_attitude_topic", defaults.px4AttitudeTopic);
  telemetry.px4GlobalPositionTopic =
      section.text("px4_global_position_topic", defaults.px4GlobalPositionTopic);
  telemetry.ardupilotAltitudeOffset_m = section.number(
      "ardupilot_altitude_offset_m", kAltitudeOffsetRange_m, defaults.ardupilotAltitudeOffset_m);
  telemetry.historyDepth =
      section.integer("history_depth", kHistoryDepthRange, defaults.historyDepth);
  section.warnUnknownKeys();
  return telemetry;
}

const Range kStationarySpeedRange_mps = Range::closed(0.0, 10.0);

// A ROS name's tokens: letters, digits and underscores, not starting with a digit, joined by
// single '/' (ROS 2 "Topic and Service name mapping to DDS").
bool isRosName(std::string_view name) {
  if (name.empty() || name.front() == '/' || name.back() == '/') {
    return false;
  }
  bool tokenStart = true;
  for (const char c : name) {
    if (c == '/') {
      if (tokenStart) {
        return false;  // "//"
      }
      tokenStart = true;
      continue;
    }
    const bool digit = c >= '0' && c <= '9';
    const bool letter = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_';
    if (!(digit || letter) || (tokenStart && digit)) {
      return false;
    }
    tokenStart = false;
  }
  return true;
}

Ros2Config readRos2(MapReader section) {
  const Ros2Config defaults;
  Ros2Config ros2;
  ros2.enabled = section.boolean("enabled", defaults.enabled);
  std::string ns = section.text("namespace", defaults.topicNamespace);
  if (!ns.empty() && ns.front() == '/') {
    ns.erase(0, 1);  // "/vp" and "vp" name the same namespace
  }
  if (!ns.empty() && !isRosName(ns)) {
    section.fail("namespace",
                 "not a ROS namespace (letters, digits, _ in tokens joined by /): '" + ns + "'");
  }
  ros2.topicNamespace = ns;
  ros2.frameId = section.text("frame_id", defaults.frameId);
  if (ros2.frameId.empty()) {
    section.fail("frame_id", "must not be empty");
  }
  section.warnUnknownKeys();
  return ros2;
}

AutowareConfig readAutoware(MapReader section) {
  const AutowareConfig defaults;
  AutowareConfig autoware;
  autoware.enabled = section.boolean("enabled", defaults.enabled);
  autoware.topic = section.text("topic", defaults.topic);
  if (autoware.topic.size() < 2 || autoware.topic.front() != '/' ||
      !isRosName(std::string_view(autoware.topic).substr(1))) {
    section.fail("topic", "not an absolute ROS topic name (/a/b, letters, digits, _): '" +
                              autoware.topic + "'");
  }
  autoware.frameId = section.text("frame_id", defaults.frameId);
  if (autoware.frameId.empty()) {
    section.fail("frame_id", "must not be empty");
  }
  autoware.stationarySpeed_mps = section.number("stationary_speed_mps", kStationarySpeedRange_mps,
                                                defaults.stationarySpeed_mps);
  section.warnUnknownKeys();
  return autoware;
}

}  // namespace

DdsConfig readDds(MapReader section, const std::string& baseDir) {
  const DdsConfig defaults;
  DdsConfig dds;
  dds.enabled = section.boolean("enabled", defaults.enabled);
  dds.domainId = section.uint32("domain_id", kDomainIdRange, defaults.domainId);
  dds.partition = section.text("partition", defaults.partition);
  dds.droneId = section.uint32("drone_id", kDroneIdRange, defaults.droneId);
  dds.topicPrefix = section.text("topic_prefix", defaults.topicPrefix);
  dds.statusRate_hz = section.number("status_rate_hz", kStatusRateRange_hz, defaults.statusRate_hz);
  dds.occupancyRate_hz =
      section.number("occupancy_rate_hz", kOccupancyRateRange_hz, defaults.occupancyRate_hz);
  {
    MapReader qos = section.section("qos");
    dds.vehicleState = readQos(qos.section("vehicle_state"), defaults.vehicleState);
    dds.droneStatus = readQos(qos.section("drone_status"), defaults.droneStatus);
    dds.occupancy = readQos(qos.section("occupancy"), defaults.occupancy);
    dds.trafficStatistics = readQos(qos.section("traffic_statistics"), defaults.trafficStatistics);
    dds.trafficEvents = readQos(qos.section("traffic_events"), defaults.trafficEvents);
    qos.warnUnknownKeys();
  }
  {
    MapReader grid = section.section("occupancy_grid");
    dds.grid.originEast_m =
        grid.number("origin_east_m", kGridOriginRange_m, defaults.grid.originEast_m);
    dds.grid.originNorth_m =
        grid.number("origin_north_m", kGridOriginRange_m, defaults.grid.originNorth_m);
    dds.grid.resolution_m =
        grid.number("resolution_m", kGridResolutionRange_m, defaults.grid.resolution_m);
    dds.grid.rows = grid.uint32("rows", kGridCellsRange, defaults.grid.rows);
    dds.grid.cols = grid.uint32("cols", kGridCellsRange, defaults.grid.cols);
    grid.warnUnknownKeys();
  }
  dds.security = readSecurity(section.section("security"), baseDir);
  dds.telemetry = readTelemetry(section.section("telemetry"));
  {
    MapReader native = section.section("native");
    dds.native.enabled = native.boolean("enabled", defaults.native.enabled);
    native.warnUnknownKeys();
  }
  dds.ros2 = readRos2(section.section("ros2"));
  dds.autoware = readAutoware(section.section("autoware"));
  section.warnUnknownKeys();
  return dds;
}

}  // namespace vp::config::detail
