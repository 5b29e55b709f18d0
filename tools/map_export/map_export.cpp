// map_export/map_export: inputs -> GeoJSON (see the header).
#include "map_export.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <map>
#include <set>
#include <string_view>
#include <tuple>
#include <utility>

#include "csv/csv_io.hpp"
#include "output_files/trajectory_file.hpp"
#include "shape/vehicle_model.hpp"
#include "site/site.hpp"
#include "traffic_tables.hpp"

namespace vp::map_export {
namespace {

// 1e-7 degree is 1.1 cm of latitude: finer than any position the app measures, coarse enough
// to keep the file small (RFC 7946 section 11.2 recommends not to write more than needed).
constexpr int kDegreeDecimals = 7;
constexpr int kValueDecimals = 3;  // metres, m/s, seconds, mean counts

// ---- JSON text ------------------------------------------------------------------------------

// Appends `value` fixed to `decimals`, without trailing zeros (and "0" for -0).
void appendNumber(std::string& out, double value, int decimals) {
  std::array<char, 64> buffer{};
  const double scale = std::pow(10.0, decimals);
  double rounded = std::round(value * scale) / scale;
  if (rounded == 0.0) {
    rounded = 0.0;  // no "-0"
  }
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), rounded,
                                    std::chars_format::fixed, decimals);
  std::string_view text(buffer.data(), static_cast<std::size_t>(result.ptr - buffer.data()));
  if (text.find('.') != std::string_view::npos) {
    while (text.back() == '0') {
      text.remove_suffix(1);
    }
    if (text.back() == '.') {
      text.remove_suffix(1);
    }
  }
  out += text;
}

// The length of the valid UTF-8 sequence at text[i], 0 when it is not one.
std::size_t utf8Length(std::string_view text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char c = byte(i);
  std::size_t length = 0;
  std::uint32_t code = 0;
  if (c < 0x80) {
    return 1;
  }
  if ((c & 0xE0) == 0xC0) {
    length = 2;
    code = c & 0x1FU;
  } else if ((c & 0xF0) == 0xE0) {
    length = 3;
    code = c & 0x0FU;
  } else if ((c & 0xF8) == 0xF0) {
    length = 4;
    code = c & 0x07U;
  } else {
    return 0;
  }
  if (i + length > text.size()) {
    return 0;
  }
  for (std::size_t k = 1; k < length; ++k) {
    if ((byte(i + k) & 0xC0) != 0x80) {
      return 0;
    }
    code = (code << 6) | (byte(i + k) & 0x3FU);
  }
  const std::uint32_t minimum = length == 2 ? 0x80 : length == 3 ? 0x800 : 0x10000;
  if (code < minimum || code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF)) {
    return 0;  // overlong, beyond Unicode, or a surrogate
  }
  return length;
}

// A JSON string: quotes, backslashes and control characters escaped; bytes that are not UTF-8
// become U+FFFD (GeoJSON is UTF-8, RFC 8259 section 8.1).
void appendString(std::string& out, std::string_view text) {
  out += '"';
  for (std::size_t i = 0; i < text.size();) {
    const char c = text[i];
    const std::size_t length = utf8Length(text, i);
    if (length == 0) {
      out += "\\ufffd";
      ++i;
      continue;
    }
    if (length > 1) {
      out.append(text.substr(i, length));
      i += length;
      continue;
    }
    ++i;
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          constexpr char kHex[] = "0123456789abcdef";
          out += "\\u00";
          out += kHex[(c >> 4) & 0xF];
          out += kHex[c & 0xF];
        } else {
          out += c;
        }
    }
  }
  out += '"';
}

// A feature's "properties" object, member by member.
class Properties {
 public:
  Properties& text(std::string_view name, std::string_view value) {
    key(name);
    appendString(body_, value);
    return *this;
  }
  Properties& integer(std::string_view name, std::int64_t value) {
    key(name);
    body_ += std::to_string(value);
    return *this;
  }
  Properties& number(std::string_view name, double value, int decimals = kValueDecimals) {
    key(name);
    appendNumber(body_, value, decimals);
    return *this;
  }
  const std::string& body() const { return body_; }

