// The detections file (docs/detections_file.md): exact write/read round trip for both key
// variants, errors naming file:line:column, and a writer that allocates nothing per row.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/resource.h>

#include <algorithm>
#include <cerrno>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "alloc_counter.hpp"
#include "output_files/detections_file.hpp"

namespace vp::output_files {
namespace {

namespace fs = std::filesystem;

class DetectionsFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        fs::temp_directory_path() /
        ("vp_detections_file_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
         "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  void writeText(const std::string& name, const std::string& text) const {
    std::ofstream(path(name), std::ios::binary) << text;
  }

  fs::path dir_;
};

// A record with every field used, from a random generator (values that are not round in
// decimal, so the round trip tests the shortest-form formatting).
DetectionRecord randomRecord(std::mt19937_64& rng, std::int64_t frameId, int detId, bool lifted) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  DetectionRecord r;
  r.frameId = frameId;
  r.detId = detId;
  r.score = static_cast<float>(unit(rng));
  r.box = {unit(rng) * 2592.0, unit(rng) * 2048.0, 20.0 + 40.0 * unit(rng), 8.0 + 10 * unit(rng),
           unit(rng) * 6.28};
  r.directionKnown = unit(rng) > 0.3;
  r.atFrameEdge = unit(rng) > 0.8;
  if (unit(rng) > 0.2) {  // else NaN: no verifier (an empty field)
    r.vehicleProbability = static_cast<float>(unit(rng));
  }
  float sum = 0.0F;
  for (float& p : r.typeProbabilities) {
    p = static_cast<float>(unit(rng));
    sum += p;
  }
  for (float& p : r.typeProbabilities) {
    p /= sum;
  }
  r.gamma.count = 3;
  for (int s = 0; s < 3; ++s) {
    r.gamma.gamma[static_cast<std::size_t>(s)] = static_cast<float>(4.0 * unit(rng) - 2.0);
  }
  r.liftStatus = lifted ? LiftStatus::Ok : LiftStatus::OutsideDtm;
  if (lifted) {
    r.positionEnu = {100 * unit(rng) - 50, 100 * unit(rng) - 50, 260 + unit(rng)};
    r.latitude_deg = 43.07 + 1e-3 * unit(rng);
    r.longitude_deg = -89.4 + 1e-3 * unit(rng);
    r.height_m = 260 + unit(rng);
    r.headingEnu_rad = 6.28 * unit(rng);
    r.dimensions_m = {4 + unit(rng), 1.7 + 0.2 * unit(rng), 1.4 + 0.3 * unit(rng)};
  }
  return r;
}

void expectSame(const DetectionRecord& a, const DetectionRecord& b) {
  EXPECT_EQ(a.frameId, b.frameId);
  EXPECT_EQ(a.imageStem(), b.imageStem());
  EXPECT_EQ(a.detId, b.detId);
  EXPECT_EQ(a.score, b.score);
  EXPECT_EQ(a.box.cx, b.box.cx);
  EXPECT_EQ(a.box.cy, b.box.cy);
  EXPECT_EQ(a.box.length, b.box.length);
  EXPECT_EQ(a.box.width, b.box.width);
  EXPECT_EQ(a.box.angle, b.box.angle);
  EXPECT_EQ(a.directionKnown, b.directionKnown);
  EXPECT_EQ(a.atFrameEdge, b.atFrameEdge);
  EXPECT_EQ(std::isnan(a.vehicleProbability), std::isnan(b.vehicleProbability));
  if (!std::isnan(a.vehicleProbability)) {
    EXPECT_EQ(a.vehicleProbability, b.vehicleProbability);
  }
  EXPECT_EQ(a.typeProbabilities, b.typeProbabilities);
  ASSERT_EQ(a.gamma.count, b.gamma.count);
  for (int i = 0; i < a.gamma.count; ++i) {
    EXPECT_EQ(a.gamma.gamma[static_cast<std::size_t>(i)],
              b.gamma.gamma[static_cast<std::size_t>(i)]);
  }
  EXPECT_EQ(a.liftStatus, b.liftStatus);
  if (a.liftStatus == LiftStatus::Ok) {
    EXPECT_EQ(a.positionEnu, b.positionEnu);
    EXPECT_EQ(a.latitude_deg, b.latitude_deg);
    EXPECT_EQ(a.longitude_deg, b.longitude_deg);
    EXPECT_EQ(a.height_m, b.height_m);
    EXPECT_EQ(a.headingEnu_rad, b.headingEnu_rad);
    EXPECT_EQ(a.dimensions_m, b.dimensions_m);
  }
}

