// tests/map_export: vp_map_export (tools/map_export) on a small run written by the product's
// own writers (the trajectory file) and traffic files written to the documented format: the
// map holds what the inputs say (track lengths and speeds, gate totals, zone occupancy, events
// where they happened), is GeoJSON that GIS programs open (parsed back, checked by structure
// and by tests/map_export/check_geojson.py: strict JSON, RFC 7946, GDAL's GeoJSON driver), and
// every bad input is refused naming the file, the line and the column.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "geodesy/geodesy.hpp"
#include "map_export.hpp"
#include "output_files/trajectory_file.hpp"

namespace vp::map_export {
namespace {

namespace fs = std::filesystem;

const geodesy::GeodeticPoint kOrigin{48.1371, 11.5750, 520.0};
const geodesy::LocalFrame kFrame(kOrigin);
constexpr double kDegreeTolerance = 1e-7;  // the map's rounding (about 1 cm)

Eigen::Vector2d lonLat(double east_m, double north_m) {
  const geodesy::GeodeticPoint p = kFrame.toGeodetic(Eigen::Vector3d(east_m, north_m, 0.0));
  return {p.longitude_deg, p.latitude_deg};
}

std::string position(double east_m, double north_m) {
  const Eigen::Vector2d p = lonLat(east_m, north_m);
  char text[64];
  std::snprintf(text, sizeof text, "[%.10f, %.10f]", p.x(), p.y());
  return text;
}

// `extra`: further members of "properties", each with its leading comma.
std::string feature(const std::string& kind, const std::string& id, const std::string& name,
                    const std::string& type, const std::string& coordinates,
                    const std::string& extra = "") {
  return R"({"type": "Feature", "properties": {"kind": ")" + kind + R"(", "id": ")" + id +
         R"(", "name": ")" + name + "\"" + extra + R"(}, "geometry": {"type": ")" + type +
         R"(", "coordinates": )" + coordinates + "}}";
}

// A road along x with a junction zone (its ring written clockwise), a lane and two gates.
std::string siteText() {
  const std::string road = "[[" + position(-60, -7) + ", " + position(60, -7) + ", " +
                           position(60, 7) + ", " + position(-60, 7) + ", " + position(-60, -7) +
                           "]]";
  const std::string zoneClockwise = "[[" + position(-7, -7) + ", " + position(-7, 7) + ", " +
                                    position(7, 7) + ", " + position(7, -7) + ", " +
                                    position(-7, -7) + "]]";
  return "{\"type\": \"FeatureCollection\", \"features\": [\n" +
         feature("drivable", "road-1", R"(K\u00f6nigstra\u00dfe \"Nord\")", "Polygon", road) +
         ",\n" +
         feature("zone", "box-1", "junction", "Polygon", zoneClockwise,
                 R"(, "role": "box_junction")") +
         ",\n" +
         feature("lane", "lane-east", "eastbound", "LineString",
                 "[" + position(-60, -3.5) + ", " + position(60, -3.5) + "]",
                 R"(, "width_m": 3.25)") +
         ",\n" +
         feature("gate", "gate-w", "west", "LineString",
                 "[" + position(-9, -7) + ", " + position(-9, 7) + "]") +
         ",\n" +
         feature("gate", "gate-e", "east", "LineString",
                 "[" + position(9, -7) + ", " + position(9, 7) + "]") +
         "\n]}\n";
}

tracking::TrackState trackState(std::uint32_t id, shape::VehicleType type, std::int64_t time_ns,
                                const Eigen::Vector2d& centre, double speed_mps) {
  tracking::TrackState t;
  t.id = id;
  t.status = tracking::TrackStatus::Confirmed;
  t.timestamp_ns = time_ns;
  t.centreEnu = centre;
  t.rearAxleEnu = centre;
  t.speed_mps = speed_mps;
  t.length_m = 4.5;
  t.width_m = 1.8;
  t.wheelbase_m = 2.7;
  t.typeProbabilities.fill(0.0F);
  t.typeProbabilities[static_cast<std::size_t>(type)] = 1.0F;
  t.type = type;
  return t;
}