 private:
  void key(std::string_view name) {
    body_ += body_.empty() ? "" : ", ";
    appendString(body_, name);
    body_ += ": ";
  }
  std::string body_;
};

using LonLat = Eigen::Vector2d;  // x longitude, y latitude (degrees)

// Positions as GeoJSON text, consecutive positions that round to the same text dropped.
std::vector<std::string> positions(std::span<const LonLat> points) {
  std::vector<std::string> out;
  for (const LonLat& p : points) {
    std::string text = "[";
    appendNumber(text, p.x(), kDegreeDecimals);
    text += ", ";
    appendNumber(text, p.y(), kDegreeDecimals);
    text += "]";
    if (out.empty() || out.back() != text) {
      out.push_back(std::move(text));
    }
  }
  return out;
}

std::string joined(const std::vector<std::string>& parts) {
  std::string s;
  for (const std::string& part : parts) {
    s += (s.empty() ? "" : ", ") + part;
  }
  return s;
}

// A LineString, or a Point when its positions round to one place (a vehicle that never moved,
// a movement back to its own gate).
std::string lineOrPoint(std::span<const LonLat> points) {
  const std::vector<std::string> p = positions(points);
  if (p.size() == 1) {
    return R"({"type": "Point", "coordinates": )" + p.front() + "}";
  }
  return R"({"type": "LineString", "coordinates": [)" + joined(p) + "]}";
}

std::string pointGeometry(const LonLat& point) {
  return R"({"type": "Point", "coordinates": )" + positions({&point, 1}).front() + "}";
}

// A ring (without its closing repeat) as a closed Polygon: counter-clockwise (RFC 7946's
// right-hand rule for outer rings; the site file may have either), the first position repeated
// last after rounding (which may merge neighbouring vertices of a ring finer than 1 cm).
std::string polygonGeometry(std::span<const LonLat> ring) {
  double twiceArea = 0.0;
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const LonLat a = ring[i] - ring[0];  // relative: no cancellation of large degrees
    const LonLat b = ring[(i + 1) % ring.size()] - ring[0];
    twiceArea += a.x() * b.y() - b.x() * a.y();
  }
  std::vector<LonLat> ordered(ring.begin(), ring.end());
  if (twiceArea < 0.0) {
    std::reverse(ordered.begin(), ordered.end());
  }
  std::vector<std::string> p = positions(ordered);
  while (p.size() > 1 && p.back() == p.front()) {
    p.pop_back();
  }
  p.push_back(p.front());
  return R"({"type": "Polygon", "coordinates": [[)" + joined(p) + "]]}";
}

void appendFeature(std::string& out, const std::string& geometry, const Properties& properties) {
  out += out.empty() ? "" : ",\n";
  out += R"({"type": "Feature", "properties": {)" + properties.body() +
         "}, \"geometry\": " + geometry + "}";
}

// ---- inputs ---------------------------------------------------------------------------------

bool fail(std::string* why, const std::string& message) {
  if (why) {
    *why = message;
  }
  return false;
}

std::string at(const std::string& file, int line, int column) {
  return csv::location(file, line) + ":" + std::to_string(column);
}

// "<file>:<line>:<column>" of field `index` (0-based) of a line of a CSV file (for a message
// about a row the reader accepted; the file is read again, on that error path only).
std::string fieldAt(const std::string& file, int line, int index) {
  int column = 1;
  try {
    const std::string text = csv::readWholeFile(file);
    csv::forEachLine(text, [&](int number, std::string_view row) {
      if (number != line) {
        return;
      }
      std::size_t start = 0;
      for (int i = 0; i < index && start != std::string_view::npos; ++i) {
        start = row.find(',', start);
        start = start == std::string_view::npos ? start : start + 1;
      }
      column = start == std::string_view::npos ? 1 : static_cast<int>(start) + 1;
    });
  } catch (const csv::ReadError&) {
  }
  return at(file, line, column);
}

