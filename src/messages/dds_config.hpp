// messages/dds_config: the typed `dds:` configuration section (domain, partition, QoS
// profiles per topic, publication rates, occupancy grid, DDS Security files).
//
// Contract: plain values, no DDS types; platform/dds turns them into QoS objects. The defaults
// are the documented ones (docs/dds.md, "QoS defaults") chosen for a lossy radio link at
// 10 Hz. parseDdsConfig() reads the `dds:` map of a YAML document and throws DdsConfigError
// naming the source and the full key path ("site.yaml: dds.qos.vehicle_state.history_depth:
// must be in [1, 1000], got 0"); unknown keys are returned as warnings. Relative security file
// paths are resolved against baseDir. This section lives here until src/config's AppConfig
// takes it over (it will become AppConfig::dds with the same keys). Start-up only.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace vp::messages {

class DdsConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

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

struct SecurityConfig {
  bool enabled = false;
  // Debian's libddsc0debian installs the plugins outside the linker path.
  std::string pluginDir = "/usr/lib/x86_64-linux-gnu/libddsc0debian";
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

struct DdsConfig {
  bool enabled = true;
  std::uint32_t domainId = 0;
  std::string partition = "vp";  // publisher/subscriber partition
  std::uint32_t droneId = 1;
  std::string topicPrefix = "vp";  // topics: <prefix>/vehicle_state, /drone_status, /occupancy
  QosProfile vehicleState = defaultVehicleStateQos();
  QosProfile droneStatus = defaultDroneStatusQos();
  QosProfile occupancy = defaultOccupancyQos();
  double statusRate_hz = 1.0;
  double occupancyRate_hz = 2.0;  // 0 = do not publish the grid
  OccupancyGridSpec grid{};
  SecurityConfig security{};

  static QosProfile defaultVehicleStateQos();
  static QosProfile defaultDroneStatusQos();
  static QosProfile defaultOccupancyQos();
};

struct DdsConfigResult {
  DdsConfig config;
  std::vector<std::string> warnings;
};

// Parses the `dds` map of the document (the whole document may hold other sections; an
// absent `dds` section gives the defaults). Throws DdsConfigError.
DdsConfigResult parseDdsConfig(const std::string& yamlText, const std::string& sourceName,
                               const std::string& baseDir);
DdsConfigResult loadDdsConfig(const std::string& path);

const char* toString(Reliability reliability);
const char* toString(Durability durability);

}  // namespace vp::messages