constexpr std::int64_t kStart_ns = 1'700'000'000'000'000'000;
constexpr std::int64_t kFrame_ns = 100'000'000;  // 10 Hz

// Track 1: a sedan eastbound along y = -3.5 from x = -50 to 50 at 10 m/s (101 rows). Track 2:
// one row. Track 3: a van parked at (20, 3.5) for 20 frames. Track 4: a truck northbound along
// x = 3.5 at 5 m/s from y = -25, 31 rows without WGS84 fields (placed through the origin).
void writeTrajectory(const fs::path& path) {
  output_files::TrajectoryFileWriter writer;
  std::string why;
  ASSERT_TRUE(writer.open(path.string(), output_files::TrajectoryFileInfo{0}, &why)) << why;
  for (int frame = 0; frame <= 100; ++frame) {
    const std::int64_t t_ns = kStart_ns + frame * kFrame_ns;
    std::vector<std::pair<tracking::TrackState, bool>> rows;  // state, with WGS84
    rows.emplace_back(trackState(1, shape::VehicleType::Sedan, t_ns, {-50.0 + frame, -3.5}, 10.0),
                      true);
    if (frame == 0) {
      rows.emplace_back(trackState(2, shape::VehicleType::Suv, t_ns, {0.0, 0.0}, 3.0), true);
    }
    if (frame < 20) {
      rows.emplace_back(trackState(3, shape::VehicleType::Van, t_ns, {20.0, 3.5}, 0.0), true);
    }
    if (frame % 2 == 0 && frame <= 60) {
      rows.emplace_back(
          trackState(4, shape::VehicleType::Large, t_ns, {3.5, -25.0 + frame * 0.5}, 5.0), false);
    }
    for (const auto& [state, withWgs84] : rows) {
      const geodesy::GeodeticPoint p =
          kFrame.toGeodetic(Eigen::Vector3d(state.centreEnu.x(), state.centreEnu.y(), 0.0));
      const tracking::Wgs84Position wgs84{p.latitude_deg, p.longitude_deg, p.height_m};
      ASSERT_TRUE(writer.writeRow(frame, state, withWgs84 ? &wgs84 : nullptr, &why)) << why;
    }
  }
  ASSERT_TRUE(writer.close(&why)) << why;
}

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

std::string readText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

const std::string kCounts =
    "# vp_firmware_app traffic_counts.csv format_version 1\n"
    "period,start_ns,end_ns,gate_id,direction,type,count\n"
    "0,0,60000000000,gate-w,forward,sedan,3\n"
    "0,0,60000000000,gate-w,forward,van,1\n"
    "1,60000000000,90000000000,gate-w,backward,sedan,2\n";
const std::string kMovements =
    "# vp_firmware_app traffic_movements.csv format_version 1\n"
    "period,start_ns,end_ns,from_gate_id,to_gate_id,count\n"
    "0,0,60000000000,gate-w,gate-e,3\n"
    "1,60000000000,90000000000,gate-w,gate-e,1\n";
// Zone box-1: mean 2 vehicles over 60 s, 0.5 over 30 s: 1.5 over the 90 s.
const std::string kZones =
    "# vp_firmware_app traffic_zones.csv format_version 1\n"
    "period,start_ns,end_ns,zone_id,vehicles_now,mean_vehicles,max_vehicles,queue_now_vehicles,"
    "max_queue_vehicles,queue_now_m,max_queue_m,dwell_count,mean_dwell_s,max_dwell_s\n"
    "0,0,60000000000,box-1,2,2.000,4,1,3,6.500,12.500,2,10.000,14.000\n"
    "1,60000000000,90000000000,box-1,0,0.500,2,0,5,0.000,30.250,1,40.000,40.000\n";