// The first position of a GeoJSON text's first feature, to read the site in a frame at the site
// (any frame would do for the loader; near the site the conversion back is exact). Nothing if
// the text does not have one where expected: the loader then says what is wrong.
std::optional<geodesy::GeodeticPoint> firstPosition(const std::string& path) {
  try {
    const YAML::Node root = YAML::LoadFile(path);
    YAML::Node node = root["features"][0]["geometry"]["coordinates"];
    while (node && node.IsSequence() && node.size() > 0 && node[0].IsSequence()) {
      node = node[0];
    }
    if (node && node.IsSequence() && node.size() >= 2) {
      const double lon = node[0].as<double>();
      const double lat = node[1].as<double>();
      if (std::isfinite(lon) && std::isfinite(lat) && std::abs(lon) <= 180.0 &&
          std::abs(lat) <= 90.0) {
        return geodesy::GeodeticPoint{lat, lon, 0.0};
      }
    }
  } catch (const YAML::Exception&) {
  }
  return std::nullopt;
}

struct LoadedSite {
  site::Site site;
  geodesy::LocalFrame frame;
  std::map<std::string, const site::Feature*> byId;
};

bool loadSite(const std::string& path, LoadedSite* out, std::string* why) {
  out->frame = geodesy::LocalFrame(firstPosition(path).value_or(geodesy::GeodeticPoint{}));
  if (!site::loadSite(path, out->frame, &out->site, why)) {
    return false;
  }
  for (const site::Feature& f : out->site.features()) {
    out->byId[f.id] = &f;
  }
  return true;
}

std::vector<LonLat> siteLonLat(const LoadedSite& s, const site::Feature& f) {
  std::vector<LonLat> points;
  for (const Eigen::Vector2d& v : s.site.vertices(f)) {
    const geodesy::GeodeticPoint p = siteVertexToWgs84(s.frame, v);
    points.emplace_back(p.longitude_deg, p.latitude_deg);
  }
  return points;
}

// The feature of that id and kind, or a message naming the row's field.
bool findFeature(const LoadedSite* s, const std::string& id, std::optional<site::FeatureKind> kind,
                 const std::string& file, int line, int column, const char* field,
                 const site::Feature** found, std::string* why) {
  const auto it = s->byId.find(id);
  if (it == s->byId.end() || (kind && it->second->kind != *kind)) {
    return fail(why, at(file, line, column) + ": " + field + ": no " +
                         (kind ? site::toString(*kind) : "feature") + " '" + id + "' in " +
                         csv::shortened(s->site.sourceName()));
  }
  *found = it->second;
  return true;
}

// ---- tracks ---------------------------------------------------------------------------------

struct TrackSummary {
  std::uint32_t id = 0;
  std::vector<const output_files::TrajectoryRecord*> rows;
  std::vector<int> lines;
};

