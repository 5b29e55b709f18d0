// The trajectory file (docs/tracking.md): write/read round trip (values at the columns'
// precision, rewrite byte for byte), a writer that allocates nothing per row, and errors naming
// file:line:column.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "geometry/rotated_box.hpp"
#include "output_files/trajectory_file.hpp"

namespace vp::output_files {
namespace {

namespace fs = std::filesystem;
using tracking::TrackState;
using tracking::TrackStatus;
using tracking::Wgs84Position;

constexpr double kDegPerRad = 180.0 / geometry::kPi;

class TrajectoryFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        fs::temp_directory_path() /
        ("vp_trajectory_file_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
         "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  std::string readText(const std::string& name) const {
    std::ifstream file(path(name), std::ios::binary);
    std::ostringstream text;
    text << file.rdbuf();
    return text.str();
  }
  void writeText(const std::string& name, const std::string& text) const {
    std::ofstream(path(name), std::ios::binary) << text;
  }

  fs::path dir_;
};

// A track with every column used; values on the print grid of each column when `onGrid`
// (multiples of 1/8 for the mm columns, 1/4 degree, 1/16 for probabilities and gamma), else
// random values that are not round in decimal.
TrackState makeTrack(std::mt19937_64& rng, std::uint32_t id, bool onGrid) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto value = [&](double scale, double grid) {
    const double v = (unit(rng) - 0.5) * scale;
    return onGrid ? std::round(v / grid) * grid : v;
  };
  TrackState t;
  t.id = id;
  t.status = static_cast<TrackStatus>(id % 3);
  t.timestamp_ns = 1'700'000'000'000'000'000 + static_cast<std::int64_t>(id) * 100'000'000;
  t.centreEnu = {value(2000.0, 0.125), value(2000.0, 0.125)};
  t.rearAxleEnu = t.centreEnu + Eigen::Vector2d(value(4.0, 0.125), value(4.0, 0.125));
  t.headingEnu_rad = std::abs(value(700.0, 0.25)) / kDegPerRad;
  t.speed_mps = value(40.0, 0.125);
  t.speedSigma_mps = std::abs(value(2.0, 0.125));
  t.acceleration_mps2 = value(6.0, 0.125);
  t.accelerationSigma_mps2 = std::abs(value(2.0, 0.125));
  t.yawRate_radps = value(60.0, 0.125) / kDegPerRad;
  t.length_m = 3.0 + std::abs(value(4.0, 0.125));
  t.width_m = 1.5 + std::abs(value(1.0, 0.125));
  t.wheelbase_m = 0.6 * t.length_m;
  t.lengthVariance_m2 = onGrid ? std::abs(value(0.5, 1.0 / 64.0)) : std::abs(value(0.5, 0.0));
  t.widthVariance_m2 = onGrid ? std::abs(value(0.1, 1.0 / 64.0)) : std::abs(value(0.1, 0.0));
  if (onGrid) {
    t.typeProbabilities = {0.0625F, 0.0625F, 0.0625F, 0.0625F, 0.0625F, 0.0625F, 0.625F};
    std::rotate(t.typeProbabilities.begin(), t.typeProbabilities.begin() + id % 7,
                t.typeProbabilities.end());
  } else {
    float sum = 0.0F;
    for (float& p : t.typeProbabilities) {
      p = static_cast<float>(unit(rng));
      sum += p;
    }
    for (float& p : t.typeProbabilities) {
      p /= sum;
    }
  }
  t.type = static_cast<shape::VehicleType>(
      std::max_element(t.typeProbabilities.begin(), t.typeProbabilities.end()) -
      t.typeProbabilities.begin());
  t.shape.count = static_cast<int>(id % 4);  // 0 to 3 of 3 columns
  for (int s = 0; s < t.shape.count; ++s) {
    t.shape.gamma[static_cast<std::size_t>(s)] = static_cast<float>(value(4.0, 0.0625));
  }
  return t;
}

