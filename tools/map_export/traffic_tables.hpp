// map_export/traffic_tables: offline readers of the traffic analysis' CSV files
// (traffic_counts.csv, traffic_movements.csv, traffic_zones.csv, traffic_lanes.csv,
// traffic_events.csv; docs/traffic.md), for vp_map_export.
//
// Contract: each reader takes the whole file: optional `#` comment lines first (the writer's
// "# vp_firmware_app <file> format_version 1"; a format_version other than 1 is refused), then
// the header, which must be exactly the file's documented columns, then one row per line. Every
// field is checked (integers, finite numbers, direction forward|backward, type one of
// shape::toString's words, a period's end after its start) and the first problem is returned as
// "<file>:<line>:<column>: <column name>: <problem>" (column = 1-based character position);
// nothing is thrown. Feature ids are kept as text: whether they name features of the site is
// the caller's check (it has the site), with the row's line kept for its message.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "shape/vehicle_model.hpp"

namespace vp::map_export {

// What every statistics row starts with.
struct PeriodFields {
  std::uint64_t period = 0;
  std::int64_t start_ns = 0;
  std::int64_t end_ns = 0;  // > start_ns
};

struct GateCountRow {
  PeriodFields period;
  std::string gateId;
  bool backward = false;  // direction: forward | backward
  shape::VehicleType type = shape::VehicleType::Sedan;
  std::uint64_t count = 0;
  int line = 0;
  int idColumn = 0;  // 1-based character position of gate_id in the line
};

struct MovementRow {
  PeriodFields period;
  std::string fromGateId;
  std::string toGateId;
  std::uint64_t count = 0;
  int line = 0;
  int idColumn = 0;    // of from_gate_id
  int toIdColumn = 0;  // of to_gate_id
};

struct ZoneRow {
  PeriodFields period;
  std::string zoneId;
  std::uint64_t vehiclesNow = 0;
  double meanVehicles = 0.0;
  std::uint64_t maxVehicles = 0;
  std::uint64_t queueNow_vehicles = 0;
  std::uint64_t maxQueue_vehicles = 0;
  double queueNow_m = 0.0;
  double maxQueue_m = 0.0;
  std::uint64_t dwellCount = 0;
  double meanDwell_s = 0.0;
  double maxDwell_s = 0.0;
  int line = 0;
  int idColumn = 0;  // of zone_id
};

struct LaneRow {
  PeriodFields period;
  std::string laneId;
  std::uint64_t vehicles = 0;
  double meanSpeed_mps = 0.0;
  double p85Speed_mps = 0.0;
  double maxSpeed_mps = 0.0;
  int line = 0;
  int idColumn = 0;  // of lane_id
};

struct EventRow {
  std::int64_t time_ns = 0;
  std::string kind;  // gate_crossing, wrong_way, box_junction_stop, turning_movement
  std::uint32_t trackId = 0;
  std::string featureId;
  std::string toFeatureId;                 // may be empty
  std::string direction;                   // forward | backward | empty
  std::optional<shape::VehicleType> type;  // empty field: none
  double speed_mps = 0.0;
  double east_m = 0.0;
  double north_m = 0.0;
  std::optional<double> lat_deg;  // both given or both empty
  std::optional<double> lon_deg;
  int line = 0;
  int idColumn = 0;    // of feature_id
  int toIdColumn = 0;  // of to_feature_id
};

// The documented event kinds (traffic::TrafficEventKind's words).
bool isEventKind(const std::string& kind);

template <typename Row>
struct TrafficTable {
  std::string path;
  std::vector<Row> rows;  // file order
};

bool readGateCounts(const std::string& path, TrafficTable<GateCountRow>* out, std::string* why);
bool readMovements(const std::string& path, TrafficTable<MovementRow>* out, std::string* why);
bool readZones(const std::string& path, TrafficTable<ZoneRow>* out, std::string* why);
bool readLanes(const std::string& path, TrafficTable<LaneRow>* out, std::string* why);
bool readEvents(const std::string& path, TrafficTable<EventRow>* out, std::string* why);

}  // namespace vp::map_export