bool appendTracks(const MapExportOptions& options, std::string& out, MapExportSummary& summary,
                  std::string* why) {
  output_files::TrajectoryFile file;
  if (!output_files::readTrajectoryFile(options.trajectoryPath, &file, why)) {
    return false;
  }
  std::optional<geodesy::LocalFrame> frame;
  if (options.origin) {
    frame.emplace(*options.origin);
  }
  std::map<std::uint32_t, TrackSummary> tracks;  // by id: the file's rows are in frame order
  for (std::size_t i = 0; i < file.rows.size(); ++i) {
    const output_files::TrajectoryRecord& row = file.rows[i];
    if (!row.centreWgs84 && !frame) {
      constexpr int kLatitudeColumn = 10;  // latitude_deg, after time_s and status
      return fail(why, fieldAt(file.path, file.lines[i], kLatitudeColumn) +
                           ": latitude_deg: empty, and no world frame origin to place the "
                           "row's ENU position (give --origin or --rig)");
    }
    TrackSummary& track = tracks[row.trackId];
    track.id = row.trackId;
    track.rows.push_back(&row);
    track.lines.push_back(file.lines[i]);
  }
  for (const auto& [id, track] : tracks) {
    if (track.rows.size() < static_cast<std::size_t>(options.minTrackPoints)) {
      ++summary.tracksTooShort;
      continue;
    }
    std::vector<Eigen::Vector2d> enu;
    double length_m = 0.0;
    double speedSum_mps = 0.0;
    double maxSpeed_mps = 0.0;
    for (const output_files::TrajectoryRecord* row : track.rows) {
      if (!enu.empty()) {
        length_m += (row->centreEnu - enu.back()).norm();
      }
      enu.push_back(row->centreEnu);
      speedSum_mps += std::abs(row->speed_mps);
      maxSpeed_mps = std::max(maxSpeed_mps, std::abs(row->speed_mps));
    }
    // Simplified in ENU; each kept vertex placed by its own row's WGS84 when it has one.
    const std::vector<Eigen::Vector2d> kept = simplifyLine(enu, options.simplify_m);
    std::vector<LonLat> line;
    std::size_t next = 0;
    for (const Eigen::Vector2d& v : kept) {
      while (next < enu.size() && enu[next] != v) {
        ++next;
      }
      const output_files::TrajectoryRecord& row = *track.rows[std::min(next, enu.size() - 1)];
      if (row.centreWgs84) {
        line.emplace_back(row.centreWgs84->longitude_deg, row.centreWgs84->latitude_deg);
      } else {
        const geodesy::GeodeticPoint p = frame->toGeodetic(Eigen::Vector3d(v.x(), v.y(), 0.0));
        line.emplace_back(p.longitude_deg, p.latitude_deg);
      }
    }
    const output_files::TrajectoryRecord& first = *track.rows.front();
    const output_files::TrajectoryRecord& last = *track.rows.back();
    Properties p;
    p.text("layer", "track")
        .integer("track_id", id)
        .text("type", shape::toString(last.type))
        .integer("points", static_cast<std::int64_t>(track.rows.size()))
        .integer("vertices", static_cast<std::int64_t>(kept.size()))
        .number("first_time_s", first.timeS)
        .number("last_time_s", last.timeS)
        .number("duration_s", last.timeS - first.timeS)
        .number("length_m", length_m)
        .number("mean_speed_mps", speedSum_mps / static_cast<double>(track.rows.size()))
        .number("max_speed_mps", maxSpeed_mps)
        .integer("first_frame_id", first.frameId)
        .integer("last_frame_id", last.frameId);
    appendFeature(out, lineOrPoint(line), p);
    ++summary.tracks;
    summary.trackRows += track.rows.size();
    summary.trackVertices += kept.size();
  }
  return true;
}

// ---- traffic statistics ---------------------------------------------------------------------

struct GateTotals {
  std::array<std::array<std::uint64_t, shape::kVehicleTypeCount>, 2> byDirectionAndType{};
  std::uint64_t movementsOut = 0;
  std::uint64_t movementsIn = 0;
};

struct ZoneTotals {
  std::size_t periods = 0;
  double weightedVehicles = 0.0;  // sum of mean_vehicles x period duration
  double duration_s = 0.0;
  std::uint64_t maxVehicles = 0;
  std::uint64_t maxQueue_vehicles = 0;
  double maxQueue_m = 0.0;
  std::uint64_t dwellCount = 0;
  double dwellSum_s = 0.0;  // sum of mean_dwell_s x dwell_count
  double maxDwell_s = 0.0;
};

struct LaneTotals {
  std::size_t periods = 0;
  std::uint64_t vehicles = 0;
  double speedSum_mps = 0.0;  // sum of mean_speed_mps x vehicles
  double maxP85_mps = 0.0;
  double maxSpeed_mps = 0.0;
};

struct Statistics {
  std::map<const site::Feature*, GateTotals> gates;
  std::map<const site::Feature*, ZoneTotals> zones;
  std::map<const site::Feature*, LaneTotals> lanes;
  std::map<std::pair<const site::Feature*, const site::Feature*>, std::uint64_t> movements;
  bool counts = false;
};