TEST_F(TrajectoryFileTest, HeaderIsSeed002ColumnsThenOurs) {
  TrajectoryFileWriter writer;
  std::string why;
  ASSERT_TRUE(writer.open(path("t.csv"), TrajectoryFileInfo{2}, &why)) << why;
  ASSERT_TRUE(writer.close(&why)) << why;
  const std::string text = readText("t.csv");
  EXPECT_EQ(
      text.rfind("frame_id,class_id,track_id,velocity,coordinate_world_x_opt,"
                 "coordinate_world_y_opt,coordinate_world_x,coordinate_world_y,time_s,status,",
                 0),
      0U)
      << text;
  EXPECT_NE(text.find(",p_large,gamma_1,gamma_2\n"), std::string::npos) << text;
  EXPECT_NE(text.find(",wheelbase_m,class_name,length_variance_m2,width_variance_m2,utm_zone,"
                      "utm_hemisphere,utm_easting_m,utm_northing_m,rear_axle_latitude_deg,"
                      "rear_axle_longitude_deg,rear_axle_height_m,p_estate,"),
            std::string::npos)
      << text;
  EXPECT_EQ(trajectoryColumns(2).size(), 40U);
  TrajectoryFile file;
  ASSERT_TRUE(readTrajectoryFile(path("t.csv"), &file, &why)) << why;
  EXPECT_EQ(file.info.gammaColumns, 2);
  EXPECT_TRUE(file.rows.empty());
}

TEST_F(TrajectoryFileTest, RoundTripIsExact) {
  std::mt19937_64 rng(6);
  std::vector<TrackState> grid;
  std::vector<TrackState> random;
  for (std::uint32_t id = 1; id <= 40; ++id) {
    grid.push_back(makeTrack(rng, id, true));
    random.push_back(makeTrack(rng, id, false));
  }
  const Wgs84Position wgs84{43.07312345, -89.40123456, 261.125};
  // UTM and the rear axle on every third row, on the print grid (mm, 1e-8 deg).
  tracking::TrajectoryPlace place;
  place.utmZone = 16;
  place.utmNorth = true;
  place.utmEasting_m = 304510.375;
  place.utmNorthing_m = 4771730.875;
  place.hasRearAxle = true;
  place.rearAxle = {43.07310001, -89.40125002, 260.5};
  tracking::TrajectoryPlace south = place;
  south.utmZone = 56;
  south.utmNorth = false;
  south.hasRearAxle = false;
  south.rearAxle = {};
  std::string why;
  for (const auto& [name, tracks] :
       {std::pair{"grid.csv", &grid}, std::pair{"random.csv", &random}}) {
    TrajectoryFileWriter writer;
    ASSERT_TRUE(writer.open(path(name), TrajectoryFileInfo{3}, &why)) << why;
    for (std::size_t i = 0; i < tracks->size(); ++i) {
      const tracking::TrajectoryPlace* rowPlace =
          i % 3 == 0 ? &place : (i % 3 == 1 ? &south : nullptr);
      ASSERT_TRUE(writer.writeRow(static_cast<std::int64_t>(i / 4), (*tracks)[i],
                                  i % 2 == 0 ? &wgs84 : nullptr, &why, rowPlace))
          << why;
    }
    ASSERT_TRUE(writer.close(&why)) << why;
  }
  // Values on the print grid come back bit for bit.
  TrajectoryFile file;
  ASSERT_TRUE(readTrajectoryFile(path("grid.csv"), &file, &why)) << why;
  ASSERT_EQ(file.rows.size(), grid.size());
  for (std::size_t i = 0; i < grid.size(); ++i) {
    const TrackState& t = grid[i];
    const TrajectoryRecord& r = file.rows[i];
    EXPECT_EQ(r.frameId, static_cast<std::int64_t>(i / 4));
    EXPECT_EQ(r.trackId, t.id);
    EXPECT_EQ(r.type, t.type);
    EXPECT_EQ(r.status, t.status);
    EXPECT_EQ(r.speed_mps, t.speed_mps);
    EXPECT_EQ(r.centreEnu, t.centreEnu);
    EXPECT_EQ(r.rearAxleEnu, t.rearAxleEnu);
    EXPECT_EQ(r.headingEnu_deg, std::round(t.headingEnu_rad * kDegPerRad * 4.0) / 4.0);
    EXPECT_EQ(r.yawRateDps, std::round(t.yawRate_radps * kDegPerRad * 8.0) / 8.0);
    EXPECT_EQ(r.speedSigma_mps, t.speedSigma_mps);
    EXPECT_EQ(r.acceleration_mps2, t.acceleration_mps2);
    EXPECT_EQ(r.accelerationSigma_mps2, t.accelerationSigma_mps2);
    EXPECT_EQ(r.length_m, t.length_m);
    EXPECT_EQ(r.width_m, t.width_m);
    EXPECT_EQ(r.lengthVariance_m2, t.lengthVariance_m2);
    EXPECT_EQ(r.widthVariance_m2, t.widthVariance_m2);
    const tracking::TrajectoryPlace expected =
        i % 3 == 0 ? place : (i % 3 == 1 ? south : tracking::TrajectoryPlace{});
    EXPECT_EQ(r.place.utmZone, expected.utmZone);
    EXPECT_EQ(r.place.utmNorth, expected.utmNorth);
    EXPECT_EQ(r.place.utmEasting_m, expected.utmEasting_m);
    EXPECT_EQ(r.place.utmNorthing_m, expected.utmNorthing_m);
    ASSERT_EQ(r.place.hasRearAxle, expected.hasRearAxle);
    EXPECT_EQ(r.place.rearAxle.latitude_deg, expected.rearAxle.latitude_deg);
    EXPECT_EQ(r.place.rearAxle.longitude_deg, expected.rearAxle.longitude_deg);
    EXPECT_EQ(r.place.rearAxle.height_m, expected.rearAxle.height_m);
    EXPECT_EQ(r.typeProbabilities, t.typeProbabilities);
    ASSERT_EQ(r.gamma.count, t.shape.count);
    for (int s = 0; s < t.shape.count; ++s) {
      EXPECT_EQ(r.gamma.gamma[static_cast<std::size_t>(s)],
                t.shape.gamma[static_cast<std::size_t>(s)]);
    }
    EXPECT_NEAR(r.timeS, 1.7e9 + 0.1 * t.id, 5e-7);  // the double nearest to the ms text
    ASSERT_EQ(r.centreWgs84.has_value(), i % 2 == 0);
    if (r.centreWgs84) {
      EXPECT_EQ(r.centreWgs84->latitude_deg, wgs84.latitude_deg);
      EXPECT_EQ(r.centreWgs84->longitude_deg, wgs84.longitude_deg);
      EXPECT_EQ(r.centreWgs84->height_m, wgs84.height_m);
    }
  }
  // Other values come back within half a unit of the column's last digit, and writing what
  // was read reproduces the file byte for byte.
  ASSERT_TRUE(readTrajectoryFile(path("random.csv"), &file, &why)) << why;
  ASSERT_EQ(file.rows.size(), random.size());
  TrajectoryFileWriter rewriter;
  ASSERT_TRUE(rewriter.open(path("rewritten.csv"), file.info, &why)) << why;
  for (std::size_t i = 0; i < random.size(); ++i) {
    const TrackState& t = random[i];
    const TrajectoryRecord& r = file.rows[i];
    EXPECT_LE(std::abs(r.speed_mps - t.speed_mps), 0.0005 + 1e-12);
    EXPECT_LE((r.centreEnu - t.centreEnu).lpNorm<Eigen::Infinity>(), 0.0005 + 1e-9);
    EXPECT_LE(std::abs(r.headingEnu_deg - t.headingEnu_rad * kDegPerRad), 0.005 + 1e-9);
    for (std::size_t k = 0; k < t.typeProbabilities.size(); ++k) {
      EXPECT_LE(std::abs(r.typeProbabilities[k] - t.typeProbabilities[k]), 0.00005 + 1e-7);
    }
    EXPECT_EQ(r.type, t.type);
    const TrackState back = toTrackState(r);
    EXPECT_LE(std::abs(r.lengthVariance_m2 - t.lengthVariance_m2), 0.0000005 + 1e-12);
    ASSERT_TRUE(rewriter.writeRow(r.frameId, back, r.centreWgs84 ? &*r.centreWgs84 : nullptr, &why,
                                  &r.place))
        << why;
  }
  ASSERT_TRUE(rewriter.close(&why)) << why;
  EXPECT_EQ(readText("rewritten.csv"), readText("random.csv"));
}