TEST_F(DetectionsFileTest, RoundTripIsExactForFrameRows) {
  std::mt19937_64 rng(7);
  std::vector<DetectionRecord> written;
  for (int frame = 0; frame < 20; ++frame) {
    for (int det = 0; det < 5; ++det) {
      written.push_back(randomRecord(rng, frame * 3, det, (frame + det) % 3 != 0));
    }
  }
  written[4].gamma.count = 0;  // a large vehicle: no shape
  written[6].gamma.count = 2;  // fewer components than columns: trailing fields empty
  DetectionsFileInfo info;
  info.model = "detector r1 int8 (sha256 0123abcd)";
  info.source = "sim seed 7";
  DetectionsFileWriter writer;
  std::string why;
  ASSERT_TRUE(writer.open(path("d.csv"), info, &why)) << why;
  for (const DetectionRecord& r : written) {
    ASSERT_TRUE(writer.writeRow(r, &why)) << why;
  }
  ASSERT_TRUE(writer.close(&why)) << why;

  DetectionsFile file;
  ASSERT_TRUE(readDetectionsFile(path("d.csv"), &file, &why)) << why;
  EXPECT_EQ(file.info.key, DetectionsKey::FrameId);
  EXPECT_EQ(file.info.gammaColumns, 3);
  EXPECT_EQ(file.info.model, info.model);
  EXPECT_EQ(file.info.source, info.source);
  ASSERT_EQ(file.rows.size(), written.size());
  for (std::size_t i = 0; i < written.size(); ++i) {
    SCOPED_TRACE(i);
    expectSame(written[i], file.rows[i]);
  }
  EXPECT_EQ(file.lines.front(), 5);  // 3 metadata lines + the header
  EXPECT_EQ(file.formatVersion, kDetectionsFormatVersion);
  const auto edge = std::count_if(written.begin(), written.end(),
                                  [](const DetectionRecord& r) { return r.atFrameEdge; });
  const auto noVerifier = std::count_if(written.begin(), written.end(), [](const auto& r) {
    return std::isnan(r.vehicleProbability);
  });
  EXPECT_GT(edge, 0);  // both values of both new columns are exercised
  EXPECT_LT(edge, static_cast<long>(written.size()));
  EXPECT_GT(noVerifier, 0);
  EXPECT_LT(noVerifier, static_cast<long>(written.size()));
}

TEST_F(DetectionsFileTest, RoundTripIsExactForImageRows) {
  std::mt19937_64 rng(8);
  DetectionsFileInfo info;
  info.key = DetectionsKey::Image;
  info.gammaColumns = 0;
  DetectionsFileWriter writer;
  std::string why;
  ASSERT_TRUE(writer.open(path("y.csv"), info, &why)) << why;
  std::vector<DetectionRecord> written;
  for (const char* stem : {"0_13", "Drone2_(363)", "0_13x"}) {
    DetectionRecord r = randomRecord(rng, 0, static_cast<int>(written.size()), false);
    r.liftStatus = LiftStatus::NotLifted;
    r.gamma.count = 0;
    ASSERT_TRUE(r.setImageStem(stem));
    ASSERT_TRUE(writer.writeRow(r, &why)) << why;
    written.push_back(r);
  }
  ASSERT_TRUE(writer.close(&why)) << why;
  DetectionsFile file;
  ASSERT_TRUE(readDetectionsFile(path("y.csv"), &file, &why)) << why;
  EXPECT_EQ(file.info.key, DetectionsKey::Image);
  ASSERT_EQ(file.rows.size(), 3U);
  for (std::size_t i = 0; i < 3; ++i) {
    expectSame(written[i], file.rows[i]);
  }
  EXPECT_EQ(file.rows[1].imageStem(), "Drone2_(363)");
}