double duration_s(const PeriodFields& p) {
  return static_cast<double>(p.end_ns - p.start_ns) * 1e-9;
}

bool readStatistics(const MapExportOptions& options, const LoadedSite* s, Statistics& stats,
                    std::string* why) {
  const auto needSite = [&](const std::string& path) {
    return fail(why, csv::shortened(path) +
                         ": traffic statistics are drawn on the site's features: give the site "
                         "file (--site)");
  };
  if (!options.countsPath.empty()) {
    TrafficTable<GateCountRow> table;
    if (!readGateCounts(options.countsPath, &table, why)) {
      return false;
    }
    if (s == nullptr) {
      return needSite(table.path);
    }
    stats.counts = true;
    for (const site::Feature& f : s->site.features()) {
      if (f.kind == site::FeatureKind::Gate) {
        stats.gates[&f];  // every gate gets counts, zero without rows (rows of 0 are omitted)
      }
    }
    std::set<std::tuple<std::uint64_t, std::string, bool, int>> seen;
    for (const GateCountRow& row : table.rows) {
      const site::Feature* gate = nullptr;
      if (!findFeature(s, row.gateId, site::FeatureKind::Gate, table.path, row.line, row.idColumn,
                       "gate_id", &gate, why)) {
        return false;
      }
      if (!seen.emplace(row.period.period, row.gateId, row.backward, static_cast<int>(row.type))
               .second) {
        return fail(why, at(table.path, row.line, row.idColumn) + ": gate_id: gate '" + row.gateId +
                             "', " + (row.backward ? "backward" : "forward") + ", " +
                             shape::toString(row.type) + " appears twice in period " +
                             std::to_string(row.period.period));
      }
      stats.gates[gate].byDirectionAndType[row.backward ? 1 : 0][static_cast<int>(row.type)] +=
          row.count;
    }
  }
  if (!options.movementsPath.empty()) {
    TrafficTable<MovementRow> table;
    if (!readMovements(options.movementsPath, &table, why)) {
      return false;
    }
    if (s == nullptr) {
      return needSite(table.path);
    }
    std::set<std::tuple<std::uint64_t, std::string, std::string>> seen;
    for (const MovementRow& row : table.rows) {
      const site::Feature* from = nullptr;
      const site::Feature* to = nullptr;
      if (!findFeature(s, row.fromGateId, site::FeatureKind::Gate, table.path, row.line,
                       row.idColumn, "from_gate_id", &from, why) ||
          !findFeature(s, row.toGateId, site::FeatureKind::Gate, table.path, row.line,
                       row.toIdColumn, "to_gate_id", &to, why)) {
        return false;
      }
      if (!seen.emplace(row.period.period, row.fromGateId, row.toGateId).second) {
        return fail(why, at(table.path, row.line, row.idColumn) + ": from_gate_id: movement '" +
                             row.fromGateId + "' -> '" + row.toGateId +
                             "' appears twice in period " + std::to_string(row.period.period));
      }
      stats.movements[{from, to}] += row.count;
      stats.gates[from].movementsOut += row.count;
      stats.gates[to].movementsIn += row.count;
    }
  }
  if (!options.zonesPath.empty()) {
    TrafficTable<ZoneRow> table;
    if (!readZones(options.zonesPath, &table, why)) {
      return false;
    }
    if (s == nullptr) {
      return needSite(table.path);
    }
    std::set<std::pair<std::uint64_t, std::string>> seen;
    for (const ZoneRow& row : table.rows) {
      const site::Feature* zone = nullptr;
      if (!findFeature(s, row.zoneId, site::FeatureKind::Zone, table.path, row.line, row.idColumn,
                       "zone_id", &zone, why)) {
        return false;
      }
      if (!seen.emplace(row.period.period, row.zoneId).second) {
        return fail(why, at(table.path, row.line, row.idColumn) + ": zone_id: zone '" + row.zoneId +
                             "' appears twice in period " + std::to_string(row.period.period));
      }
      ZoneTotals& z = stats.zones[zone];
      ++z.periods;
      z.weightedVehicles += row.meanVehicles * duration_s(row.period);
      z.duration_s += duration_s(row.period);
      z.maxVehicles = std::max(z.maxVehicles, row.maxVehicles);
      z.maxQueue_vehicles = std::max(z.maxQueue_vehicles, row.maxQueue_vehicles);
      z.maxQueue_m = std::max(z.maxQueue_m, row.maxQueue_m);
      z.dwellCount += row.dwellCount;
      z.dwellSum_s += row.meanDwell_s * static_cast<double>(row.dwellCount);
      z.maxDwell_s = std::max(z.maxDwell_s, row.maxDwell_s);
    }
  }
  if (!options.lanesPath.empty()) {
    TrafficTable<LaneRow> table;
    if (!readLanes(options.lanesPath, &table, why)) {
      return false;
    }
    if (s == nullptr) {
      return needSite(table.path);
    }
    std::set<std::pair<std::uint64_t, std::string>> seen;
    for (const LaneRow& row : table.rows) {
      const site::Feature* lane = nullptr;
      if (!findFeature(s, row.laneId, site::FeatureKind::Lane, table.path, row.line, row.idColumn,
                       "lane_id", &lane, why)) {
        return false;
      }
      if (!seen.emplace(row.period.period, row.laneId).second) {
        return fail(why, at(table.path, row.line, row.idColumn) + ": lane_id: lane '" + row.laneId +
                             "' appears twice in period " + std::to_string(row.period.period));
      }
      LaneTotals& l = stats.lanes[lane];
      ++l.periods;
      l.vehicles += row.vehicles;
      l.speedSum_mps += row.meanSpeed_mps * static_cast<double>(row.vehicles);
      l.maxP85_mps = std::max(l.maxP85_mps, row.p85Speed_mps);
      l.maxSpeed_mps = std::max(l.maxSpeed_mps, row.maxSpeed_mps);
    }
  }
  return true;
}