TEST_F(TrajectoryFileTest, WriterAllocatesNothingPerRow) {
  std::mt19937_64 rng(9);
  std::vector<TrackState> tracks;
  for (std::uint32_t id = 1; id <= 2000; ++id) {
    tracks.push_back(makeTrack(rng, id, false));
  }
  const Wgs84Position wgs84{43.0731, -89.4012, 260.5};
  TrajectoryFileWriter writer;
  std::string why;
  ASSERT_TRUE(writer.open(path("a.csv"), TrajectoryFileInfo{3}, &why)) << why;
  ASSERT_TRUE(writer.writeRow(0, tracks[0], &wgs84, &why)) << why;  // warm-up
  test::AllocationCounter counter;
  bool ok = true;
  for (std::size_t i = 1; i < tracks.size(); ++i) {
    // ~500 KB in all, one commit (write(2)) per frame of 50 tracks.
    ok = writer.writeRow(static_cast<std::int64_t>(i / 50), tracks[i], i % 2 ? &wgs84 : nullptr,
                         nullptr) &&
         ok;
    if (i % 50 == 49) {
      ok = writer.commit() && ok;
    }
  }
  ok = writer.flush(nullptr) && ok;
  counter.stop();
  EXPECT_TRUE(ok);
  EXPECT_EQ(counter.count(), 0U) << "allocations while writing 1999 rows";
  ASSERT_TRUE(writer.close(&why)) << why;
  TrajectoryFile file;
  ASSERT_TRUE(readTrajectoryFile(path("a.csv"), &file, &why)) << why;
  EXPECT_EQ(file.rows.size(), tracks.size());
}