TEST_F(DetectionsFileTest, WriterAllocatesNothingPerRow) {
  std::mt19937_64 rng(9);
  std::vector<DetectionRecord> rows;
  for (int i = 0; i < 2000; ++i) {
    rows.push_back(randomRecord(rng, i / 10, i % 10, i % 2 == 0));
  }
  DetectionsFileWriter writer;
  std::string why;
  ASSERT_TRUE(writer.open(path("a.csv"), DetectionsFileInfo{}, &why)) << why;
  ASSERT_TRUE(writer.writeRow(rows[0], &why)) << why;  // warm-up
  test::AllocationCounter counter;
  bool ok = true;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    ok = writer.writeRow(rows[i], nullptr) && ok;  // ~150 KB in all
    if (i % 10 == 9) {
      ok = writer.commit() && ok;  // one write(2) per frame of 10 rows
    }
  }
  ok = writer.flush(nullptr) && ok;
  counter.stop();
  EXPECT_TRUE(ok);
  EXPECT_EQ(counter.count(), 0U) << "allocations while writing 1999 rows";
  ASSERT_TRUE(writer.close(&why)) << why;
  DetectionsFile file;
  ASSERT_TRUE(readDetectionsFile(path("a.csv"), &file, &why)) << why;
  EXPECT_EQ(file.rows.size(), rows.size());
}

std::string fileText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST_F(DetectionsFileTest, CommittedRowsAreInTheFileAtOnceAndOnlyCompleteRows) {
  // What a kill leaves: the rows of every committed frame, nothing of the frame being written.
  std::mt19937_64 rng(21);
  DetectionsFileWriter writer;
  std::string why;
  ASSERT_TRUE(writer.open(path("c.csv"), DetectionsFileInfo{}, &why)) << why;
  const std::string header = fileText(path("c.csv"));
  ASSERT_FALSE(header.empty()) << "the header is written at open";
  for (int det = 0; det < 3; ++det) {
    ASSERT_TRUE(writer.writeRow(randomRecord(rng, 0, det, det != 1), &why)) << why;
  }
  EXPECT_EQ(fileText(path("c.csv")), header) << "rows before the commit stay pending";
  ASSERT_TRUE(writer.commit());
  const std::string frame0 = fileText(path("c.csv"));
  EXPECT_GT(frame0.size(), header.size());
  EXPECT_EQ(frame0.back(), '\n');
  EXPECT_EQ(std::count(frame0.begin(), frame0.end(), '\n') -
                std::count(header.begin(), header.end(), '\n'),
            3);
  ASSERT_TRUE(writer.writeRow(randomRecord(rng, 1, 0, true), &why)) << why;
  EXPECT_EQ(fileText(path("c.csv")), frame0);
  ASSERT_TRUE(writer.close(&why)) << why;  // close commits the rest
  DetectionsFile file;
  ASSERT_TRUE(readDetectionsFile(path("c.csv"), &file, &why)) << why;
  EXPECT_EQ(file.rows.size(), 4U);
}

TEST_F(DetectionsFileTest, AFullDiskIsAnErrorWhenItHappens) {
  // /dev/full: every write fails with ENOSPC. The header is written at open, so a full disk
  // is a start-up error naming the file, not a count found at close.
  DetectionsFileWriter writer;
  std::string why;
  EXPECT_FALSE(writer.open("/dev/full", DetectionsFileInfo{}, &why));
  EXPECT_NE(why.find("/dev/full: write failed: No space left on device"), std::string::npos) << why;
}