void appendSite(const LoadedSite& s, const Statistics& stats, std::string& out,
                MapExportSummary& summary) {
  for (const site::Feature& f : s.site.features()) {
    Properties p;
    p.text("layer", "site")
        .text("kind", site::toString(f.kind))
        .text("id", f.id)
        .text("name", f.name);
    // What the site file says of the feature beyond its name, as a map user reads it back.
    if (f.kind == site::FeatureKind::Lane) {
      p.number("width_m", f.width_m, 2);
    } else if (f.kind == site::FeatureKind::Zone) {
      p.text("role", site::toString(f.role));
      if (!f.lane.empty()) {
        p.text("lane", f.lane);
      }
    }
    if (const auto gate = stats.gates.find(&f); gate != stats.gates.end()) {
      const GateTotals& g = gate->second;
      if (stats.counts) {
        std::array<std::uint64_t, 2> byDirection{};
        for (int d = 0; d < 2; ++d) {
          for (const std::uint64_t n : g.byDirectionAndType[d]) {
            byDirection[d] += n;
          }
        }
        p.integer("total", static_cast<std::int64_t>(byDirection[0] + byDirection[1]))
            .integer("forward", static_cast<std::int64_t>(byDirection[0]))
            .integer("backward", static_cast<std::int64_t>(byDirection[1]));
        for (int d = 0; d < 2; ++d) {
          for (int t = 0; t < shape::kVehicleTypeCount; ++t) {
            p.integer(std::string(d == 0 ? "forward_" : "backward_") +
                          shape::toString(static_cast<shape::VehicleType>(t)),
                      static_cast<std::int64_t>(g.byDirectionAndType[d][t]));
          }
        }
        ++summary.gatesWithCounts;
      }
      if (!stats.movements.empty()) {
        p.integer("movements_out", static_cast<std::int64_t>(g.movementsOut))
            .integer("movements_in", static_cast<std::int64_t>(g.movementsIn));
      }
    }
    if (const auto zone = stats.zones.find(&f); zone != stats.zones.end()) {
      const ZoneTotals& z = zone->second;
      p.integer("periods", static_cast<std::int64_t>(z.periods))
          .number("mean_vehicles", z.duration_s > 0.0 ? z.weightedVehicles / z.duration_s : 0.0)
          .integer("max_vehicles", static_cast<std::int64_t>(z.maxVehicles))
          .integer("max_queue_vehicles", static_cast<std::int64_t>(z.maxQueue_vehicles))
          .number("max_queue_m", z.maxQueue_m)
          .integer("dwell_count", static_cast<std::int64_t>(z.dwellCount))
          .number("mean_dwell_s",
                  z.dwellCount > 0 ? z.dwellSum_s / static_cast<double>(z.dwellCount) : 0.0)
          .number("max_dwell_s", z.maxDwell_s);
      ++summary.zonesWithStatistics;
    }
    if (const auto lane = stats.lanes.find(&f); lane != stats.lanes.end()) {
      const LaneTotals& l = lane->second;
      p.integer("periods", static_cast<std::int64_t>(l.periods))
          .integer("vehicles", static_cast<std::int64_t>(l.vehicles))
          .number("mean_speed_mps",
                  l.vehicles > 0 ? l.speedSum_mps / static_cast<double>(l.vehicles) : 0.0)
          .number("max_p85_speed_mps", l.maxP85_mps)
          .number("max_speed_mps", l.maxSpeed_mps);
      ++summary.lanesWithStatistics;
    }
    const std::vector<LonLat> points = siteLonLat(s, f);
    appendFeature(out, site::isArea(f.kind) ? polygonGeometry(points) : lineOrPoint(points), p);
    ++summary.siteFeatures;
  }
  // Turning movements: a line from the middle of one gate to the middle of the other.
  const auto middle = [&](const site::Feature& gate) {
    const std::span<const Eigen::Vector2d> v = s.site.vertices(gate);
    const geodesy::GeodeticPoint p = siteVertexToWgs84(s.frame, 0.5 * (v.front() + v.back()));
    return LonLat(p.longitude_deg, p.latitude_deg);
  };
  for (const auto& [pair, count] : stats.movements) {
    const std::array<LonLat, 2> line = {middle(*pair.first), middle(*pair.second)};
    Properties p;
    p.text("layer", "movement")
        .text("from_gate_id", pair.first->id)
        .text("to_gate_id", pair.second->id)
        .integer("count", static_cast<std::int64_t>(count));
    appendFeature(out, lineOrPoint(line), p);
    ++summary.movements;
  }
}

