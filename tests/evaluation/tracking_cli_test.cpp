// vp_evaluate --tracks end to end on tests/fixtures/sequence_min: a trajectory file made from
// the ground truth (perfect), one with a known id swap, tracks beside a detections file with a
// reversed detection, several sequence/tracks pairs in one report, and the command's errors.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

#include <yaml-cpp/yaml.h>

#include "cli_test_support.hpp"
#include "evaluate_app.hpp"
#include "geometry/rotated_box.hpp"
#include "output_files/detections_file.hpp"
#include "output_files/trajectory_file.hpp"
#include "sequence/recorded_sequence.hpp"

namespace vp::evaluate {
namespace {

namespace fs = std::filesystem;
using geometry::kPi;

// The ground truth of sequence_min, frame by frame: frame 0 holds the moving sedan (track 1),
// frame 1 the sedan and the parked large vehicle (track 2).
class TrackingCli : public EvaluateCliTest {
 protected:
  TrackingCli() : EvaluateCliTest("vp_tracking_cli_") {}

  // One confirmed track row per ground-truth vehicle and frame, exactly on it; trackId(frame,
  // truth id) names its track. Two extra rows that are not hypotheses: a tentative and a lost
  // track far from every vehicle.
  std::string writeTracks(const std::string& name,
                          const std::function<std::uint32_t(std::int64_t, int)>& trackId) const {
    const std::string path = (dir_ / name).string();
    output_files::TrajectoryFileWriter writer;
    std::string why;
    EXPECT_TRUE(writer.open(path, output_files::TrajectoryFileInfo{3}, &why)) << why;
    for (const sequence::FrameRecord& frame : reader_.frames()) {
      for (const sequence::ObjectTruth& object : reader_.objects(frame.frameId)) {
        tracking::TrackState t;
        t.id = trackId(frame.frameId, object.trackId);
        t.status = tracking::TrackStatus::Confirmed;
        t.timestamp_ns = frame.timestamp_ns;
        t.centreEnu = object.positionEnu.head<2>();
        t.headingEnu_rad = geometry::wrapTwoPi(object.headingEnu_rad);
        t.rearAxleEnu = t.centreEnu - 1.4 * Eigen::Vector2d(std::cos(t.headingEnu_rad),
                                                            std::sin(t.headingEnu_rad));
        t.speed_mps = object.speed_mps;
        t.length_m = object.dimensions_m.x();
        t.width_m = object.dimensions_m.y();
        t.wheelbase_m = 0.6 * t.length_m;
        t.typeProbabilities.fill(0.0F);
        t.typeProbabilities[static_cast<std::size_t>(object.type)] = 1.0F;
        t.type = object.type;
        t.shape = object.shape;
        EXPECT_TRUE(writer.writeRow(frame.frameId, t, nullptr, &why)) << why;
      }
      tracking::TrackState other;
      other.id = 90 + static_cast<std::uint32_t>(frame.frameId);
      other.status =
          frame.frameId == 0 ? tracking::TrackStatus::Tentative : tracking::TrackStatus::Lost;
      other.centreEnu = {300.0, 300.0};
      other.typeProbabilities.fill(1.0F / 7.0F);
      other.type = shape::VehicleType::Estate;
      EXPECT_TRUE(writer.writeRow(frame.frameId, other, nullptr, &why)) << why;
    }
    EXPECT_TRUE(writer.close(&why)) << why;
    return path;
  }

