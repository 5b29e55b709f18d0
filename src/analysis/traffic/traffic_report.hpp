// traffic/traffic_report: what the traffic analysis reports — one statistics record per period
// (gate counts by direction and type, turning movements, per-zone occupancy and queue length,
// per-lane speeds, dwell of stopped vehicles) and the events it sees as they happen (gate
// crossings, wrong-way driving, a stop inside a box junction).
//
// Contract: plain fixed-size value types, no allocation, copied freely. Arrays are sized by the
// kMax* limits; the *Count members say how many entries are valid, in the order of the site's
// features (gates, zones, lanes as the site file lists them). Units follow the names. Outputs
// (CSV, DDS, GeoJSON) are filled from these types; nothing here knows how they are written.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include <Eigen/Core>

#include "shape/vehicle_model.hpp"

namespace vp::traffic {

constexpr std::size_t kMaxReportGates = 32;
constexpr std::size_t kMaxReportZones = 32;
constexpr std::size_t kMaxReportLanes = 64;
constexpr std::size_t kReportTypeCount = static_cast<std::size_t>(shape::kVehicleTypeCount);

// Vehicles that crossed one gate in the period, by direction (0 forward, 1 backward; see
// GateCrossing) and type.
struct GateCountRecord {
  std::uint32_t gateIndex = 0;  // index among the site's gates
  std::array<std::array<std::uint32_t, kReportTypeCount>, 2> byDirectionAndType{};
};

// A zone's state over the period. A vehicle is in a zone when its footprint centre is; it is
// stopped below TrafficAnalyzerOptions' stop speed. The queue is the stopped vehicles in the
// zone; its length in metres runs from the zone's downstream end (along its lane, when the zone
// names one) to the far end of the last queued vehicle.
struct ZoneRecord {
  std::uint32_t zoneIndex = 0;
  std::uint32_t vehiclesNow = 0;  // at the period's end
  double meanVehicles = 0.0;      // time average over the period
  std::uint32_t maxVehicles = 0;
  std::uint32_t queueNow_vehicles = 0;  // at the period's end
  std::uint32_t maxQueue_vehicles = 0;
  double queueNow_m = 0.0;
  double maxQueue_m = 0.0;
  // Stopped vehicles that left the zone or started again in the period: how long they stood.
  std::uint32_t dwellCount = 0;
  double meanDwell_s = 0.0;
  double maxDwell_s = 0.0;
};

// Speeds of the vehicles driving along one lane in the period (one sample per vehicle: its mean
// speed while on the lane; stopped vehicles included).
struct LaneRecord {
  std::uint32_t laneIndex = 0;
  std::uint32_t vehicles = 0;
  double meanSpeed_mps = 0.0;
  double p85Speed_mps = 0.0;  // 85th percentile (the engineer's design speed)
  double maxSpeed_mps = 0.0;
};

// One period's statistics [start_ns, end_ns).
struct TrafficStatistics {
  std::uint64_t sequence = 0;  // period number since start-up, from 0
  std::int64_t start_ns = 0;
  std::int64_t end_ns = 0;
  std::size_t gateCount = 0;
  std::array<GateCountRecord, kMaxReportGates> gates{};
  // Turning movements of vehicles that ended in the period: [from gate][to gate], all types.
  std::array<std::array<std::uint32_t, kMaxReportGates>, kMaxReportGates> movements{};
  std::size_t zoneCount = 0;
  std::array<ZoneRecord, kMaxReportZones> zones{};
  std::size_t laneCount = 0;
  std::array<LaneRecord, kMaxReportLanes> lanes{};
  std::uint32_t wrongWayEvents = 0;
  std::uint32_t boxJunctionStops = 0;
};

enum class TrafficEventKind : std::uint8_t {
  GateCrossing = 0,     // featureIndex: the gate; direction 0 forward, 1 backward
  WrongWay = 1,         // featureIndex: the lane driven against its direction
  BoxJunctionStop = 2,  // featureIndex: the box-junction zone the vehicle stopped in
  TurningMovement = 3,  // featureIndex: origin gate; toFeatureIndex: destination gate
};
const char* toString(TrafficEventKind kind);  // "gate_crossing", "wrong_way", ...

struct TrafficEvent {
  TrafficEventKind kind = TrafficEventKind::GateCrossing;
  std::int64_t time_ns = 0;
  std::uint32_t trackId = 0;
  std::uint32_t featureIndex = 0;
  std::uint32_t toFeatureIndex = 0;  // TurningMovement only
  std::uint8_t direction = 0;        // GateCrossing only
  shape::VehicleType type = shape::VehicleType::Sedan;
  double speed_mps = 0.0;
  Eigen::Vector2d positionEnu_m{0.0, 0.0};
};

}  // namespace vp::traffic