bool appendEvents(const MapExportOptions& options, const LoadedSite* s, std::string& out,
                  MapExportSummary& summary, std::string* why) {
  TrafficTable<EventRow> table;
  if (!readEvents(options.eventsPath, &table, why)) {
    return false;
  }
  std::optional<geodesy::LocalFrame> frame;
  if (options.origin) {
    frame.emplace(*options.origin);
  }
  for (const EventRow& row : table.rows) {
    if (s != nullptr) {
      const site::Feature* feature = nullptr;
      if (!findFeature(s, row.featureId, std::nullopt, table.path, row.line, row.idColumn,
                       "feature_id", &feature, why) ||
          (!row.toFeatureId.empty() &&
           !findFeature(s, row.toFeatureId, std::nullopt, table.path, row.line, row.toIdColumn,
                        "to_feature_id", &feature, why))) {
        return false;
      }
    }
    LonLat position;
    if (row.lat_deg) {
      position = LonLat(*row.lon_deg, *row.lat_deg);
    } else if (frame) {
      const geodesy::GeodeticPoint p =
          frame->toGeodetic(Eigen::Vector3d(row.east_m, row.north_m, 0.0));
      position = LonLat(p.longitude_deg, p.latitude_deg);
    } else {
      constexpr int kLatitudeColumn = 10;  // lat_deg
      return fail(why, fieldAt(table.path, row.line, kLatitudeColumn) +
                           ": lat_deg: empty, and no world frame origin to place the event's "
                           "ENU position (give --origin or --rig)");
    }
    Properties p;
    p.text("layer", "event")
        .text("kind", row.kind)
        .integer("time_ns", row.time_ns)
        .number("time_s", static_cast<double>(row.time_ns) * 1e-9)
        .integer("track_id", row.trackId)
        .text("feature_id", row.featureId)
        .text("to_feature_id", row.toFeatureId)
        .text("direction", row.direction)
        .text("type", row.type ? shape::toString(*row.type) : "")
        .number("speed_mps", row.speed_mps);
    appendFeature(out, pointGeometry(position), p);
    ++summary.events;
  }
  return true;
}

}  // namespace