  // One lifted detection per ground-truth vehicle; the sedan in frame 1 is reversed and the
  // large vehicle called a van.
  std::string writeDetections(const std::string& name) const {
    const std::string path = (dir_ / name).string();
    output_files::DetectionsFileWriter writer;
    std::string why;
    EXPECT_TRUE(writer.open(path, output_files::DetectionsFileInfo{}, &why)) << why;
    for (const sequence::FrameRecord& frame : reader_.frames()) {
      int detId = 0;
      for (const sequence::ObjectTruth& object : reader_.objects(frame.frameId)) {
        output_files::DetectionRecord r = perfectDetection(frame.frameId, detId++, object);
        r.gamma = shape::ShapeParams{};  // no shape
        const bool large = object.type == shape::VehicleType::Large;
        if (large) {
          r.typeProbabilities.fill(0.0F);
          r.typeProbabilities[static_cast<std::size_t>(shape::VehicleType::Van)] = 1.0F;
        }
        r.headingEnu_rad =
            geometry::wrapTwoPi(object.headingEnu_rad + (frame.frameId == 1 && !large ? kPi : 0.0));
        EXPECT_TRUE(writer.writeRow(r, &why)) << why;
      }
    }
    EXPECT_TRUE(writer.close(&why)) << why;
    return path;
  }