TEST_F(TrajectoryFileTest, WriterRejectsWhatTheReaderWould) {
  std::mt19937_64 rng(3);
  TrajectoryFileWriter writer;
  std::string why;
  EXPECT_FALSE(writer.writeRow(0, makeTrack(rng, 1, true), nullptr, &why));
  EXPECT_NE(why.find("not open"), std::string::npos) << why;
  EXPECT_FALSE(writer.open(path("x.csv"), TrajectoryFileInfo{9}, &why));
  EXPECT_NE(why.find("gammaColumns"), std::string::npos) << why;
  EXPECT_FALSE(writer.open((dir_ / "missing" / "x.csv").string(), TrajectoryFileInfo{}, &why));
  EXPECT_NE(why.find("cannot create"), std::string::npos) << why;
  ASSERT_TRUE(writer.open(path("t.csv"), TrajectoryFileInfo{3}, &why)) << why;
  const auto expectRejected = [&](const TrackState& track, std::int64_t frameId,
                                  const std::string& field) {
    why.clear();
    EXPECT_FALSE(writer.writeRow(frameId, track, nullptr, &why));
    EXPECT_NE(why.find(": " + field + ": "), std::string::npos) << why;
  };
  TrackState t = makeTrack(rng, 7, true);
  TrackState bad = t;
  bad.speed_mps = std::nan("");
  expectRejected(bad, 0, "velocity");
  expectRejected(t, -1, "frame_id");
  bad = t;
  bad.type = static_cast<shape::VehicleType>((static_cast<int>(t.type) + 1) % 7);
  expectRejected(bad, 0, "class_id");
  bad = t;
  bad.typeProbabilities.fill(0.0F);
  expectRejected(bad, 0, "p_estate");
  bad = t;
  bad.shape.count = 4;
  expectRejected(bad, 0, "gamma_1");
  bad = t;
  bad.length_m = -1.0;
  expectRejected(bad, 0, "length_m");
  bad = t;
  bad.headingEnu_rad = -0.5;
  expectRejected(bad, 0, "heading_enu_deg");
  bad = t;
  bad.widthVariance_m2 = -0.01;
  expectRejected(bad, 0, "width_variance_m2");
  Wgs84Position wgs84{95.0, 8.0, 400.0};
  EXPECT_FALSE(writer.writeRow(0, t, &wgs84, &why));
  EXPECT_NE(why.find("latitude_deg"), std::string::npos) << why;
  tracking::TrajectoryPlace place;
  place.utmZone = 61;
  EXPECT_FALSE(writer.writeRow(0, t, nullptr, &why, &place));
  EXPECT_NE(why.find(": utm_zone: "), std::string::npos) << why;
  place.utmZone = 32;
  place.utmEasting_m = -5.0;
  EXPECT_FALSE(writer.writeRow(0, t, nullptr, &why, &place));
  EXPECT_NE(why.find(": utm_easting_m: "), std::string::npos) << why;
  place.utmEasting_m = 500000.0;
  place.hasRearAxle = true;
  place.rearAxle = {45.0, 190.0, 0.0};
  EXPECT_FALSE(writer.writeRow(0, t, nullptr, &why, &place));
  EXPECT_NE(why.find(": rear_axle_longitude_deg: "), std::string::npos) << why;
  EXPECT_EQ(writer.rowsWritten(), 0);
  ASSERT_TRUE(writer.writeRow(0, t, nullptr, &why)) << why;
  ASSERT_TRUE(writer.close(&why)) << why;
  EXPECT_FALSE(writer.close(&why));
}