const std::string kLanes =
    "# vp_firmware_app traffic_lanes.csv format_version 1\n"
    "period,start_ns,end_ns,lane_id,vehicles,mean_speed_mps,p85_speed_mps,max_speed_mps\n"
    "0,0,60000000000,lane-east,3,10.000,11.000,12.000\n"
    "1,60000000000,90000000000,lane-east,1,6.000,6.000,6.000\n";
// A gate crossing with WGS84 fields; a wrong-way event with ENU only (placed through the
// origin).
std::string eventsText() {
  const Eigen::Vector2d p = lonLat(-9.0, -3.5);
  char row[256];
  std::snprintf(row, sizeof row,
                "1700000000500000000,gate_crossing,1,gate-w,,forward,sedan,10.000,-9.000,-3.500,"
                "%.9f,%.9f\n",
                p.y(), p.x());
  return "# vp_firmware_app traffic_events.csv format_version 1\n"
         "time_ns,kind,track_id,feature_id,to_feature_id,direction,type,speed_mps,east_m,"
         "north_m,lat_deg,lon_deg\n" +
         std::string(row) +
         "1700000001000000000,wrong_way,4,lane-east,,,large,5.000,30.000,-3.500,,\n";
}

class MapExport : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("vp_map_export_" + std::string(info->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    writeText(dir_ / "site.geojson", siteText());
    writeTrajectory(dir_ / "trajectory.csv");
    writeText(dir_ / "traffic_counts.csv", kCounts);
    writeText(dir_ / "traffic_movements.csv", kMovements);
    writeText(dir_ / "traffic_zones.csv", kZones);
    writeText(dir_ / "traffic_lanes.csv", kLanes);
    writeText(dir_ / "traffic_events.csv", eventsText());
  }
  void TearDown() override { fs::remove_all(dir_); }

  MapExportOptions allInputs() const {
    MapExportOptions o;
    o.trajectoryPath = (dir_ / "trajectory.csv").string();
    o.sitePath = (dir_ / "site.geojson").string();
    o.countsPath = (dir_ / "traffic_counts.csv").string();
    o.movementsPath = (dir_ / "traffic_movements.csv").string();
    o.zonesPath = (dir_ / "traffic_zones.csv").string();
    o.lanesPath = (dir_ / "traffic_lanes.csv").string();
    o.eventsPath = (dir_ / "traffic_events.csv").string();
    o.origin = kOrigin;
    return o;
  }

  // The refusal of these options' inputs.
  std::string refusal(const MapExportOptions& options) const {
    std::string geojson;
    std::string why;
    EXPECT_FALSE(exportMap(options, &geojson, nullptr, &why));
    return why;
  }

  fs::path dir_;
};

// Structure of the map (RFC 7946); returns the features by "layer" and "id"/"track_id"/"kind".
std::map<std::string, YAML::Node> checkStructure(const std::string& geojson) {
  const YAML::Node root = YAML::Load(geojson);  // JSON is YAML 1.2's flow style
  EXPECT_EQ(root["type"].as<std::string>(), "FeatureCollection");
  EXPECT_FALSE(root["crs"]) << "RFC 7946 has no crs member";
  std::map<std::string, YAML::Node> byName;
  for (const YAML::Node& f : root["features"]) {
    EXPECT_EQ(f["type"].as<std::string>(), "Feature");
    const YAML::Node props = f["properties"];
    EXPECT_TRUE(props.IsMap());
    const std::string type = f["geometry"]["type"].as<std::string>();
    const YAML::Node c = f["geometry"]["coordinates"];
    std::vector<YAML::Node> positions;
    if (type == "Point") {
      positions.push_back(c);
    } else if (type == "LineString") {
      EXPECT_GE(c.size(), 2U);
      for (const YAML::Node& p : c) {
        positions.push_back(p);
      }
    } else if (type == "Polygon") {
      EXPECT_EQ(c.size(), 1U) << "one outer ring";
      EXPECT_GE(c[0].size(), 4U);
      EXPECT_EQ(c[0][0][0].as<double>(), c[0][c[0].size() - 1][0].as<double>()) << "closed";
      EXPECT_EQ(c[0][0][1].as<double>(), c[0][c[0].size() - 1][1].as<double>()) << "closed";
      for (const YAML::Node& p : c[0]) {
        positions.push_back(p);
      }
    } else {
      ADD_FAILURE() << "unexpected geometry " << type;
    }
    for (const YAML::Node& p : positions) {
      EXPECT_EQ(p.size(), 2U);
      EXPECT_LE(std::abs(p[0].as<double>()), 180.0);
      EXPECT_LE(std::abs(p[1].as<double>()), 90.0);
    }
    const std::string layer = props["layer"].as<std::string>();
    std::string name = layer + ":";
    if (layer == "track") {
      name += props["track_id"].as<std::string>();
    } else if (layer == "event") {
      name += props["kind"].as<std::string>();
    } else if (layer == "movement") {
      name += props["from_gate_id"].as<std::string>() + ">" + props["to_gate_id"].as<std::string>();
    } else {
      name += props["id"].as<std::string>();
    }
    EXPECT_EQ(byName.count(name), 0U) << name << " twice";
    byName[name] = f;
  }
  return byName;
}