  static YAML::Node tracking(const std::string& outDir) {
    return YAML::LoadFile(outDir + "/report.json")["tracking"];
  }
};

std::uint32_t sameAsTruth(std::int64_t, int truthId) {
  return static_cast<std::uint32_t>(truthId);
}

TEST_F(TrackingCli, TracksFromTheGroundTruthArePerfect) {
  const std::string tracks = writeTracks("perfect.csv", sameAsTruth);
  const std::string out = (dir_ / "report").string();
  const CommandResult result =
      run("--sequence " + kSequence + " --tracks " + tracks + " --out " + out);
  ASSERT_EQ(result.exitCode, 0) << result.err;
  const YAML::Node t = tracking(out);
  ASSERT_TRUE(t) << readText(out + "/report.json");
  const YAML::Node m = t["measures"];
  EXPECT_DOUBLE_EQ(m["mota"].as<double>(), 1.0);
  EXPECT_DOUBLE_EQ(m["idf1"].as<double>(), 1.0);
  EXPECT_EQ(m["id_switches"].as<int>(), 0);
  EXPECT_EQ(m["fragmentations"].as<int>(), 0);
  EXPECT_EQ(m["truth_objects"].as<int>(), 3);
  EXPECT_EQ(m["hypotheses"].as<int>(), 3);  // the tentative and the lost rows are not
  EXPECT_EQ(m["mostly_tracked"].as<int>(), 2);
  EXPECT_DOUBLE_EQ(m["motp_m"].as<double>(), 0.0);
  EXPECT_DOUBLE_EQ(m["speed_rmse_mps"].as<double>(), 0.0);
  EXPECT_EQ(t["samples"]["speed_rmse_mps"].as<int>(), 2);  // the sedan; the large is parked
  EXPECT_DOUBLE_EQ(m["heading_flip_share_tracks"].as<double>(), 0.0);
  EXPECT_DOUBLE_EQ(m["type_oa1_per_track"].as<double>(), 1.0);
  EXPECT_EQ(t["samples"]["type_oa1_per_track"].as<int>(), 2);
  EXPECT_TRUE(m["heading_flip_share_detector"].IsNull());  // no detections file
  EXPECT_FALSE(t["detector"].as<bool>());
  EXPECT_DOUBLE_EQ(t["match_distance_m"].as<double>(), 2.0);
  const YAML::Node input = t["inputs"][0];
  EXPECT_EQ(input["confirmed_rows"].as<int>(), 3);
  EXPECT_EQ(input["tentative_rows"].as<int>(), 1);
  EXPECT_EQ(input["lost_rows"].as<int>(), 1);
  // Tracks alone: no detection sections, no orientation plot.
  const YAML::Node report = YAML::LoadFile(out + "/report.json");
  EXPECT_FALSE(report["measures"]);
  EXPECT_FALSE(fs::exists(out + "/orientation_cdf.png"));
  const std::string md = readText(out + "/report.md");
  EXPECT_NE(md.find("## Tracking"), std::string::npos) << md;
  EXPECT_EQ(md.find("## Detection"), std::string::npos) << md;
  EXPECT_NE(md.find("| MOTA = 1 − (misses + false positives + ID switches) / vehicle-frames | "
                    "1.000 | 3 |"),
            std::string::npos)
      << md;
  EXPECT_NE(result.out.find("MOTA 1 IDF1 1 ID switches 0"), std::string::npos) << result.out;
}

TEST_F(TrackingCli, KnownIdSwapIsCounted) {
  // Frame 0: the sedan is track 10. Frame 1: the sedan is track 11, the large vehicle 10.
  const std::string tracks =
      writeTracks("swap.csv", [](std::int64_t frame, int truthId) -> std::uint32_t {
        if (frame == 0) {
          return 10;
        }
        return truthId == 1 ? 11 : 10;
      });
  const std::string out = (dir_ / "report").string();
  const CommandResult result =
      run("--sequence " + kSequence + " --tracks " + tracks + " --out " + out);
  ASSERT_EQ(result.exitCode, 0) << result.err;
  const YAML::Node m = tracking(out)["measures"];
  EXPECT_EQ(m["id_switches"].as<int>(), 1);
  EXPECT_NEAR(m["mota"].as<double>(), 1.0 - 1.0 / 3.0, 1e-12);
  // Identity: sedan <-> 10 (1 frame) or 11 (1 frame), large <-> 10: at best 2 of 3 + 3.
  EXPECT_NEAR(m["idf1"].as<double>(), 2.0 * 2.0 / 6.0, 1e-12);
  EXPECT_EQ(m["fragmentations"].as<int>(), 0);
  EXPECT_EQ(m["tracks"].as<int>(), 2);
  EXPECT_DOUBLE_EQ(m["speed_rmse_mps"].as<double>(), 0.0);
  // Track 10 matched the sedan first (1 frame each): its fused type (large) is wrong.
  EXPECT_DOUBLE_EQ(m["type_oa1_per_track"].as<double>(), 0.5);
}

TEST_F(TrackingCli, TracksBesideTheDetectorAndSeveralPairs) {
  const std::string perfect = writeTracks("perfect.csv", sameAsTruth);
  const std::string swap = writeTracks("swap.csv", [](std::int64_t frame, int truthId) {
    return static_cast<std::uint32_t>(frame == 0 ? 10 : (truthId == 1 ? 11 : 10));
  });
  const std::string detections = writeDetections("detections.csv");
  const std::string out = (dir_ / "report").string();
  const CommandResult result =
      run("--sequence " + kSequence + " --detections " + detections + " --tracks " + perfect +
          " --sequence " + kSequence + " --detections " + detections + " --tracks " + swap +
          " --out " + out + " --asm none");
  ASSERT_EQ(result.exitCode, 0) << result.err;
  const YAML::Node report = YAML::LoadFile(out + "/report.json");
  // Both sections: the detection measures of the two inputs and the tracking measures.
  EXPECT_EQ(report["measures"]["tp"].as<int>(), 6);
  const YAML::Node t = report["tracking"];
  const YAML::Node m = t["measures"];
  EXPECT_TRUE(t["detector"].as<bool>());
  EXPECT_EQ(t["inputs"].size(), 2U);
  EXPECT_EQ(t["inputs"][1]["id_switches"].as<int>(), 1);
  EXPECT_EQ(m["truth_objects"].as<int>(), 6);
  EXPECT_EQ(m["truth_vehicles"].as<int>(), 4);  // the same ids in two sequences stay apart
  EXPECT_EQ(m["id_switches"].as<int>(), 1);
  EXPECT_NEAR(m["mota"].as<double>(), 1.0 - 1.0 / 6.0, 1e-12);
  // Heading flips on the moving sedan (2 frames per sequence): tracks none, the detector one
  // frame of two.
  EXPECT_DOUBLE_EQ(m["heading_flip_share_tracks"].as<double>(), 0.0);
  EXPECT_DOUBLE_EQ(m["heading_flip_share_detector"].as<double>(), 0.5);
  EXPECT_EQ(t["samples"]["heading_flip_share_detector"].as<int>(), 4);
  // Type: the detector calls the large vehicle a van (1 of 3 per sequence); per track: all
  // right in the perfect run, 1 of 2 in the swapped one.
  EXPECT_NEAR(m["type_oa1_detector_per_frame"].as<double>(), 4.0 / 6.0, 1e-12);
  EXPECT_DOUBLE_EQ(m["type_oa1_per_track"].as<double>(), 3.0 / 4.0);
  EXPECT_EQ(m["detections_matched"].as<int>(), 6);
  const std::string md = readText(out + "/report.md");
  EXPECT_NE(md.find("| heading error > 90° on moving vehicles (front/back swapped) | 0.0 % | 4 | "
                    "50.0 % | 4 |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("## Detection"), std::string::npos);
}

TEST_F(TrackingCli, BadTrackFilesAndArgumentsAreNamed) {
  const std::string out = (dir_ / "report").string();
  // A row of a frame the sequence does not have.
  const std::string foreign = (dir_ / "foreign.csv").string();
  {
    output_files::TrajectoryFileWriter writer;
    std::string why;
    ASSERT_TRUE(writer.open(foreign, output_files::TrajectoryFileInfo{0}, &why)) << why;
    tracking::TrackState t;
    t.id = 1;
    t.status = tracking::TrackStatus::Confirmed;
    t.typeProbabilities.fill(0.0F);
    t.typeProbabilities[3] = 1.0F;
    t.type = shape::VehicleType::Sedan;
    ASSERT_TRUE(writer.writeRow(7, t, nullptr, &why)) << why;
    ASSERT_TRUE(writer.close(&why)) << why;
  }
  CommandResult result = run("--sequence " + kSequence + " --tracks " + foreign + " --out " + out);
  EXPECT_EQ(result.exitCode, 1);
  EXPECT_NE(result.err.find(foreign + ":2: frame_id: no frame 7 in " + kSequence),
            std::string::npos)
      << result.err;
  // A malformed row: the reader's file:line:column message.
  std::string text = readText(foreign);
  text.replace(text.find("confirmed"), 9, "parked");
  std::ofstream((dir_ / "broken.csv").string(), std::ios::binary) << text;
  result = run("--sequence " + kSequence + " --tracks " + (dir_ / "broken.csv").string() +
               " --out " + out);
  EXPECT_EQ(result.exitCode, 1);
  EXPECT_NE(result.err.find("broken.csv:2:"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("status: unknown track status 'parked'"), std::string::npos)
      << result.err;
  // Usage errors.
  EvaluateOptions options;
  std::string why;
  const std::vector<std::string> mismatch{"--sequence", "a", "--sequence", "b",
                                          "--tracks",   "t", "--out",      "o"};
  EXPECT_FALSE(parseArguments(mismatch, &options, &why));
  EXPECT_NE(why.find("each --sequence needs its --tracks: got 2 sequences and 1"),
            std::string::npos)
      << why;
  const std::vector<std::string> yolo{"--yolo",   "y", "--detections", "d",
                                      "--tracks", "t", "--out",        "o"};
  EXPECT_FALSE(parseArguments(yolo, &options, &why));
  EXPECT_NE(why.find("--tracks needs --sequence"), std::string::npos) << why;
  const std::vector<std::string> gate{"--sequence",   "a", "--tracks", "t",
                                      "--track-gate", "0", "--out",    "o"};
  EXPECT_FALSE(parseArguments(gate, &options, &why));
  EXPECT_NE(why.find("--track-gate"), std::string::npos) << why;
  const std::vector<std::string> alone{"--sequence", "a", "--out", "o"};
  EXPECT_FALSE(parseArguments(alone, &options, &why));
  EXPECT_NE(why.find("--detections FILE and/or --tracks FILE"), std::string::npos) << why;
  const std::vector<std::string> good{"--sequence",     "a", "--tracks", "t",
                                      "--moving-speed", "1", "--out",    "o"};
  ASSERT_TRUE(parseArguments(good, &options, &why)) << why;
  ASSERT_EQ(options.sequences.size(), 1U);
  EXPECT_EQ(options.sequences[0].tracksFile, "t");
  EXPECT_TRUE(options.sequences[0].detectionsFile.empty());
  EXPECT_DOUBLE_EQ(options.movingSpeed_mps, 1.0);
}

}  // namespace
}  // namespace vp::evaluate