TEST_F(TrajectoryFileTest, MalformedRowsNameFileLineAndColumn) {
  std::mt19937_64 rng(5);
  TrajectoryFileWriter writer;
  std::string why;
  ASSERT_TRUE(writer.open(path("good.csv"), TrajectoryFileInfo{2}, &why)) << why;
  TrackState a = makeTrack(rng, 3, true);  // rows without WGS84
  a.shape.count = 1;
  TrackState b = makeTrack(rng, 4, true);
  b.shape.count = 2;
  ASSERT_TRUE(writer.writeRow(5, a, nullptr, &why)) << why;
  ASSERT_TRUE(writer.writeRow(5, b, nullptr, &why)) << why;
  ASSERT_TRUE(writer.close(&why)) << why;
  const std::string good = readText("good.csv");
  std::vector<std::string> lines;
  std::istringstream split(good);
  for (std::string line; std::getline(split, line);) {
    lines.push_back(line);
  }
  ASSERT_EQ(lines.size(), 3U);
  // The start (0-based) and length of field `index` of a row.
  const auto field = [](const std::string& row, int index) {
    std::size_t start = 0;
    for (int i = 0; i < index; ++i) {
      start = row.find(',', start) + 1;
    }
    return std::make_pair(start, row.find(',', start) - start);
  };
  const std::string bad = path("bad.csv");
  const auto expectError = [&](const std::string& text, const std::string& message) {
    writeText("bad.csv", text);
    TrajectoryFile file;
    std::string problem;
    EXPECT_FALSE(readTrajectoryFile(bad, &file, &problem)) << message;
    EXPECT_NE(problem.find(message), std::string::npos) << "got: " << problem;
    EXPECT_TRUE(file.rows.empty());
  };
  // Replaces field `index` of line `line` (0-based) by `value`; the error is expected at
  // field `reported` of that line: "<file>:<line>:<column>: <message>".
  const auto expectFieldError = [&](int line, int index, const std::string& value, int reported,
                                    const std::string& message) {
    std::vector<std::string> copy = lines;
    std::string& row = copy[static_cast<std::size_t>(line)];
    const auto [start, length] = field(row, index);
    row.replace(start, length, value);
    std::string text;
    for (const std::string& l : copy) {
      text += l + "\n";
    }
    expectError(text, bad + ":" + std::to_string(line + 1) + ":" +
                          std::to_string(field(row, reported).first + 1) + ": " + message);
  };
  TrajectoryFile file;
  ASSERT_TRUE(readTrajectoryFile(path("good.csv"), &file, &why)) << why;
  ASSERT_EQ(file.rows.size(), 2U);
  expectFieldError(1, 3, "8.5x", 3, "velocity: not a number '8.5x'");
  expectFieldError(2, 9, "parked", 9, "status: unknown track status 'parked'");
  expectFieldError(1, 1, "9", 1, "class_id: must be in [0, 6], got 9");
  expectFieldError(2, 0, "4", 0, "frame_id: not in non-decreasing order (4 after 5)");
  expectFieldError(2, 2, std::to_string(a.id), 2, "track_id: track 3 appears twice in frame 5");
  expectFieldError(1, 10, "43.1", 11,
                   "longitude_deg: latitude_deg, longitude_deg, height_m must be all set or all "
                   "empty");
  expectFieldError(1, 13, "nan", 13, "heading_enu_deg: not finite 'nan'");
  expectFieldError(1, 13, "361", 13, "heading_enu_deg: must be in [0, 360], got '361'");
  expectFieldError(1, 18, "-4.5", 18, "length_m: must be >= 0 and finite, got '-4.5'");
  expectFieldError(1, 21, "van", 21, "class_name: must name class_id's type");
  expectFieldError(1, 22, "-0.5", 22, "length_variance_m2: must be >= 0 and finite, got '-0.5'");
  expectFieldError(1, 24, "61", 24,
                   "utm_zone: utm_zone, utm_hemisphere, utm_easting_m, utm_northing_m must be all "
                   "set or all empty");
  expectFieldError(1, 28, "43.1", 28,
                   "rear_axle_latitude_deg: rear_axle_latitude_deg, rear_axle_longitude_deg, "
                   "rear_axle_height_m must be all set or all empty");
  expectFieldError(1, 31, "0.9", 31, "p_estate: probabilities p_estate..p_large do not sum to 1");
  expectFieldError(2, 38, "", 39, "gamma_2: value after an empty gamma field");
  std::string header = lines[0];
  header.replace(field(header, 2).first, 8, "id");
  expectError(header + "\n" + lines[1] + "\n",
              bad + ":1: header: expected 'frame_id,class_id,track_id,");
  expectError(lines[0] + "\n" + lines[1] + ",0.5\n", bad + ":2: expected 40 fields, got 41");
  expectError(lines[0] + "\n\n" + lines[1] + "\n", bad + ":2: empty line");
  expectError("", bad + ":1: header: missing");
  expectError(lines[0] + ",gamma_3,gamma_4,gamma_5,gamma_6,gamma_7,gamma_8,gamma_9\n",
              bad + ":1: header: expected 38 to 46 columns (0 to 8 gamma columns), got 47");
  EXPECT_FALSE(readTrajectoryFile(path("none.csv"), &file, &why));
  EXPECT_NE(why.find("none.csv: cannot open"), std::string::npos) << why;
}

}  // namespace
}  // namespace vp::output_files