double number(const YAML::Node& feature, const char* property) {
  return feature["properties"][property].as<double>();
}

void expectAt(const YAML::Node& position, const Eigen::Vector2d& lonLat) {
  EXPECT_NEAR(position[0].as<double>(), lonLat.x(), kDegreeTolerance);
  EXPECT_NEAR(position[1].as<double>(), lonLat.y(), kDegreeTolerance);
}

TEST_F(MapExport, TracksSiteCountsZonesMovementsAndEventsHoldWhatTheInputsSay) {
  std::string geojson;
  std::string why;
  MapExportSummary summary;
  ASSERT_TRUE(exportMap(allInputs(), &geojson, &summary, &why)) << why;
  const std::map<std::string, YAML::Node> f = checkStructure(geojson);
  EXPECT_EQ(summary.tracks, 3U);
  EXPECT_EQ(summary.tracksTooShort, 1U);  // track 2: one row
  EXPECT_EQ(summary.siteFeatures, 5U);
  EXPECT_EQ(summary.events, 2U);
  EXPECT_EQ(summary.movements, 1U);
  EXPECT_EQ(f.size(), 3U + 5U + 2U + 1U);
  EXPECT_EQ(f.count("track:2"), 0U);

  // Track 1: 100 m at 10 m/s over 10 s, from (-50, -3.5) to (50, -3.5).
  const YAML::Node& t1 = f.at("track:1");
  EXPECT_EQ(t1["geometry"]["type"].as<std::string>(), "LineString");
  EXPECT_EQ(t1["properties"]["type"].as<std::string>(), "sedan");
  EXPECT_EQ(number(t1, "points"), 101);
  EXPECT_NEAR(number(t1, "length_m"), 100.0, 1e-3);
  EXPECT_NEAR(number(t1, "mean_speed_mps"), 10.0, 1e-3);
  EXPECT_NEAR(number(t1, "max_speed_mps"), 10.0, 1e-3);
  EXPECT_NEAR(number(t1, "duration_s"), 10.0, 1e-3);
  EXPECT_NEAR(number(t1, "first_time_s"), 1.7e9, 1e-3);
  const YAML::Node line1 = t1["geometry"]["coordinates"];
  EXPECT_EQ(line1.size(), 101U);
  expectAt(line1[0], lonLat(-50.0, -3.5));
  expectAt(line1[line1.size() - 1], lonLat(50.0, -3.5));
  // Track 3 never moved: a point. Track 4 had ENU only: placed through the origin.
  EXPECT_EQ(f.at("track:3")["geometry"]["type"].as<std::string>(), "Point");
  expectAt(f.at("track:3")["geometry"]["coordinates"], lonLat(20.0, 3.5));
  const YAML::Node& t4 = f.at("track:4");
  EXPECT_NEAR(number(t4, "length_m"), 30.0, 1e-3);
  expectAt(t4["geometry"]["coordinates"][0], lonLat(3.5, -25.0));

  // The site: its features converted back to where the file put them; the clockwise zone
  // ring turned counter-clockwise; the name's escapes survive.
  const YAML::Node& road = f.at("site:road-1");
  EXPECT_EQ(road["properties"]["kind"].as<std::string>(), "drivable");
  EXPECT_EQ(road["properties"]["name"].as<std::string>(), "K\u00f6nigstra\u00dfe \"Nord\"");
  expectAt(road["geometry"]["coordinates"][0][0], lonLat(-60, -7));
  const YAML::Node zoneRing = f.at("site:box-1")["geometry"]["coordinates"][0];
  // The file's ring (-7,-7) (-7,7) (7,7) (7,-7), reversed.
  expectAt(zoneRing[0], lonLat(7, -7));
  expectAt(zoneRing[1], lonLat(7, 7));
  expectAt(zoneRing[3], lonLat(-7, -7));

  // Gate totals over both periods; a gate without rows counts zero.
  const YAML::Node& west = f.at("site:gate-w");
  EXPECT_EQ(number(west, "total"), 6);
  EXPECT_EQ(number(west, "forward"), 4);
  EXPECT_EQ(number(west, "backward"), 2);
  EXPECT_EQ(number(west, "forward_sedan"), 3);
  EXPECT_EQ(number(west, "forward_van"), 1);
  EXPECT_EQ(number(west, "backward_sedan"), 2);
  EXPECT_EQ(number(west, "forward_large"), 0);
  EXPECT_EQ(number(west, "movements_out"), 4);
  EXPECT_EQ(number(f.at("site:gate-e"), "total"), 0);
  EXPECT_EQ(number(f.at("site:gate-e"), "movements_in"), 4);
  const YAML::Node& movement = f.at("movement:gate-w>gate-e");
  EXPECT_EQ(number(movement, "count"), 4);
  expectAt(movement["geometry"]["coordinates"][0], lonLat(-9, 0));
  expectAt(movement["geometry"]["coordinates"][1], lonLat(9, 0));

  // Zone: its role as the site file gave it, time-weighted mean occupancy, the longest queue.
  const YAML::Node& zone = f.at("site:box-1");
  EXPECT_EQ(zone["properties"]["role"].as<std::string>(), "box_junction");
  EXPECT_FALSE(zone["properties"]["lane"]) << "only a queue zone names a lane";
  EXPECT_NEAR(number(zone, "mean_vehicles"), 1.5, 1e-9);
  EXPECT_EQ(number(zone, "max_vehicles"), 4);
  EXPECT_EQ(number(zone, "max_queue_vehicles"), 5);
  EXPECT_NEAR(number(zone, "max_queue_m"), 30.25, 1e-9);
  EXPECT_EQ(number(zone, "dwell_count"), 3);
  EXPECT_NEAR(number(zone, "mean_dwell_s"), 20.0, 1e-9);
  // Lane: vehicles and their mean speed over both periods.
  const YAML::Node& lane = f.at("site:lane-east");
  EXPECT_NEAR(number(lane, "width_m"), 3.25, 1e-9);
  EXPECT_EQ(number(lane, "vehicles"), 4);
  EXPECT_NEAR(number(lane, "mean_speed_mps"), 9.0, 1e-9);
  EXPECT_NEAR(number(lane, "max_speed_mps"), 12.0, 1e-9);

  // Events where they happened (the wrong-way one from its ENU position and the origin).
  expectAt(f.at("event:gate_crossing")["geometry"]["coordinates"], lonLat(-9.0, -3.5));
  expectAt(f.at("event:wrong_way")["geometry"]["coordinates"], lonLat(30.0, -3.5));
  EXPECT_EQ(f.at("event:wrong_way")["properties"]["time_ns"].as<std::int64_t>(),
            1700000001000000000);
  EXPECT_EQ(f.at("event:gate_crossing")["properties"]["direction"].as<std::string>(), "forward");
}