TEST_F(DetectionsFileTest, AWriteThatFailsMidRunIsReportedAtThatCommitAndTheFileStaysWhole) {
  // A file-size limit stands in for a disk that fills during the run: the commit that crosses
  // it fails (EFBIG) at once, its rows are lost, and the file is cut back to its last complete
  // row; later commits fail too, and close() reports it.
  std::mt19937_64 rng(22);
  DetectionsFileWriter writer;
  std::string why;
  ASSERT_TRUE(writer.open(path("d.csv"), DetectionsFileInfo{}, &why)) << why;
  const std::size_t headerBytes = fs::file_size(path("d.csv"));
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  struct sigaction previousSignal {};
  ASSERT_EQ(sigaction(SIGXFSZ, &ignore, &previousSignal), 0);
  rlimit previousLimit{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &previousLimit), 0);
  rlimit limit = previousLimit;
  limit.rlim_cur = headerBytes + 2000;  // a few frames of rows
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &limit), 0);
  int failedAt = -1;
  for (int frame = 0; frame < 20 && failedAt < 0; ++frame) {
    for (int det = 0; det < 3; ++det) {
      EXPECT_TRUE(writer.writeRow(randomRecord(rng, frame, det, true), &why)) << why;
    }
    if (!writer.commit()) {
      failedAt = frame;
    }
  }
  const int error = writer.lastErrno();
  for (int det = 0; det < 3; ++det) {
    EXPECT_TRUE(writer.writeRow(randomRecord(rng, 20, det, true), &why)) << why;
  }
  const bool laterCommit = writer.commit();
  const bool closed = writer.close(&why);
  setrlimit(RLIMIT_FSIZE, &previousLimit);
  sigaction(SIGXFSZ, &previousSignal, nullptr);
  ASSERT_GT(failedAt, 0) << "the first frames fit, a later one does not";
  EXPECT_EQ(error, EFBIG);
  EXPECT_FALSE(laterCommit);
  EXPECT_FALSE(closed);
  EXPECT_NE(why.find("d.csv: write failed: File too large"), std::string::npos) << why;
  EXPECT_EQ(writer.rowsLost(), 6);  // the failed frame's and the later frame's rows
  const std::string text = fileText(path("d.csv"));
  ASSERT_FALSE(text.empty());
  EXPECT_EQ(text.back(), '\n') << "cut back to the last complete row";
  DetectionsFile file;
  ASSERT_TRUE(readDetectionsFile(path("d.csv"), &file, &why)) << why;
  EXPECT_EQ(file.rows.size(), static_cast<std::size_t>(3 * failedAt));
}

TEST_F(DetectionsFileTest, WriterRejectsBadRecordsWithoutWriting) {
  DetectionsFileWriter writer;
  std::string why;
  ASSERT_TRUE(writer.open(path("b.csv"), DetectionsFileInfo{}, &why)) << why;
  std::mt19937_64 rng(10);
  DetectionRecord r = randomRecord(rng, 1, 0, true);
  r.score = 1.5F;
  EXPECT_FALSE(writer.writeRow(r, &why));
  EXPECT_NE(why.find("score: must be in [0, 1]"), std::string::npos) << why;
  r = randomRecord(rng, 1, 0, true);
  r.box.angle = -0.1;
  EXPECT_FALSE(writer.writeRow(r, &why));
  EXPECT_NE(why.find("box_angle_rad"), std::string::npos) << why;
  r = randomRecord(rng, 1, 0, true);
  r.vehicleProbability = 1.25F;
  EXPECT_FALSE(writer.writeRow(r, &why));
  EXPECT_NE(why.find("vehicle_probability: must be in [0, 1]"), std::string::npos) << why;
  r = randomRecord(rng, 1, 0, true);
  r.headingEnu_rad = std::nan("");
  EXPECT_FALSE(writer.writeRow(r, &why));
  EXPECT_NE(why.find("heading_enu_rad: not finite"), std::string::npos) << why;
  EXPECT_EQ(writer.rowsWritten(), 0);
  ASSERT_TRUE(writer.close(&why)) << why;
}

TEST_F(DetectionsFileTest, WriterReportsAnUnwritablePath) {
  DetectionsFileWriter writer;
  std::string why;
  EXPECT_FALSE(writer.open(path("missing_dir/d.csv"), DetectionsFileInfo{}, &why));
  EXPECT_NE(why.find("missing_dir/d.csv: cannot create file"), std::string::npos) << why;
  EXPECT_FALSE(writer.writeRow(DetectionRecord{}, &why));
  EXPECT_NE(why.find("not open"), std::string::npos) << why;
}

// A valid two-row file (format 2), broken one way at a time.
const std::string kHeader =
    "frame_id,det_id,score,box_cx_px,box_cy_px,box_length_px,box_width_px,box_angle_rad,"
    "direction_known,at_frame_edge,vehicle_probability,type,p_estate,p_compact,p_sports,p_sedan,"
    "p_suv,p_van,p_large,gamma_0,gamma_1,gamma_2,lift_status,east_m,north_m,up_m,lat_deg,lon_deg,"
    "height_m,heading_enu_rad,length_m,width_m,height_m_vehicle";
const std::string kRow1 =
    "3,0,0.9,100.5,200.25,40,16,1.5,1,0,0.97,sedan,0,0,0,1,0,0,0,0.5,-1,0.25,ok,1,2,260,43.07,"
    "-89.4,260,0.5,4.5,1.8,1.45";
