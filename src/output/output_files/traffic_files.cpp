#include "output_files/traffic_files.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <span>

#include "shape/vehicle_model.hpp"

namespace vp::output_files {
namespace {

// Longest row of each file without its feature ids: 16 numeric fields of at most 24 characters
// each and the words, with room to spare.
constexpr std::size_t kRowBytesWithoutIds = 512;
// Decimals: metres and speeds to the millimetre (per second), seconds and mean counts to the
// millisecond (thousandth), WGS84 degrees to 1e-9 (0.1 mm).
constexpr int kMetreDecimals = 3;
constexpr int kDegreeDecimals = 9;

constexpr std::array<const char*, kTrafficFileCount> kNames{
    "traffic_counts.csv", "traffic_movements.csv", "traffic_zones.csv", "traffic_lanes.csv",
    "traffic_events.csv"};
constexpr std::array<const char*, kTrafficFileCount> kColumns{
    "period,start_ns,end_ns,gate_id,direction,type,count",
    "period,start_ns,end_ns,from_gate_id,to_gate_id,count",
    "period,start_ns,end_ns,zone_id,vehicles_now,mean_vehicles,max_vehicles,queue_now_vehicles,"
    "max_queue_vehicles,queue_now_m,max_queue_m,dwell_count,mean_dwell_s,max_dwell_s",
    "period,start_ns,end_ns,lane_id,vehicles,mean_speed_mps,p85_speed_mps,max_speed_mps",
    "time_ns,kind,track_id,feature_id,to_feature_id,direction,type,speed_mps,east_m,north_m,"
    "lat_deg,lon_deg"};

// The file's first line: "# vp_firmware_app traffic_counts.csv format_version 1".
std::string commentLine(TrafficFile file) {
  return std::string("# vp_firmware_app ") + kNames[static_cast<std::size_t>(file)] +
         " format_version " + std::to_string(kTrafficFormatVersion);
}

// Formats one row into a preallocated buffer; any overflow or non-finite number is remembered
// and reported by the caller (no allocation, no exception).
class RowFormatter {
 public:
  explicit RowFormatter(std::span<char> buffer) : buffer_(buffer) {}

  RowFormatter& text(std::string_view value) {
    if (size_ + value.size() > buffer_.size()) {
      overflow_ = true;
      return *this;
    }
    std::copy(value.begin(), value.end(), buffer_.begin() + static_cast<std::ptrdiff_t>(size_));
    size_ += value.size();
    return *this;
  }
  RowFormatter& comma() { return text(","); }
  template <typename Integer>
  RowFormatter& integer(Integer value) {
    char* begin = buffer_.data() + size_;
    const auto result = std::to_chars(begin, buffer_.data() + buffer_.size(), value);
    if (result.ec != std::errc{}) {
      overflow_ = true;
      return *this;
    }
    size_ = static_cast<std::size_t>(result.ptr - buffer_.data());
    return *this;
  }
  RowFormatter& fixed(double value, int decimals) {
    if (!std::isfinite(value)) {
      invalid_ = true;
      return *this;
    }
    // -0.000 reads as a surprise in a spreadsheet; print 0.000.
    if (std::abs(value) < 0.5 * std::pow(10.0, -decimals)) {
      value = 0.0;
    }
    char* begin = buffer_.data() + size_;
    const auto result = std::to_chars(begin, buffer_.data() + buffer_.size(), value,
                                      std::chars_format::fixed, decimals);
    if (result.ec != std::errc{}) {
      overflow_ = true;
      return *this;
    }
    size_ = static_cast<std::size_t>(result.ptr - buffer_.data());
    return *this;
  }
  // The row's size with its line break, or the status of what went wrong.
  TrafficWriteStatus finish(std::size_t* size) {
    text("\n");
    if (invalid_) {
      return TrafficWriteStatus::InvalidValue;
    }
    if (overflow_) {
      return TrafficWriteStatus::RowTooLong;
    }
    *size = size_;
    return TrafficWriteStatus::Ok;
  }