TEST_F(MapExport, SimplifyDropsVerticesCloserThanTheSpacingAlongTheLine) {
  std::vector<Eigen::Vector2d> line;
  for (int i = 0; i <= 10; ++i) {
    line.emplace_back(i, 0.0);
  }
  const std::vector<Eigen::Vector2d> kept = simplifyLine(line, 2.5);
  ASSERT_EQ(kept.size(), 4U);  // 0, 3, 6, then 10 in place of 9 (1 m before it)
  EXPECT_EQ(kept[1].x(), 3.0);
  EXPECT_EQ(kept[2].x(), 6.0);
  EXPECT_EQ(kept[3].x(), 10.0);
  EXPECT_EQ(simplifyLine(line, 0.0).size(), line.size());

  MapExportOptions o = allInputs();
  o.simplify_m = 5.0;
  std::string geojson;
  std::string why;
  ASSERT_TRUE(exportMap(o, &geojson, nullptr, &why)) << why;
  const std::map<std::string, YAML::Node> f = checkStructure(geojson);
  // Track 1: a vertex every 5 m over 100 m; its ends unchanged.
  const YAML::Node line1 = f.at("track:1")["geometry"]["coordinates"];
  EXPECT_EQ(line1.size(), 21U);
  EXPECT_EQ(number(f.at("track:1"), "vertices"), 21);
  EXPECT_NEAR(number(f.at("track:1"), "length_m"), 100.0, 1e-3) << "measured before simplifying";
  expectAt(line1[line1.size() - 1], lonLat(50.0, -3.5));
}

