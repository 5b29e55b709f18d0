// map_export/traffic_tables: the traffic CSV files -> rows (see the header).
#include "traffic_tables.hpp"

#include <array>
#include <charconv>
#include <limits>
#include <string_view>
#include <utility>

#include "csv/csv_io.hpp"

namespace vp::map_export {
namespace {

constexpr int kFormatVersion = 1;
constexpr std::int64_t kMaxInt64 = std::numeric_limits<std::int64_t>::max();
constexpr std::int64_t kMaxCount = std::numeric_limits<std::uint32_t>::max();

constexpr std::array<const char*, 4> kEventKinds = {"gate_crossing", "wrong_way",
                                                    "box_junction_stop", "turning_movement"};

const std::vector<std::string> kCountColumns = {"period",    "start_ns", "end_ns", "gate_id",
                                                "direction", "type",     "count"};
const std::vector<std::string> kMovementColumns = {"period",       "start_ns",   "end_ns",
                                                   "from_gate_id", "to_gate_id", "count"};
const std::vector<std::string> kZoneColumns = {
    "period",       "start_ns",           "end_ns",
    "zone_id",      "vehicles_now",       "mean_vehicles",
    "max_vehicles", "queue_now_vehicles", "max_queue_vehicles",
    "queue_now_m",  "max_queue_m",        "dwell_count",
    "mean_dwell_s", "max_dwell_s"};
const std::vector<std::string> kLaneColumns = {"period",        "start_ns",     "end_ns",
                                               "lane_id",       "vehicles",     "mean_speed_mps",
                                               "p85_speed_mps", "max_speed_mps"};
const std::vector<std::string> kEventColumns = {
    "time_ns", "kind",      "track_id", "feature_id", "to_feature_id", "direction",
    "type",    "speed_mps", "east_m",   "north_m",    "lat_deg",       "lon_deg"};

// Reads the comment lines, the header and calls onRow(parser, line) for each row; throws
// csv::ReadError.
template <typename OnRow>
void readTable(const std::string& path, const std::vector<std::string>& columns, OnRow&& onRow) {
  const std::string text = csv::readWholeFile(path);
  const std::string header = csv::joinColumns(columns);
  bool haveHeader = false;
  csv::forEachLine(text, [&](int line, std::string_view row) {
    if (!haveHeader) {
      if (row.starts_with("#")) {
        // "# vp_firmware_app traffic_counts.csv format_version 1": refuse a later version.
        const std::size_t at = row.find("format_version");
        if (at != std::string_view::npos) {
          std::string_view rest = row.substr(at + std::string_view("format_version").size());
          while (!rest.empty() && (rest.front() == ' ' || rest.front() == ':')) {
            rest.remove_prefix(1);
          }
          int version = 0;
          const auto [end, error] =
              std::from_chars(rest.data(), rest.data() + rest.size(), version);
          if (error != std::errc() || version != kFormatVersion) {
            throw csv::ReadError{csv::location(path, line) + ":" + std::to_string(at + 1) +
                                 ": format_version: expected " + std::to_string(kFormatVersion) +
                                 ", got " + csv::quote(rest.substr(0, end - rest.data()))};
          }
        }
        return;
      }
      if (row != header) {
        throw csv::ReadError{csv::location(path, line) + ": header: expected '" + header +
                             "', got " + csv::quote(row)};
      }
      haveHeader = true;
      return;
    }
    const csv::RowParser parser(path, line, row, columns);
    onRow(parser, line);
  });
  if (!haveHeader) {
    throw csv::ReadError{path + ": no header line (expected '" + header + "')"};
  }
}

// 1-based character position of field i in its line.
int columnOf(const csv::RowParser& p, int i) {
  return static_cast<int>(p.field(i).data() - p.field(0).data()) + 1;
}

std::string idField(const csv::RowParser& p, int i) {
  const std::string_view id = p.field(i);
  if (id.empty()) {
    p.fail(i, "empty (a feature id of the site is required)");
  }
  return std::string(id);
}

PeriodFields period(const csv::RowParser& p) {
  PeriodFields f;
  f.period = static_cast<std::uint64_t>(p.integer(0, 0, kMaxInt64));
  f.start_ns = p.integer(1, std::numeric_limits<std::int64_t>::min(), kMaxInt64);
  f.end_ns = p.integer(2, std::numeric_limits<std::int64_t>::min(), kMaxInt64);
  if (f.end_ns <= f.start_ns) {
    p.fail(2, "must be after start_ns (" + std::to_string(f.start_ns) + "), got " +
                  std::string(p.field(2)));
  }
  return f;
}

std::optional<shape::VehicleType> vehicleType(std::string_view word) {
  for (int t = 0; t < shape::kVehicleTypeCount; ++t) {
    const auto type = static_cast<shape::VehicleType>(t);
    if (word == shape::toString(type)) {
      return type;
    }
  }
  return std::nullopt;
}

shape::VehicleType typeField(const csv::RowParser& p, int i) {
  const std::optional<shape::VehicleType> type = vehicleType(p.field(i));
  if (!type) {
    p.fail(i, "unknown vehicle type " + csv::quote(p.field(i)) +
                  " (estate, compact, sports, sedan, suv, van, large)");
  }
  return *type;
}

double nonNegative(const csv::RowParser& p, int i) {
  const double value = p.real<double>(i);
  if (value < 0.0) {
    p.fail(i, "must be >= 0, got " + std::string(p.field(i)));
  }
  return value;
}

std::uint64_t count(const csv::RowParser& p, int i) {
  return static_cast<std::uint64_t>(p.integer(i, 0, kMaxCount));
}

std::optional<double> optionalReal(const csv::RowParser& p, int i) {
  if (p.field(i).empty()) {
    return std::nullopt;
  }
  return p.real<double>(i);
}

}  // namespace

bool isEventKind(const std::string& kind) {
  for (const char* k : kEventKinds) {
    if (kind == k) {
      return true;
    }
  }
  return false;
}

bool readGateCounts(const std::string& path, TrafficTable<GateCountRow>* out, std::string* why) {
  return csv::readChecked(path, out, why, [&] {
    readTable(path, kCountColumns, [&](const csv::RowParser& p, int line) {
      GateCountRow r;
      r.period = period(p);
      r.gateId = idField(p, 3);
      r.idColumn = columnOf(p, 3);
      if (p.field(4) == "backward") {
        r.backward = true;
      } else if (p.field(4) != "forward") {
        p.fail(4, "expected forward or backward, got " + csv::quote(p.field(4)));
      }
      r.type = typeField(p, 5);
      r.count = count(p, 6);
      r.line = line;
      out->rows.push_back(std::move(r));
    });
  });
}

bool readMovements(const std::string& path, TrafficTable<MovementRow>* out, std::string* why) {
  return csv::readChecked(path, out, why, [&] {
    readTable(path, kMovementColumns, [&](const csv::RowParser& p, int line) {
      MovementRow r;
      r.period = period(p);
      r.fromGateId = idField(p, 3);
      r.toGateId = idField(p, 4);
      r.idColumn = columnOf(p, 3);
      r.toIdColumn = columnOf(p, 4);
      r.count = count(p, 5);
      r.line = line;
      out->rows.push_back(std::move(r));
    });
  });
}

bool readZones(const std::string& path, TrafficTable<ZoneRow>* out, std::string* why) {
  return csv::readChecked(path, out, why, [&] {
    readTable(path, kZoneColumns, [&](const csv::RowParser& p, int line) {
      ZoneRow r;
      r.period = period(p);
      r.zoneId = idField(p, 3);
      r.idColumn = columnOf(p, 3);
      r.vehiclesNow = count(p, 4);
      r.meanVehicles = nonNegative(p, 5);
      r.maxVehicles = count(p, 6);
      r.queueNow_vehicles = count(p, 7);
      r.maxQueue_vehicles = count(p, 8);
      r.queueNow_m = nonNegative(p, 9);
      r.maxQueue_m = nonNegative(p, 10);
      r.dwellCount = count(p, 11);
      r.meanDwell_s = nonNegative(p, 12);
      r.maxDwell_s = nonNegative(p, 13);
      r.line = line;
      out->rows.push_back(std::move(r));
    });
  });
}

bool readLanes(const std::string& path, TrafficTable<LaneRow>* out, std::string* why) {
  return csv::readChecked(path, out, why, [&] {
    readTable(path, kLaneColumns, [&](const csv::RowParser& p, int line) {
      LaneRow r;
      r.period = period(p);
      r.laneId = idField(p, 3);
      r.idColumn = columnOf(p, 3);
      r.vehicles = count(p, 4);
      r.meanSpeed_mps = nonNegative(p, 5);
      r.p85Speed_mps = nonNegative(p, 6);
      r.maxSpeed_mps = nonNegative(p, 7);
      r.line = line;
      out->rows.push_back(std::move(r));
    });
  });
}

bool readEvents(const std::string& path, TrafficTable<EventRow>* out, std::string* why) {
  return csv::readChecked(path, out, why, [&] {
    readTable(path, kEventColumns, [&](const csv::RowParser& p, int line) {
      EventRow r;
      r.time_ns = p.integer(0, std::numeric_limits<std::int64_t>::min(), kMaxInt64);
      r.kind = std::string(p.field(1));
      if (!isEventKind(r.kind)) {
        p.fail(1, "unknown event kind " + csv::quote(r.kind) +
                      " (gate_crossing, wrong_way, box_junction_stop, turning_movement)");
      }
      r.trackId = static_cast<std::uint32_t>(p.integer(2, 0, kMaxCount));
      r.featureId = idField(p, 3);
      r.toFeatureId = std::string(p.field(4));
      r.idColumn = columnOf(p, 3);
      r.toIdColumn = columnOf(p, 4);
      r.direction = std::string(p.field(5));
      if (!r.direction.empty() && r.direction != "forward" && r.direction != "backward") {
        p.fail(5, "expected forward, backward or empty, got " + csv::quote(r.direction));
      }
      if (!p.field(6).empty()) {
        r.type = typeField(p, 6);
      }
      r.speed_mps = p.real<double>(7);
      r.east_m = p.real<double>(8);
      r.north_m = p.real<double>(9);
      r.lat_deg = optionalReal(p, 10);
      r.lon_deg = optionalReal(p, 11);
      if (r.lat_deg.has_value() != r.lon_deg.has_value()) {
        p.fail(r.lat_deg ? 11 : 10, "lat_deg and lon_deg must both be given or both empty");
      }
      if (r.lat_deg && (*r.lat_deg < -90.0 || *r.lat_deg > 90.0)) {
        p.fail(10, "must be in [-90, 90], got " + std::string(p.field(10)));
      }
      if (r.lon_deg && (*r.lon_deg < -180.0 || *r.lon_deg > 180.0)) {
        p.fail(11, "must be in [-180, 180], got " + std::string(p.field(11)));
      }
      r.line = line;
      out->rows.push_back(std::move(r));
    });
  });
}

}  // namespace vp::map_export
