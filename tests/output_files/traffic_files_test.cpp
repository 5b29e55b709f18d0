// The traffic files (docs/traffic_files.md): every column of the five files from hand-filled
// report structs, rows of count 0 left out, ids from the site's order, no allocation per period
// or event, refused rows counted, and the reader's checks.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "output_files/traffic_files.hpp"

namespace vp::output_files {
namespace {

namespace fs = std::filesystem;
using traffic::TrafficEvent;
using traffic::TrafficEventKind;
using traffic::TrafficStatistics;

class TrafficFilesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        fs::temp_directory_path() /
        ("vp_traffic_files_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
         "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    ids_.gates = {"north-in", "south-out", "east"};
    ids_.zones = {"box-1"};
    ids_.lanes = {"lane-a", "lane-b"};
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(TrafficFile file) const { return (dir_ / fileName(file)).string(); }
  std::vector<std::vector<std::string>> rows(TrafficFile file) const {
    TrafficFileRows read;
    std::string why;
    EXPECT_TRUE(readTrafficFile(path(file), file, &read, &why)) << why;
    return read.rows;
  }

  fs::path dir_;
  TrafficFeatureIds ids_;
  geodesy::LocalFrame frame_{geodesy::GeodeticPoint{48.1, 11.5, 520.0}};
};

TrafficStatistics makeStatistics() {
  TrafficStatistics s;
  s.sequence = 4;
  s.start_ns = 240'000'000'000;
  s.end_ns = 300'000'000'000;
  s.gateCount = 3;
  for (std::uint32_t g = 0; g < 3; ++g) {
    s.gates[g].gateIndex = g;
  }
  s.gates[0].byDirectionAndType[0][static_cast<std::size_t>(shape::VehicleType::Sedan)] = 7;
  s.gates[0].byDirectionAndType[1][static_cast<std::size_t>(shape::VehicleType::Van)] = 2;
  s.gates[2].byDirectionAndType[0][static_cast<std::size_t>(shape::VehicleType::Large)] = 1;
  s.movements[0][2] = 3;
  s.movements[2][1] = 1;
  s.zoneCount = 1;
  s.zones[0] = {0, 2, 1.25, 4, 1, 3, 6.5, 17.25, 5, 12.5, 40.125};
  s.laneCount = 2;
  s.lanes[0] = {0, 9, 11.5, 13.875, 15.0};
  s.lanes[1] = {1, 0, 0.0, 0.0, 0.0};
  s.wrongWayEvents = 1;
  return s;
}

TEST_F(TrafficFilesTest, WritesEveryColumnOfEveryFile) {
  TrafficFilesWriter writer;
  std::string why;
  ASSERT_TRUE(writer.open(dir_.string(), ids_, frame_, &why)) << why;
  EXPECT_EQ(writer.writeStatistics(makeStatistics()), TrafficWriteStatus::Ok);
  TrafficEvent crossing;
  crossing.kind = TrafficEventKind::GateCrossing;
  crossing.time_ns = 250'000'000'000;
  crossing.trackId = 17;
  crossing.featureIndex = 1;
  crossing.direction = 1;
  crossing.type = shape::VehicleType::Suv;
  crossing.speed_mps = 8.25;
  crossing.positionEnu_m = {100.0, -50.0};
  EXPECT_EQ(writer.writeEvent(crossing), TrafficWriteStatus::Ok);
  TrafficEvent movement = crossing;
  movement.kind = TrafficEventKind::TurningMovement;
  movement.featureIndex = 0;
  movement.toFeatureIndex = 2;
  EXPECT_EQ(writer.writeEvent(movement), TrafficWriteStatus::Ok);
  TrafficEvent wrongWay = crossing;
  wrongWay.kind = TrafficEventKind::WrongWay;
  wrongWay.featureIndex = 1;
  EXPECT_EQ(writer.writeEvent(wrongWay), TrafficWriteStatus::Ok);
  TrafficEvent box = crossing;
  box.kind = TrafficEventKind::BoxJunctionStop;
  box.featureIndex = 0;
  box.speed_mps = 0.0;
  EXPECT_EQ(writer.writeEvent(box), TrafficWriteStatus::Ok);
  EXPECT_EQ(writer.commit(), TrafficWriteStatus::Ok);
  ASSERT_TRUE(writer.close(&why)) << why;
  EXPECT_EQ(writer.errors(), 0U);

  std::ifstream first(path(TrafficFile::Counts));
  std::string comment;
  std::getline(first, comment);
  EXPECT_EQ(comment, "# vp_firmware_app traffic_counts.csv format_version 1");

  using Rows = std::vector<std::vector<std::string>>;
  EXPECT_EQ(rows(TrafficFile::Counts),
            (Rows{{"4", "240000000000", "300000000000", "north-in", "forward", "sedan", "7"},
                  {"4", "240000000000", "300000000000", "north-in", "backward", "van", "2"},
                  {"4", "240000000000", "300000000000", "east", "forward", "large", "1"}}));
  EXPECT_EQ(rows(TrafficFile::Movements),
            (Rows{{"4", "240000000000", "300000000000", "north-in", "east", "3"},
                  {"4", "240000000000", "300000000000", "east", "south-out", "1"}}));
  EXPECT_EQ(rows(TrafficFile::Zones),
            (Rows{{"4", "240000000000", "300000000000", "box-1", "2", "1.250", "4", "1", "3",
                   "6.500", "17.250", "5", "12.500", "40.125"}}));
  EXPECT_EQ(
      rows(TrafficFile::Lanes),
      (Rows{{"4", "240000000000", "300000000000", "lane-a", "9", "11.500", "13.875", "15.000"},
            {"4", "240000000000", "300000000000", "lane-b", "0", "0.000", "0.000", "0.000"}}));
  const Rows events = rows(TrafficFile::Events);
  ASSERT_EQ(events.size(), 4U);
  const geodesy::GeodeticPoint where = frame_.toGeodetic(Eigen::Vector3d(100.0, -50.0, 0.0));
  EXPECT_EQ(events[0][0], "250000000000");
  EXPECT_EQ(events[0][1], "gate_crossing");
  EXPECT_EQ(events[0][2], "17");
  EXPECT_EQ(events[0][3], "south-out");
  EXPECT_EQ(events[0][4], "");
  EXPECT_EQ(events[0][5], "backward");
  EXPECT_EQ(events[0][6], "suv");
  EXPECT_EQ(events[0][7], "8.250");
  EXPECT_EQ(events[0][8], "100.000");
  EXPECT_EQ(events[0][9], "-50.000");
  EXPECT_NEAR(std::stod(events[0][10]), where.latitude_deg, 1e-9);
  EXPECT_NEAR(std::stod(events[0][11]), where.longitude_deg, 1e-9);
  EXPECT_LT(std::stod(events[0][10]), 48.1);  // 50 m south of the origin
  EXPECT_EQ(events[1][1], "turning_movement");
  EXPECT_EQ(events[1][3], "north-in");
  EXPECT_EQ(events[1][4], "east");
  EXPECT_EQ(events[1][5], "");
  EXPECT_EQ(events[2][1], "wrong_way");
  EXPECT_EQ(events[2][3], "lane-b");
  EXPECT_EQ(events[3][1], "box_junction_stop");
  EXPECT_EQ(events[3][3], "box-1");
  EXPECT_EQ(events[3][7], "0.000");
}

TEST_F(TrafficFilesTest, RefusesUnknownFeaturesAndNonFiniteValuesAndCountsThem) {
  TrafficFilesWriter writer;
  std::string why;
  ASSERT_TRUE(writer.open(dir_.string(), ids_, frame_, &why)) << why;
  TrafficEvent event;
  event.featureIndex = 3;  // three gates
  EXPECT_EQ(writer.writeEvent(event), TrafficWriteStatus::UnknownFeature);
  event.featureIndex = 0;
  event.speed_mps = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(writer.writeEvent(event), TrafficWriteStatus::InvalidValue);
  TrafficStatistics s = makeStatistics();
  s.zoneCount = 2;  // one zone in the site
  EXPECT_EQ(writer.writeStatistics(s), TrafficWriteStatus::UnknownFeature);
  EXPECT_EQ(writer.errors(), 3U);
  ASSERT_TRUE(writer.close(&why)) << why;
  EXPECT_TRUE(rows(TrafficFile::Events).empty());
  TrafficFilesWriter closed;
  EXPECT_EQ(closed.writeEvent(event), TrafficWriteStatus::NotOpen);
}

TEST_F(TrafficFilesTest, RefusesIdsThatBreakTheCsvAndMissingDirectories) {
  TrafficFilesWriter writer;
  std::string why;
  TrafficFeatureIds bad = ids_;
  bad.gates.push_back("a,b");
  EXPECT_FALSE(writer.open(dir_.string(), bad, frame_, &why));
  EXPECT_NE(why.find("'a,b'"), std::string::npos) << why;
  EXPECT_FALSE(writer.open((dir_ / "missing").string(), ids_, frame_, &why));
  EXPECT_NE(why.find("traffic_counts.csv"), std::string::npos) << why;
  EXPECT_NE(why.find("cannot create"), std::string::npos) << why;
}

TEST_F(TrafficFilesTest, WriterAllocatesNothingPerPeriodOrEvent) {
  TrafficFilesWriter writer;
  std::string why;
  ASSERT_TRUE(writer.open(dir_.string(), ids_, frame_, &why)) << why;
  TrafficStatistics s = makeStatistics();
  TrafficEvent event;
  event.positionEnu_m = {10.0, 20.0};
  test::AllocationCounter counter;
  bool ok = true;
  for (int period = 0; period < 200; ++period) {
    s.sequence = static_cast<std::uint64_t>(period);
    ok = writer.writeStatistics(s) == TrafficWriteStatus::Ok && ok;
    for (int e = 0; e < 20; ++e) {
      event.time_ns = period * 1000 + e;
      event.featureIndex = static_cast<std::uint32_t>(e % 3);
      ok = writer.writeEvent(event) == TrafficWriteStatus::Ok && ok;
    }
    ok = writer.commit() == TrafficWriteStatus::Ok && ok;
  }
  counter.stop();
  EXPECT_TRUE(ok);
  EXPECT_EQ(counter.count(), 0U) << "allocations while writing 200 periods and 4000 events";
  ASSERT_TRUE(writer.close(&why)) << why;
  EXPECT_EQ(rows(TrafficFile::Counts).size(), 600U);
  EXPECT_EQ(rows(TrafficFile::Events).size(), 4000U);
}

TEST_F(TrafficFilesTest, ReaderNamesTheFileAndLine) {
  {
    std::ofstream(path(TrafficFile::Lanes))
        << "# vp_firmware_app traffic_lanes.csv format_version 1\n"
        << trafficColumns(TrafficFile::Lanes) << "\n"
        << "0,1,2,lane-a,3\n";
  }
  TrafficFileRows read;
  std::string why;
  EXPECT_FALSE(readTrafficFile(path(TrafficFile::Lanes), TrafficFile::Lanes, &read, &why));
  EXPECT_NE(why.find("traffic_lanes.csv:3: expected 8 fields, got 5"), std::string::npos) << why;
  EXPECT_FALSE(readTrafficFile(path(TrafficFile::Lanes), TrafficFile::Zones, &read, &why));
  EXPECT_NE(why.find(":1: expected"), std::string::npos) << why;
}

TEST(TrafficFeatureIdsTest, FollowsTheSiteOrderOfEachKind) {
  site::Site site("test");
  const std::vector<Eigen::Vector2d> line{{0.0, 0.0}, {5.0, 0.0}};
  const std::vector<Eigen::Vector2d> ring{{0.0, 0.0}, {5.0, 0.0}, {5.0, 5.0}};
  const auto add = [&](site::FeatureKind kind, const char* id) {
    site::Feature f;
    f.kind = kind;
    f.id = id;
    site.append(f, site::isArea(kind) ? std::span<const Eigen::Vector2d>(ring)
                                      : std::span<const Eigen::Vector2d>(line));
  };
  add(site::FeatureKind::Drivable, "road");
  add(site::FeatureKind::Gate, "g2");
  add(site::FeatureKind::Lane, "l1");
  add(site::FeatureKind::Gate, "g1");
  add(site::FeatureKind::Zone, "z1");
  const TrafficFeatureIds ids = trafficFeatureIds(site);
  EXPECT_EQ(ids.gates, (std::vector<std::string>{"g2", "g1"}));
  EXPECT_EQ(ids.zones, (std::vector<std::string>{"z1"}));
  EXPECT_EQ(ids.lanes, (std::vector<std::string>{"l1"}));
}

}  // namespace
}  // namespace vp::output_files
