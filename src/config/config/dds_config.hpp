// config/dds_config: the typed `dds:` section of the application configuration (domain,
// partition, topic prefix, QoS profile per topic, publication rates, occupancy grid, DDS
// Security files, and the flight stack's DDS telemetry topics).
//
// Contract: plain values, no DDS types; platform/dds turns them into QoS objects and entities.
// The defaults are the documented ones (docs/configuration.md, docs/dds.md "QoS defaults"),
// chosen for a lossy radio link at 10 Hz. config.cpp reads the section (as AppConfig::dds, or
// alone with parseDdsSection() for tools such as the roadside-unit subscriber) and reports a
// malformed key as ConfigError naming the file and the full key path
// ("site.yaml: dds.qos.vehicle_state.history_depth: must be in [1, 1000], got 0"). Relative
// security file paths are resolved against the configuration file's directory and, when
// security is enabled, must exist. Start-up only.
#pragma once

#include <cstdint>
#include <string>

namespace vp::config {

enum class Reliability : std::uint8_t { BestEffort, Reliable };
enum class Durability : std::uint8_t { Volatile, TransientLocal };

// One topic's QoS. A duration of 0 means "infinite" (the policy is off).
struct QosProfile {
  Reliability reliability = Reliability::Reliable;
  double maxBlocking_s = 0.01;  // how long a reliable write may block on a full queue
  Durability durability = Durability::Volatile;
  std::int32_t historyDepth = 1;   // KEEP_LAST depth per instance
  double deadline_s = 0.0;         // expected maximum period between samples of an instance
  double lifespan_s = 0.0;         // samples older than this are dropped, not delivered
  double livelinessLease_s = 0.0;  // automatic liveliness lease
};

// Where Debian's libddsc0debian installs Cyclone's security plugins (outside the linker path)
// for the architecture built for: /usr/lib/<multiarch triplet>/libddsc0debian.
const char* defaultDdsPluginDir();

struct SecurityConfig {
  bool enabled = false;
  std::string pluginDir = defaultDdsPluginDir();
  std::string identityCa;           // PEM file
  std::string identityCertificate;  // PEM file
  std::string privateKey;           // PEM file
  std::string permissionsCa;        // PEM file
  std::string governance;           // signed S/MIME (.p7s)
  std::string permissions;          // signed S/MIME (.p7s)
};

struct OccupancyGridSpec {
  double originEast_m = -50.0;  // south-west corner of the grid in the world ENU frame
  double originNorth_m = -50.0;
  double resolution_m = 0.5;
  std::uint32_t rows = 200;
  std::uint32_t cols = 200;
};

// Which flight stack's ROS 2 bridge the drone pose comes from over DDS (docs/telemetry.md).
enum class TelemetrySource : std::uint8_t {
  None,       // pose from elsewhere (MAVLink, a recording)
  ArduPilot,  // ArduPilot DDS: geographic_msgs/GeoPoseStamped
  Px4,        // PX4 uXRCE-DDS: px4_msgs/VehicleAttitude + VehicleGlobalPosition
};

struct TelemetryConfig {
  TelemetrySource source = TelemetrySource::None;
  // The bridge's ROS_DOMAIN_ID; ROS 2 uses no partition and no DDS Security by default.
  std::uint32_t domainId = 0;
  std::string ardupilotGeoPoseTopic = "rt/ap/geopose/filtered";
  std::string px4AttitudeTopic = "rt/fmu/out/vehicle_attitude";
  std::string px4GlobalPositionTopic = "rt/fmu/out/vehicle_global_position";
  // Added to ArduPilot's GeoPose altitude to give the ellipsoidal height: ArduPilot fills it
  // with its absolute (AMSL) altitude, so set the geoid undulation N of the site here.
  double ardupilotAltitudeOffset_m = 0.0;
  std::int32_t historyDepth = 8;  // KEEP_LAST depth of each telemetry reader
};

// The native topics (vp_perception.idl, keyed per track, in `partition`): what the roadside
// units read, with a DDS instance per track (disposed when the track is deleted).
struct NativeTopicsConfig {
  bool enabled = true;
};

// The same outputs as ROS 2 topics (docs/dds.md, "ROS 2 and Autoware"): DDS topics
// rt/<namespace>/vehicle_states (vp_msgs/msg/VehicleStateArray, one per frame),
// rt/<namespace>/drone_status (vp_msgs/msg/DroneStatus), rt/<namespace>/occupancy
// (nav_msgs/msg/OccupancyGrid), in the default partition, with the QoS profiles above.
struct Ros2Config {
  bool enabled = true;
  std::string topicNamespace = "vp";  // ROS namespace of the topics, without leading '/'
  std::string frameId = "map";        // header.frame_id: the world ENU frame at the origin
};

// Autoware's tracked objects (autoware_perception_msgs/msg/TrackedObjects, one per frame):
// Autoware's map frame must be our world ENU frame, i.e. its map origin the configured origin.
struct AutowareConfig {
  bool enabled = false;
  std::string topic = "/perception/object_recognition/tracking/objects";  // absolute ROS name
  std::string frameId = "map";
  double stationarySpeed_mps = 0.5;  // |speed| below it: is_stationary
};

struct DdsConfig {
  bool enabled = true;
  std::uint32_t domainId = 0;
  std::string partition = "vp";  // publisher/subscriber partition
  std::uint32_t droneId = 1;
  std::string topicPrefix = "vp";  // topics: <prefix>/vehicle_state, /drone_status, /occupancy
  QosProfile vehicleState = defaultVehicleStateQos();
  QosProfile droneStatus = defaultDroneStatusQos();
  QosProfile occupancy = defaultOccupancyQos();
  // The traffic analysis' outputs (docs/dds.md, "Traffic"): <prefix>/traffic_statistics and
  // <prefix>/traffic_events, and their ROS 2 topics.
  QosProfile trafficStatistics = defaultTrafficStatisticsQos();
  QosProfile trafficEvents = defaultTrafficEventsQos();
  double statusRate_hz = 1.0;
  double occupancyRate_hz = 2.0;  // 0 = do not publish the grid
  OccupancyGridSpec grid{};
  SecurityConfig security{};
  TelemetryConfig telemetry{};
  NativeTopicsConfig native{};
  Ros2Config ros2{};
  AutowareConfig autoware{};

  static QosProfile defaultVehicleStateQos();
  static QosProfile defaultDroneStatusQos();
  static QosProfile defaultOccupancyQos();
  static QosProfile defaultTrafficStatisticsQos();
  static QosProfile defaultTrafficEventsQos();
};

const char* toString(Reliability reliability);
const char* toString(Durability durability);
const char* toString(TelemetrySource source);

}  // namespace vp::config