 private:
  std::span<char> buffer_;
  std::size_t size_ = 0;
  bool overflow_ = false;
  bool invalid_ = false;
};

// period,start_ns,end_ns, (the first three columns of the statistics files)
void periodColumns(RowFormatter& row, const traffic::TrafficStatistics& s) {
  row.integer(s.sequence).comma().integer(s.start_ns).comma().integer(s.end_ns).comma();
}

const char* typeName(shape::VehicleType type) {
  const int t = static_cast<int>(type);
  return t >= 0 && t < shape::kVehicleTypeCount ? shape::toString(type) : nullptr;
}

}  // namespace

const char* fileName(TrafficFile file) {
  return kNames[static_cast<std::size_t>(file)];
}

const char* trafficColumns(TrafficFile file) {
  return kColumns[static_cast<std::size_t>(file)];
}

TrafficFeatureIds trafficFeatureIds(const site::Site& site) {
  TrafficFeatureIds ids;
  for (const site::Feature& feature : site.features()) {
    if (feature.kind == site::FeatureKind::Gate) {
      ids.gates.push_back(feature.id);
    } else if (feature.kind == site::FeatureKind::Zone) {
      ids.zones.push_back(feature.id);
    } else if (feature.kind == site::FeatureKind::Lane) {
      ids.lanes.push_back(feature.id);
    }
  }
  return ids;
}

const char* toString(TrafficWriteStatus status) {
  switch (status) {
    case TrafficWriteStatus::Ok:
      return "ok";
    case TrafficWriteStatus::NotOpen:
      return "not open";
    case TrafficWriteStatus::UnknownFeature:
      return "feature index beyond the site's features";
    case TrafficWriteStatus::InvalidValue:
      return "value not finite";
    case TrafficWriteStatus::RowTooLong:
      return "row longer than the row buffer";
    case TrafficWriteStatus::WriteFailed:
      return "write failed (disk full or I/O error)";
  }
  return "unknown";
}

TrafficFilesWriter::~TrafficFilesWriter() = default;

bool TrafficFilesWriter::open(const std::string& dir, const TrafficFeatureIds& ids,
                              const geodesy::LocalFrame& frame, std::string* why) {
  if (open_) {
    return csv::failWith(why, csv::shortened(dir) + ": traffic files already open");
  }
  std::size_t longestId = 0;
  for (const std::vector<std::string>* list : {&ids.gates, &ids.zones, &ids.lanes}) {
    for (const std::string& id : *list) {
      if (id.find_first_of(",\n\r\"") != std::string::npos) {
        return csv::failWith(why, "traffic files: feature id " + csv::quote(id) +
                                      " holds a comma, quote or line break (not allowed in CSV)");
      }
      longestId = std::max(longestId, id.size());
    }
  }
  const std::size_t rowBytes = kRowBytesWithoutIds + 2 * longestId;
  const std::string base = dir.empty() || dir.back() == '/' ? dir : dir + "/";
  for (std::size_t f = 0; f < kTrafficFileCount; ++f) {
    const auto file = static_cast<TrafficFile>(f);
    if (!files_[f].open(base + kNames[f], rowBytes, why) ||
        !files_[f].writeHeader(commentLine(file) + "\n" + kColumns[f] + "\n", why)) {
      for (csv::CsvFileWriter& opened : files_) {
        std::string ignored;
        opened.close("traffic writer", &ignored);
      }
      return false;
    }
  }
  ids_ = ids;
  frame_ = frame;
  open_ = true;
  errors_ = 0;
  periods_ = 0;
  events_ = 0;
  return true;
}

TrafficWriteStatus TrafficFilesWriter::writeStatistics(const traffic::TrafficStatistics& s) {
  if (!open_) {
    return fail(TrafficWriteStatus::NotOpen);
  }
  if (s.gateCount > std::min(traffic::kMaxReportGates, ids_.gates.size()) ||
      s.zoneCount > std::min(traffic::kMaxReportZones, ids_.zones.size()) ||
      s.laneCount > std::min(traffic::kMaxReportLanes, ids_.lanes.size())) {
    return fail(TrafficWriteStatus::UnknownFeature);
  }
  // Checks and writes one row of a file.
  const auto emit = [&](TrafficFile file, auto&& format) {
    csv::CsvFileWriter& writer = files_[index(file)];
    RowFormatter row(writer.rowBuffer());
    format(row);
    std::size_t size = 0;
    if (const TrafficWriteStatus status = row.finish(&size); status != TrafficWriteStatus::Ok) {
      return fail(status);
    }
    return writer.writeRow(size) ? TrafficWriteStatus::Ok : fail(TrafficWriteStatus::WriteFailed);
  };
  for (std::size_t g = 0; g < s.gateCount; ++g) {
    const traffic::GateCountRecord& gate = s.gates[g];
    if (gate.gateIndex >= ids_.gates.size()) {
      return fail(TrafficWriteStatus::UnknownFeature);
    }
    for (std::size_t d = 0; d < 2; ++d) {
      for (std::size_t t = 0; t < traffic::kReportTypeCount; ++t) {
        const std::uint32_t count = gate.byDirectionAndType[d][t];
        if (count == 0) {
          continue;
        }
        const TrafficWriteStatus status = emit(TrafficFile::Counts, [&](RowFormatter& row) {
          periodColumns(row, s);
          row.text(ids_.gates[gate.gateIndex]).comma().text(d == 0 ? "forward" : "backward");
          row.comma().text(shape::toString(static_cast<shape::VehicleType>(t))).comma();
          row.integer(count);
        });
        if (status != TrafficWriteStatus::Ok) {
          return status;
        }
      }
    }
  }
  // Movements: indices are the gates' site order (the report's gates[g].gateIndex order).
  for (std::size_t from = 0; from < s.gateCount; ++from) {
    for (std::size_t to = 0; to < s.gateCount; ++to) {
      const std::uint32_t count = s.movements[from][to];
      if (count == 0) {
        continue;
      }
      const TrafficWriteStatus status = emit(TrafficFile::Movements, [&](RowFormatter& row) {
        periodColumns(row, s);
        row.text(ids_.gates[from]).comma().text(ids_.gates[to]).comma().integer(count);
      });
      if (status != TrafficWriteStatus::Ok) {
        return status;
      }
    }
  }
  for (std::size_t z = 0; z < s.zoneCount; ++z) {
    const traffic::ZoneRecord& zone = s.zones[z];
    if (zone.zoneIndex >= ids_.zones.size()) {
      return fail(TrafficWriteStatus::UnknownFeature);
    }
    const TrafficWriteStatus status = emit(TrafficFile::Zones, [&](RowFormatter& row) {
      periodColumns(row, s);
      row.text(ids_.zones[zone.zoneIndex]).comma().integer(zone.vehiclesNow).comma();
      row.fixed(zone.meanVehicles, kMetreDecimals).comma().integer(zone.maxVehicles).comma();
      row.integer(zone.queueNow_vehicles).comma().integer(zone.maxQueue_vehicles).comma();
      row.fixed(zone.queueNow_m, kMetreDecimals).comma();
      row.fixed(zone.maxQueue_m, kMetreDecimals).comma().integer(zone.dwellCount).comma();
      row.fixed(zone.meanDwell_s, kMetreDecimals).comma().fixed(zone.maxDwell_s, kMetreDecimals);
    });
    if (status != TrafficWriteStatus::Ok) {
      return status;
    }
  }
  for (std::size_t l = 0; l < s.laneCount; ++l) {
    const traffic::LaneRecord& lane = s.lanes[l];
    if (lane.laneIndex >= ids_.lanes.size()) {
      return fail(TrafficWriteStatus::UnknownFeature);
    }
    const TrafficWriteStatus status = emit(TrafficFile::Lanes, [&](RowFormatter& row) {
      periodColumns(row, s);
      row.text(ids_.lanes[lane.laneIndex]).comma().integer(lane.vehicles).comma();
      row.fixed(lane.meanSpeed_mps, kMetreDecimals).comma();
      row.fixed(lane.p85Speed_mps, kMetreDecimals).comma();
      row.fixed(lane.maxSpeed_mps, kMetreDecimals);
    });
    if (status != TrafficWriteStatus::Ok) {
      return status;
    }
  }
  ++periods_;
  return TrafficWriteStatus::Ok;
}

TrafficWriteStatus TrafficFilesWriter::writeEvent(const traffic::TrafficEvent& e) {
  if (!open_) {
    return fail(TrafficWriteStatus::NotOpen);
  }
  // feature_id: a gate (crossing, movement), a lane (wrong way) or a zone (box junction).
  const std::vector<std::string>* features = &ids_.gates;
  if (e.kind == traffic::TrafficEventKind::WrongWay) {
    features = &ids_.lanes;
  } else if (e.kind == traffic::TrafficEventKind::BoxJunctionStop) {
    features = &ids_.zones;
  }
  const bool movement = e.kind == traffic::TrafficEventKind::TurningMovement;
  const char* type = typeName(e.type);
  if (e.featureIndex >= features->size() || (movement && e.toFeatureIndex >= ids_.gates.size()) ||
      type == nullptr || e.direction > 1) {
    return fail(TrafficWriteStatus::UnknownFeature);
  }
  if (!std::isfinite(e.positionEnu_m.x()) || !std::isfinite(e.positionEnu_m.y())) {
    return fail(TrafficWriteStatus::InvalidValue);
  }
  const geodesy::GeodeticPoint wgs84 =
      frame_.toGeodetic(Eigen::Vector3d(e.positionEnu_m.x(), e.positionEnu_m.y(), 0.0));
  csv::CsvFileWriter& writer = files_[index(TrafficFile::Events)];
  RowFormatter row(writer.rowBuffer());
  row.integer(e.time_ns).comma().text(traffic::toString(e.kind)).comma().integer(e.trackId);
  row.comma().text((*features)[e.featureIndex]).comma();
  if (movement) {
    row.text(ids_.gates[e.toFeatureIndex]);
  }
  row.comma();
  if (e.kind == traffic::TrafficEventKind::GateCrossing) {
    row.text(e.direction == 0 ? "forward" : "backward");
  }
  row.comma().text(type).comma().fixed(e.speed_mps, kMetreDecimals).comma();
  row.fixed(e.positionEnu_m.x(), kMetreDecimals).comma();
  row.fixed(e.positionEnu_m.y(), kMetreDecimals).comma();
  row.fixed(wgs84.latitude_deg, kDegreeDecimals).comma();
  row.fixed(wgs84.longitude_deg, kDegreeDecimals);
  std::size_t size = 0;
  if (const TrafficWriteStatus status = row.finish(&size); status != TrafficWriteStatus::Ok) {
    return fail(status);
  }
  if (!writer.writeRow(size)) {
    return fail(TrafficWriteStatus::WriteFailed);
  }
  ++events_;
  return TrafficWriteStatus::Ok;
}

TrafficWriteStatus TrafficFilesWriter::commit() {
  if (!open_) {
    return fail(TrafficWriteStatus::NotOpen);
  }
  TrafficWriteStatus result = TrafficWriteStatus::Ok;
  for (csv::CsvFileWriter& file : files_) {
    if (!file.commit()) {
      result = fail(TrafficWriteStatus::WriteFailed);
    }
  }
  return result;
}

std::int64_t TrafficFilesWriter::rowsLost() const {
  std::int64_t lost = 0;
  for (const csv::CsvFileWriter& file : files_) {
    lost += file.rowsLost();
  }
  return lost;
}

bool TrafficFilesWriter::close(std::string* why) {
  bool ok = true;
  for (csv::CsvFileWriter& file : files_) {
    std::string problem;
    if (!file.close("traffic writer", &problem) && ok) {
      ok = false;
      csv::failWith(why, problem);
    }
  }
  open_ = false;
  return ok;
}

bool readTrafficFile(const std::string& path, TrafficFile file, TrafficFileRows* out,
                     std::string* why) {
  return csv::readChecked(path, out, why, [&] {
    const std::string text = csv::readWholeFile(path);
    const std::string comment = commentLine(file);
    const std::string_view header = kColumns[static_cast<std::size_t>(file)];
    const auto fieldCount =
        static_cast<std::size_t>(std::count(header.begin(), header.end(), ',')) + 1;
    std::vector<std::string_view> fields;
    const int lines = csv::forEachLine(text, [&](int line, std::string_view row) {
      if (line == 1 && row != comment) {
        throw csv::ReadError{csv::location(path, line) + ": expected " + csv::quote(comment) +
                             ", got " + csv::quote(row)};
      }
      if (line == 2 && row != header) {
        throw csv::ReadError{csv::location(path, line) + ": header: expected " +
                             csv::quote(header) + ", got " + csv::quote(row)};
      }
      if (line <= 2) {
        return;
      }
      csv::splitFields(row, fields);
      if (fields.size() != fieldCount) {
        throw csv::ReadError{csv::location(path, line) + ": expected " +
                             std::to_string(fieldCount) + " fields, got " +
                             std::to_string(fields.size())};
      }
      out->rows.emplace_back(fields.begin(), fields.end());
    });
    if (lines < 2) {
      throw csv::ReadError{path + ": missing the comment line or the header"};
    }
  });
}

}  // namespace vp::output_files