TEST_F(MapExport, TracksWithFewerRowsThanTheMinimumAreLeftOut) {
  MapExportOptions o = allInputs();
  o.minTrackPoints = 25;  // track 1 (101 rows) and 4 (31) stay, 2 (1) and 3 (20) go
  std::string geojson;
  std::string why;
  MapExportSummary summary;
  ASSERT_TRUE(exportMap(o, &geojson, &summary, &why)) << why;
  const std::map<std::string, YAML::Node> f = checkStructure(geojson);
  EXPECT_EQ(summary.tracks, 2U);
  EXPECT_EQ(summary.tracksTooShort, 2U);
  EXPECT_EQ(f.count("track:1") + f.count("track:4"), 2U);
  EXPECT_EQ(f.count("track:3"), 0U);
  o.minTrackPoints = 0;
  EXPECT_NE(refusal(o).find("--min-track-points"), std::string::npos);
}

TEST_F(MapExport, BadInputsAreRefusedNamingFileLineAndColumn) {
  MapExportOptions o = allInputs();
  const fs::path counts = dir_ / "traffic_counts.csv";
  const std::string header =
      "# vp_firmware_app traffic_counts.csv format_version 1\n"
      "period,start_ns,end_ns,gate_id,direction,type,count\n";
  // A gate the site does not have: gate_id starts at column 16 of line 3.
  writeText(counts, header + "0,0,60000000000,gate-x,forward,sedan,3\n");
  EXPECT_NE(refusal(o).find("traffic_counts.csv:3:17: gate_id: no gate 'gate-x' in "),
            std::string::npos)
      << refusal(o);
  // A lane id where a gate is expected is refused the same way.
  writeText(counts, header + "0,0,60000000000,lane-east,forward,sedan,3\n");
  EXPECT_NE(refusal(o).find("traffic_counts.csv:3:17: gate_id: no gate 'lane-east'"),
            std::string::npos);
  writeText(counts, header + "0,0,60000000000,gate-w,sideways,sedan,3\n");
  EXPECT_NE(refusal(o).find("traffic_counts.csv:3:24: direction: expected forward or backward"),
            std::string::npos)
      << refusal(o);
  writeText(counts, header + "0,0,60000000000,gate-w,forward,tank,3\n");
  EXPECT_NE(refusal(o).find("traffic_counts.csv:3:32: type: unknown vehicle type 'tank'"),
            std::string::npos)
      << refusal(o);
  writeText(counts, header + "0,60000000000,0,gate-w,forward,sedan,3\n");
  EXPECT_NE(refusal(o).find("traffic_counts.csv:3:15: end_ns: must be after start_ns"),
            std::string::npos)
      << refusal(o);
  writeText(counts, "# vp_firmware_app traffic_counts.csv format_version 2\n" +
                        header.substr(header.find('\n') + 1));
  EXPECT_NE(refusal(o).find("traffic_counts.csv:1:"), std::string::npos) << refusal(o);
  EXPECT_NE(refusal(o).find("format_version: expected 1, got '2'"), std::string::npos);
  writeText(counts, "period,start_ns,end_ns,gate,direction,type,count\n");
  EXPECT_NE(refusal(o).find("traffic_counts.csv:1: header: expected "), std::string::npos);
  writeText(counts, header + "0,0,60000000000,gate-w,forward,sedan\n");
  EXPECT_NE(refusal(o).find("traffic_counts.csv:3: expected 7 fields, got 6"), std::string::npos);
  writeText(counts, kCounts);

  // A zone twice in one period.
  writeText(dir_ / "traffic_zones.csv",
            kZones + "1,60000000000,90000000000,box-1,0,0.5,2,0,5,0,30.25,1,40,40\n");
  EXPECT_NE(refusal(o).find("traffic_zones.csv:5:27: zone_id: zone 'box-1' appears twice in "
                            "period 1"),
            std::string::npos)
      << refusal(o);
  writeText(dir_ / "traffic_zones.csv", kZones);

  // An event naming a feature the site does not have; one with a bad kind.
  const std::string events = eventsText();
  writeText(dir_ / "traffic_events.csv", events +
                                             "1700000002000000000,wrong_way,4,lane-9,,,large,"
                                             "5.000,30.000,-3.500,,\n");
  EXPECT_NE(refusal(o).find("traffic_events.csv:5:33: feature_id: no feature 'lane-9'"),
            std::string::npos)
      << refusal(o);
  writeText(dir_ / "traffic_events.csv",
            events + "1700000002000000000,u_turn,4,lane-east,,,large,5.000,30.000,-3.500,,\n");
  EXPECT_NE(refusal(o).find("traffic_events.csv:5:21: kind: unknown event kind 'u_turn'"),
            std::string::npos)
      << refusal(o);
  writeText(dir_ / "traffic_events.csv", events);

  // Rows without WGS84 need the origin: the message names the first such row's latitude_deg
  // (track 4's first row, the 4th row of frame 0, at column 66).
  o.origin.reset();
  const std::string why = refusal(o);
  EXPECT_NE(why.find("trajectory.csv:5:66: latitude_deg"), std::string::npos) << why;
  EXPECT_NE(why.find(": latitude_deg: empty, and no world frame origin"), std::string::npos) << why;
  o.origin = kOrigin;

  // A trajectory the product's reader refuses: its message (file:line:column) is passed on.
  std::string trajectory = readText(dir_ / "trajectory.csv");
  trajectory.replace(trajectory.find(",sedan,"), 7, ",sedxn,");
  writeText(dir_ / "trajectory.csv", trajectory);
  EXPECT_NE(refusal(o).find("trajectory.csv:2:"), std::string::npos) << refusal(o);

  // Statistics need the site; a site the loader refuses is named with its feature and line.
  o = allInputs();
  o.sitePath.clear();
  EXPECT_NE(refusal(o).find("traffic_counts.csv: traffic statistics are drawn on the site's "
                            "features: give the site file (--site)"),
            std::string::npos)
      << refusal(o);
  o = allInputs();
  o.trajectoryPath.clear();
  writeText(dir_ / "site.geojson", siteText().replace(siteText().find("\"gate\""), 6, "\"door\""));
  EXPECT_NE(refusal(o).find("site.geojson: feature 3 (id \"gate-w\", line 5): unknown kind"),
            std::string::npos)
      << refusal(o);
}