bool checkOptions(const MapExportOptions& options, std::string* why) {
  if (options.minTrackPoints < 1) {
    return fail(why,
                "--min-track-points: must be >= 1, got " + std::to_string(options.minTrackPoints));
  }
  if (!std::isfinite(options.simplify_m) || options.simplify_m < 0.0) {
    return fail(why, "--simplify-m: must be a finite number >= 0");
  }
  if (options.trajectoryPath.empty() && options.sitePath.empty() && options.eventsPath.empty() &&
      options.countsPath.empty() && options.movementsPath.empty() && options.zonesPath.empty() &&
      options.lanesPath.empty()) {
    return fail(why, "nothing to export: give --trajectory, --site, --traffic or a traffic file");
  }
  return true;
}

geodesy::GeodeticPoint siteVertexToWgs84(const geodesy::LocalFrame& frame,
                                         const Eigen::Vector2d& east_north_m) {
  // The loader converted the point at the origin's height and kept east/north: find the up
  // coordinate that puts the point back at that height (a few iterations: up depends on
  // east/north through the Earth's curvature only).
  Eigen::Vector3d enu(east_north_m.x(), east_north_m.y(), 0.0);
  for (int i = 0; i < 4; ++i) {
    geodesy::GeodeticPoint p = frame.toGeodetic(enu);
    p.height_m = frame.origin().height_m;
    enu.z() = frame.toEnu(p).z();
  }
  return frame.toGeodetic(enu);
}

std::vector<Eigen::Vector2d> simplifyLine(std::span<const Eigen::Vector2d> line,
                                          double minSpacing_m) {
  if (line.size() <= 2 || minSpacing_m <= 0.0) {
    return {line.begin(), line.end()};
  }
  std::vector<Eigen::Vector2d> kept{line.front()};
  double along_m = 0.0;  // distance along the line since the last kept vertex
  for (std::size_t i = 1; i + 1 < line.size(); ++i) {
    along_m += (line[i] - line[i - 1]).norm();
    if (along_m >= minSpacing_m) {
      kept.push_back(line[i]);
      along_m = 0.0;
    }
  }
  along_m += (line.back() - line[line.size() - 2]).norm();
  if (along_m < minSpacing_m && kept.size() > 1) {
    kept.pop_back();  // the last vertex takes the place of a kept one too close to it
  }
  kept.push_back(line.back());
  return kept;
}

bool exportMap(const MapExportOptions& options, std::string* geojson, MapExportSummary* summary,
               std::string* why) {
  if (!checkOptions(options, why)) {
    return false;
  }
  MapExportSummary counts;
  std::optional<LoadedSite> loaded;
  if (!options.sitePath.empty()) {
    loaded.emplace();
    if (!loadSite(options.sitePath, &*loaded, why)) {
      return false;
    }
  }
  const LoadedSite* s = loaded ? &*loaded : nullptr;
  Statistics stats;
  if (!readStatistics(options, s, stats, why)) {
    return false;
  }
  std::string features;
  if (s != nullptr) {
    appendSite(*s, stats, features, counts);
  }
  if (!options.trajectoryPath.empty() && !appendTracks(options, features, counts, why)) {
    return false;
  }
  if (!options.eventsPath.empty() && !appendEvents(options, s, features, counts, why)) {
    return false;
  }
  *geojson = "{\"type\": \"FeatureCollection\", \"features\": [\n" + features + "\n]}\n";
  if (summary) {
    *summary = counts;
  }
  return true;
}

}  // namespace vp::map_export