const std::string kRow2 =
    "4,0,0.8,10,20,30,12,0,0,1,,van,0.1,0.1,0.1,0.1,0.1,0.3,0.2,,,,outside_dtm,,,,,,,,,,";
// The same rows in format 1 (no at_frame_edge, vehicle_probability), which the reader still reads.
const std::string kHeaderFormat1 =
    "frame_id,det_id,score,box_cx_px,box_cy_px,box_length_px,box_width_px,box_angle_rad,"
    "direction_known,type,p_estate,p_compact,p_sports,p_sedan,p_suv,p_van,p_large,gamma_0,"
    "gamma_1,gamma_2,lift_status,east_m,north_m,up_m,lat_deg,lon_deg,height_m,heading_enu_rad,"
    "length_m,width_m,height_m_vehicle";
const std::string kRow1Format1 =
    "3,0,0.9,100.5,200.25,40,16,1.5,1,sedan,0,0,0,1,0,0,0,0.5,-1,0.25,ok,1,2,260,43.07,-89.4,"
    "260,0.5,4.5,1.8,1.45";

TEST_F(DetectionsFileTest, ValidFixtureReads) {
  writeText("ok.csv", "# model: m1\n" + kHeader + "\n" + kRow1 + "\n" + kRow2 + "\n");
  DetectionsFile file;
  std::string why;
  ASSERT_TRUE(readDetectionsFile(path("ok.csv"), &file, &why)) << why;
  ASSERT_EQ(file.rows.size(), 2U);
  EXPECT_EQ(file.rows[0].topType(), shape::VehicleType::Sedan);
  EXPECT_EQ(file.rows[0].gamma.count, 3);
  EXPECT_EQ(file.rows[1].gamma.count, 0);
  EXPECT_EQ(file.rows[1].liftStatus, LiftStatus::OutsideDtm);
  EXPECT_DOUBLE_EQ(file.rows[0].positionEnu.z(), 260.0);
  EXPECT_EQ(file.lines, (std::vector<int>{3, 4}));
  EXPECT_EQ(file.formatVersion, 2);
  EXPECT_FALSE(file.rows[0].atFrameEdge);
  EXPECT_FLOAT_EQ(file.rows[0].vehicleProbability, 0.97F);
  EXPECT_TRUE(file.rows[1].atFrameEdge);
  EXPECT_TRUE(std::isnan(file.rows[1].vehicleProbability));
}

TEST_F(DetectionsFileTest, FormatOneFilesStillRead) {
  for (const std::string& metadata : {std::string("# format_version: 1\n"), std::string()}) {
    SCOPED_TRACE(metadata);
    writeText("v1.csv", metadata + kHeaderFormat1 + "\n" + kRow1Format1 + "\n");
    DetectionsFile file;
    std::string why;
    ASSERT_TRUE(readDetectionsFile(path("v1.csv"), &file, &why)) << why;
    EXPECT_EQ(file.formatVersion, 1);
    ASSERT_EQ(file.rows.size(), 1U);
    EXPECT_EQ(file.rows[0].topType(), shape::VehicleType::Sedan);
    EXPECT_EQ(file.rows[0].gamma.count, 3);
    EXPECT_DOUBLE_EQ(file.rows[0].dimensions_m.z(), 1.45);
    EXPECT_FALSE(file.rows[0].atFrameEdge);  // not in format 1: unknown, read as false / NaN
    EXPECT_TRUE(std::isnan(file.rows[0].vehicleProbability));
  }
  // A declared version must match the header.
  writeText("mixed.csv", "# format_version: 1\n" + kHeader + "\n");
  DetectionsFile file;
  std::string why;
  EXPECT_FALSE(readDetectionsFile(path("mixed.csv"), &file, &why));
  EXPECT_NE(why.find("mixed.csv:2: header: expected"), std::string::npos) << why;
}