TEST_F(MapExport, EveryNameIsValidUtf8Json) {
  // Control characters and bytes that are not UTF-8 in a name are escaped or replaced.
  std::string site = siteText();
  site.replace(site.find("\"west\""), 6, "\"we\\tst \xff\"");
  writeText(dir_ / "site.geojson", site);
  MapExportOptions o;
  o.sitePath = (dir_ / "site.geojson").string();
  std::string geojson;
  std::string why;
  ASSERT_TRUE(exportMap(o, &geojson, nullptr, &why)) << why;
  EXPECT_NE(geojson.find(R"("name": "we\tst \ufffd")"), std::string::npos) << geojson;
  const std::map<std::string, YAML::Node> f = checkStructure(geojson);
  EXPECT_EQ(f.size(), 5U);
}

// The executable: its options, its exit statuses, and a map that strict JSON, RFC 7946 and
// GDAL's GeoJSON driver (QGIS's reader) accept (tests/map_export/check_geojson.py).
int run(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST_F(MapExport, TheToolWritesAMapThatGisProgramsOpen) {
  const std::string tool = VP_MAP_EXPORT;
  const std::string out = (dir_ / "map.geojson").string();
  const std::string log = (dir_ / "log.txt").string();
  EXPECT_EQ(run(tool + " --help > " + log), 0);
  EXPECT_NE(readText(log).find("--simplify-m"), std::string::npos);
  EXPECT_EQ(run(tool + " --out " + out + " --bogus 2> " + log), 2);
  EXPECT_NE(readText(log).find("unknown argument '--bogus'"), std::string::npos);
  EXPECT_EQ(run(tool + " --trajectory x.csv 2> " + log), 2) << "no --out";

  // --traffic finds the five files; the origin from a rig file.
  writeText(dir_ / "rig.yaml",
            "origin: {latitude_deg: 48.1371, longitude_deg: 11.575, height_m: 520}\n"
            "camera: {width_px: 32, height_px: 24, fx_px: 40.0, fy_px: 40.0}\n"
            "terrain: {dtm_path: dtm.tif, crs: utm:32N}\n");
  const std::string inputs = " --trajectory " + (dir_ / "trajectory.csv").string() + " --site " +
                             (dir_ / "site.geojson").string() + " --traffic " + dir_.string() +
                             " --rig " + (dir_ / "rig.yaml").string();
  ASSERT_EQ(run(tool + inputs + " --simplify-m 2 --out " + out + " > " + log), 0) << readText(log);
  EXPECT_NE(readText(log).find("3 tracks (1 with fewer than 2 rows left out"), std::string::npos)
      << readText(log);
  EXPECT_NE(readText(log).find("2 events"), std::string::npos) << readText(log);
  EXPECT_FALSE(fs::exists(out + ".tmp"));
  const std::string check = std::string("/usr/bin/python3 ") + VP_SOURCE_DIR +
                            "/tests/map_export/check_geojson.py --expect-features 11 " + out;
  EXPECT_EQ(run(check + " > " + log + " 2>&1"), 0) << readText(log);

  // A bad input: status 1, the message on stderr names the file and line, nothing written.
  fs::remove(out);
  writeText(dir_ / "traffic_lanes.csv", kLanes + "2,90000000000,95000000000,lane-east,x,1,1,1\n");
  EXPECT_EQ(run(tool + inputs + " --out " + out + " 2> " + log), 1);
  EXPECT_NE(readText(log).find("traffic_lanes.csv:5:"), std::string::npos) << readText(log);
  EXPECT_NE(readText(log).find("vehicles: not an integer 'x'"), std::string::npos);
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace vp::map_export