TEST_F(DetectionsFileTest, MalformedRowsNameFileLineAndColumn) {
  struct Case {
    std::string text;
    std::string expected;
  };
  const auto replaced = [](std::string row, const std::string& from, const std::string& to) {
    row.replace(row.find(from), from.size(), to);
    return row;
  };
  const std::vector<Case> cases{
      {kHeader + "\n" + replaced(kRow1, "100.5", "10x") + "\n",
       "bad.csv:2:9: box_cx_px: not a number '10x'"},
      {kHeader + "\n" + kRow1 + "\n" + replaced(kRow2, "outside_dtm", "lost") + "\n",
       "bad.csv:3:63: lift_status: unknown lift status 'lost'"},
      {kHeader + "\n" + replaced(kRow1, ",sedan,", ",van,") + "\n",
       "bad.csv:2:41: type: 'van' is not the most probable type (p_sedan 1)"},
      {kHeader + "\n" + replaced(kRow1, ",sedan,", ",truck,") + "\n",
       "bad.csv:2:41: type: unknown vehicle type 'truck'"},
      {kHeader + "\n" + replaced(kRow1, "0.9,", "1.2,") + "\n",
       "bad.csv:2:5: score: must be in [0, 1], got '1.2'"},
      {kHeader + "\n" + replaced(kRow1, "0,0,0,1,0,0,0,", "0,0,0,0.5,0,0,0,") + "\n",
       "bad.csv:2:47: p_estate: probabilities p_estate..p_large do not sum to 1"},
      {kHeader + "\n" + replaced(kRow1, "0.5,-1,0.25", "0.5,,0.25") + "\n",
       "bad.csv:2:66: gamma_2: value after an empty gamma field"},
      {kHeader + "\n" + replaced(kRow2, "outside_dtm,,,", "outside_dtm,1,,") + "\n",
       "bad.csv:2:75: east_m: must be empty when lift_status is outside_dtm, got '1'"},
      {kHeader + "\n" + replaced(kRow1, ",1.45", "") + "\n",
       "bad.csv:2: expected 33 fields, got 32"},
      {kHeader + "\n" + kRow2 + "\n" + kRow1 + "\n",
       "bad.csv:3:1: frame_id: not in non-decreasing order (3 after 4)"},
      {kHeader + "\n" + kRow1 + "\n" + kRow1 + "\n",
       "bad.csv:3:3: det_id: det_id 0 appears twice in frame 3"},
      {kHeader + "\n" + kRow1 + "\n\n", "bad.csv:3: empty line"},
      {"# model: a\n# colour: red\n" + kHeader + "\n", "bad.csv:2: unknown metadata key 'colour'"},
      {"# format_version: 3\n" + kHeader + "\n",
       "bad.csv:1: format_version: 3 not supported (this reader reads 1 to 2)"},
      {kHeader + "\n" + replaced(kRow1, ",1,0,0.97,", ",1,2,0.97,") + "\n",
       "bad.csv:2:34: at_frame_edge: expected 0 or 1, got '2'"},
      {kHeader + "\n" + replaced(kRow1, ",0.97,", ",1.5,") + "\n",
       "vehicle_probability: must be in [0, 1] (or empty: no verifier), got '1.5'"},
      {"id,det_id\n", "bad.csv:1: header: must start with 'frame_id,'"},
      {replaced(kHeader, "p_van", "p_bus") + "\n", "bad.csv:1: header: expected"},
      {"# model: only metadata\n", "bad.csv:2: header: missing"},
  };
  for (const Case& c : cases) {
    writeText("bad.csv", c.text);
    DetectionsFile file;
    std::string why;
    EXPECT_FALSE(readDetectionsFile(path("bad.csv"), &file, &why)) << c.text;
    EXPECT_NE(why.find(c.expected), std::string::npos)
        << "got: " << why << "\nexpected: " << c.expected;
    EXPECT_TRUE(file.rows.empty());
  }
  DetectionsFile file;
  std::string why;
  EXPECT_FALSE(readDetectionsFile(path("nothing.csv"), &file, &why));
  EXPECT_NE(why.find("nothing.csv: cannot open"), std::string::npos) << why;
}

TEST(LiftStatusWords, RoundTripEveryStatus) {
  for (int i = 0; i < kLiftStatusCount; ++i) {
    const auto status = static_cast<LiftStatus>(i);
    EXPECT_EQ(liftStatusFromString(toString(status)), status);
  }
  EXPECT_EQ(std::string(toString(LiftStatus::StalePose)), "stale_pose");
  EXPECT_FALSE(liftStatusFromString("OK").has_value());
}

}  // namespace
}  // namespace vp::output_files
