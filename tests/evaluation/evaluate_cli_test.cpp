// vp_evaluate end to end: detections generated from the ground truth of
// tests/fixtures/sequence_min (perfect, then with known perturbations), a tiny YOLO folder,
// and the command's errors.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cli_test_support.hpp"
#include "evaluate_app.hpp"
#include "geometry/rotated_box.hpp"
#include "output_files/detections_file.hpp"
#include "sequence/recorded_sequence.hpp"

namespace vp::evaluate {
namespace {

namespace fs = std::filesystem;
using geometry::kPi;

constexpr double kDegPerRad = 180.0 / kPi;

class EvaluateCli : public EvaluateCliTest {
 protected:
  EvaluateCli() : EvaluateCliTest("vp_evaluate_cli_") {}

  // One perfect detection per ground-truth object; `perturb` edits it (object index, record).
  template <typename Perturb>
  std::string writeDetections(const std::string& name, Perturb perturb,
                              bool extraFalsePositive) const {
    const std::string path = (dir_ / name).string();
    output_files::DetectionsFileWriter writer;
    output_files::DetectionsFileInfo info;
    info.model = "ground truth copy";
    std::string why;
    EXPECT_TRUE(writer.open(path, info, &why)) << why;
    int index = 0;
    for (const sequence::FrameRecord& frame : reader_.frames()) {
      int detId = 0;
      for (const sequence::ObjectTruth& object : reader_.objects(frame.frameId)) {
        output_files::DetectionRecord r = perfectDetection(frame.frameId, detId++, object);
        r.score = 0.9F - 0.1F * static_cast<float>(index);
        perturb(index++, r);
        EXPECT_TRUE(writer.writeRow(r, &why)) << why;
      }
      if (extraFalsePositive && frame.frameId == 0) {
        output_files::DetectionRecord r;
        r.frameId = 0;
        r.detId = detId;
        r.score = 0.95F;
        r.box = {2, 2, 3, 1, 0};
        r.typeProbabilities.fill(1.0F / 7.0F);
        EXPECT_TRUE(writer.writeRow(r, &why)) << why;
      }
    }
    EXPECT_TRUE(writer.close(&why)) << why;
    return path;
  }

  YAML::Node measures(const std::string& outDir) const {
    const YAML::Node report = YAML::LoadFile(outDir + "/report.json");
    return report["measures"];
  }
};

TEST_F(EvaluateCli, PerfectDetectionsGivePerfectMeasures) {
  const std::string detections = writeDetections(
      "perfect.csv", [](int, auto&) {}, false);
  const std::string out = (dir_ / "report").string();
  const CommandResult result =
      run("--sequence " + kSequence + " --detections " + detections + " --out " + out);
  ASSERT_EQ(result.exitCode, 0) << result.err;
  const YAML::Node m = measures(out);
  EXPECT_EQ(m["tp"].as<int>(), 3);
  EXPECT_EQ(m["fp"].as<int>(), 0);
  EXPECT_EQ(m["fn"].as<int>(), 0);
  for (const char* key :
       {"precision", "recall", "f1", "type_oa1", "type_oa2", "mean_matched_iou"}) {
    EXPECT_DOUBLE_EQ(m[key].as<double>(), 1.0) << key;
  }
  for (const char* key :
       {"position_median_px", "position_median_m", "position_mad_m", "position_world_median_m",
        "orientation_median_deg", "orientation_mad_deg", "orientation_flip_share",
        "heading_world_median_deg", "rms_length_m", "rms_width_m", "rms_height_m", "e_d2d_m",
        "e_dh_m", "e_d2d_world_m", "e_dh_world_m", "e_d2d_vehicle_m", "e_dh_vehicle_m",
        "lifted_rms_length_m"}) {
    EXPECT_NEAR(m[key].as<double>(), 0.0, 1e-9) << key;
  }
  EXPECT_EQ(m["shape_count"].as<int>(), 2);  // the large vehicle has no shape
  const YAML::Node report = YAML::LoadFile(out + "/report.json");
  EXPECT_EQ(report["model"].as<std::string>(), "ground truth copy");
  EXPECT_EQ(report["counts"]["images"].as<int>(), 2);
  EXPECT_DOUBLE_EQ(report["seed"]["precision"]["value"].as<double>(), 0.816);
  EXPECT_EQ(report["orientation_cumulative"].size(), 181U);
  const std::string md = readText(out + "/report.md");
  EXPECT_NE(md.find("| precision | 100.0 % |  | 81.6 % | Table 1, UAV V_L1 |"), std::string::npos)
      << md;
  EXPECT_NE(md.find("vp_evaluate --sequence"), std::string::npos);
  const cv::Mat plot = cv::imread(out + "/orientation_cdf.png");
  ASSERT_FALSE(plot.empty());
  EXPECT_EQ(plot.cols, 720);
}

TEST_F(EvaluateCli, KnownPerturbationsAreRecovered) {
  // Objects in file order: 0 = sedan frame 0 (box angle 3 pi / 2), 1 = sedan frame 1,
  // 2 = large frame 1 (angle 0).
  const auto perturb = [](int index, output_files::DetectionRecord& r) {
    switch (index) {
      case 0:  // 0.1 px along the box, driving direction reversed, lifted 0.3 m east
        r.box.cy += 0.1;
        r.box.angle = geometry::wrapTwoPi(r.box.angle + kPi);
        r.positionEnu.x() += 0.3;
        break;
      case 1:  // 0.2 px along the box, 5 degrees, lifted 0.1 m up, type right only second
        r.box.cy += 0.2;
        r.box.angle = geometry::wrapTwoPi(r.box.angle + 5.0 / kDegPerRad);
        r.positionEnu.z() += 0.1;
        r.typeProbabilities.fill(0.0F);
        r.typeProbabilities[static_cast<std::size_t>(shape::VehicleType::Suv)] = 0.7F;
        r.typeProbabilities[static_cast<std::size_t>(shape::VehicleType::Sedan)] = 0.3F;
        break;
      default:  // 0.3 px along the box
        r.box.cx += 0.3;
        break;
    }
  };
  const std::string detections = writeDetections("perturbed.csv", perturb, true);
  const std::string out = (dir_ / "report").string();
  const CommandResult result = run("--sequence " + kSequence + " --detections " + detections +
                                   " --out " + out + " --model-id test-model");
  ASSERT_EQ(result.exitCode, 0) << result.err;
  const YAML::Node m = measures(out);
  EXPECT_EQ(m["tp"].as<int>(), 3);
  EXPECT_EQ(m["fp"].as<int>(), 1);
  EXPECT_EQ(m["fn"].as<int>(), 0);
  EXPECT_DOUBLE_EQ(m["precision"].as<double>(), 0.75);
  EXPECT_DOUBLE_EQ(m["recall"].as<double>(), 1.0);
  EXPECT_NEAR(m["f1"].as<double>(), 6.0 / 7.0, 1e-12);
  // Position: 0.1, 0.2, 0.3 px -> median 0.2 px, MAD 1.4826 * 0.1 px; in metres with the
  // fallback GSD length_m / box_length_px (the fixture's wheel keypoints are < 1 px apart).
  EXPECT_NEAR(m["position_median_px"].as<double>(), 0.2, 1e-9);
  EXPECT_NEAR(m["position_mad_px"].as<double>(), 0.14826, 1e-9);
  EXPECT_NEAR(m["position_median_m"].as<double>(), 0.2 * 4.62 / 1.8, 1e-9);
  // Orientation: 180, 5, 0 degrees.
  EXPECT_NEAR(m["orientation_median_deg"].as<double>(), 5.0, 1e-9);
  EXPECT_NEAR(m["orientation_mad_deg"].as<double>(), 1.4826 * 5.0, 1e-9);
  EXPECT_NEAR(m["orientation_flip_share"].as<double>(), 1.0 / 3.0, 1e-12);
  // Type: OA-1 2/3, OA-2 1; sedan F1: TP 1, FN 1 -> 2/3; SUV: FP 1 -> 0.
  EXPECT_NEAR(m["type_oa1"].as<double>(), 2.0 / 3.0, 1e-12);
  EXPECT_DOUBLE_EQ(m["type_oa2"].as<double>(), 1.0);
  EXPECT_NEAR(m["type_f1_sedan"].as<double>(), 2.0 / 3.0, 1e-12);
  EXPECT_DOUBLE_EQ(m["type_f1_suv"].as<double>(), 0.0);
  // World: horizontal errors 0.3, 0, 0 m; keypoints of the two cars: 0.3 m off for one,
  // 0.1 m higher for the other -> E_D2D = sqrt(0.09 / 2), E_dH = sqrt(0.01 / 2).
  EXPECT_NEAR(m["position_world_median_m"].as<double>(), 0.0, 1e-9);
  EXPECT_NEAR(m["e_d2d_world_m"].as<double>(), std::sqrt(0.09 / 2.0), 1e-9);
  EXPECT_NEAR(m["e_dh_world_m"].as<double>(), std::sqrt(0.01 / 2.0), 1e-9);
  // Same gamma: the shape-only errors stay 0.
  EXPECT_NEAR(m["e_d2d_vehicle_m"].as<double>(), 0.0, 1e-9);
  EXPECT_NEAR(m["rms_height_m"].as<double>(), 0.0, 1e-9);
  const YAML::Node report = YAML::LoadFile(out + "/report.json");
  EXPECT_EQ(report["model"].as<std::string>(), "test-model");
}

TEST_F(EvaluateCli, SeveralSequencesAndFrameRange) {
  const std::string detections = writeDetections(
      "perfect.csv", [](int, auto&) {}, false);
  const std::string out = (dir_ / "report").string();
  CommandResult result =
      run("--sequence " + kSequence + " --detections " + detections + " --sequence " + kSequence +
          " --detections " + detections + " --out " + out);
  ASSERT_EQ(result.exitCode, 0) << result.err;
  YAML::Node report = YAML::LoadFile(out + "/report.json");
  EXPECT_EQ(report["measures"]["tp"].as<int>(), 6);
  EXPECT_EQ(report["inputs"].size(), 2U);
  EXPECT_EQ(report["inputs"][1]["tp"].as<int>(), 3);
  result =
      run("--sequence " + kSequence + " --detections " + detections + " --frames 1:1 --out " + out);
  ASSERT_EQ(result.exitCode, 0) << result.err;
  report = YAML::LoadFile(out + "/report.json");
  EXPECT_EQ(report["counts"]["images"].as<int>(), 1);
  EXPECT_EQ(report["measures"]["tp"].as<int>(), 2);
  EXPECT_EQ(report["inputs"][0]["skipped_rows"].as<int>(), 1);
}

TEST_F(EvaluateCli, ErrorsNameWhatAndWhere) {
  CommandResult result = run("--sequence " + kSequence);
  EXPECT_EQ(result.exitCode, 2);
  EXPECT_NE(result.err.find("--out DIR is required"), std::string::npos) << result.err;
  result = run("--sequence " + kSequence + " --out " + (dir_ / "o").string());
  EXPECT_EQ(result.exitCode, 2);
  EXPECT_NE(result.err.find("each --sequence needs its --detections"), std::string::npos)
      << result.err;
  result = run("--bogus");
  EXPECT_EQ(result.exitCode, 2);
  EXPECT_NE(result.err.find("unknown argument '--bogus'"), std::string::npos) << result.err;
  result = run("--help");
  EXPECT_EQ(result.exitCode, 0);
  EXPECT_NE(result.out.find("--val-list"), std::string::npos);

  // A detection of a frame the sequence does not have.
  const std::string wrongFrame = writeDetections(
      "wrong.csv",
      [](int index, output_files::DetectionRecord& r) { r.frameId += index == 2 ? 8 : 0; }, false);
  result = run("--sequence " + kSequence + " --detections " + wrongFrame + " --out " +
               (dir_ / "o").string());
  EXPECT_EQ(result.exitCode, 1);
  EXPECT_NE(result.err.find("wrong.csv:6: frame_id: no frame 9 in"), std::string::npos)
      << result.err;
  // A malformed row: file, line and column.
  std::string text = readText(writeDetections(
      "bad.csv", [](int, auto&) {}, false));
  text.replace(text.find(",sedan,"), 7, ",sedn,");
  std::ofstream(dir_ / "bad.csv", std::ios::binary) << text;
  result = run("--sequence " + kSequence + " --detections " + (dir_ / "bad.csv").string() +
               " --out " + (dir_ / "o").string());
  EXPECT_EQ(result.exitCode, 1);
  EXPECT_NE(result.err.find("bad.csv:4:"), std::string::npos) << result.err;
  EXPECT_NE(result.err.find("type: unknown vehicle type 'sedn'"), std::string::npos) << result.err;
}

// A tiny YOLO folder: a_1 (one car), b_2 (two cars, one class-1 object that is dropped).
class EvaluateYolo : public EvaluateCli {
 protected:
  void SetUp() override {
    EvaluateCli::SetUp();
    fs::create_directories(dir_ / "yolo/images");
    fs::create_directories(dir_ / "yolo/labels");
    const cv::Mat image(48, 64, CV_8UC3, cv::Scalar(90, 90, 90));
    ASSERT_TRUE(cv::imwrite((dir_ / "yolo/images/a_1.png").string(), image));
    ASSERT_TRUE(cv::imwrite((dir_ / "yolo/images/b_2.png").string(), image));
    std::ofstream(dir_ / "yolo/labels/a_1.txt") << "0 0.5 0.5 0.25 0.5\n";
    std::ofstream(dir_ / "yolo/labels/b_2.txt") << "0 0.25 0.25 0.25 0.25\n\n"
                                                   "0 0.75 0.75 0.25 0.25\n1 0.5 0.5 0.1 0.1\n";
    // a_1's car: centre (0.5 * 64 - 0.5, 0.5 * 48 - 0.5), 16 x 24 px. The detection stands at
    // 90 degrees (length 24 along v), so its enclosing box is the label's box.
    writeImageDetections("yolo_dets.csv",
                         {imageRow("a_1", 0, 0.9F, {31.5, 23.5, 24, 16, kPi / 2}),
                          // exactly the first car of b_2
                          imageRow("b_2", 0, 0.9F, {15.5, 11.5, 16, 12, 0.0})},
                         "yolo-test");
  }

  // One image-keyed row with uniform type probabilities.
  static output_files::DetectionRecord imageRow(const char* stem, int detId, float score,
                                                const geometry::RotatedBox& box,
                                                bool atFrameEdge = false) {
    output_files::DetectionRecord r;
    r.typeProbabilities.fill(1.0F / 7.0F);
    r.setImageStem(stem);
    r.detId = detId;
    r.score = score;
    r.box = box;
    r.atFrameEdge = atFrameEdge;
    return r;
  }

  // An image-keyed detections file (no gamma columns) of these rows, in dir_.
  void writeImageDetections(const std::string& name,
                            const std::vector<output_files::DetectionRecord>& rows,
                            const std::string& model = "") const {
    output_files::DetectionsFileInfo info;
    info.key = output_files::DetectionsKey::Image;
    info.gammaColumns = 0;
    info.model = model;
    output_files::DetectionsFileWriter writer;
    std::string why;
    ASSERT_TRUE(writer.open((dir_ / name).string(), info, &why)) << why;
    for (const output_files::DetectionRecord& r : rows) {
      ASSERT_TRUE(writer.writeRow(r, &why)) << why;
    }
    ASSERT_TRUE(writer.close(&why)) << why;
  }
};

// A vehicle cut by the image's edge is labelled as its visible part; a miss of one is counted
// apart (fn_cut_by_border), the other misses not.
TEST_F(EvaluateYolo, MissesOfVehiclesCutByTheImageBorderAreCountedApart) {
  const cv::Mat image(48, 64, CV_8UC3, cv::Scalar(90, 90, 90));
  ASSERT_TRUE(cv::imwrite((dir_ / "yolo/images/c_3.png").string(), image));
  std::ofstream(dir_ / "yolo/labels/c_3.txt") << "0 0.1 0.5 0.2 0.25\n";  // from u = 0
  std::ofstream(dir_ / "val.txt") << "b_2\nc_3\n";
  const std::string out = (dir_ / "report").string();
  const CommandResult result = run("--yolo " + (dir_ / "yolo").string() + " --detections " +
                                   (dir_ / "yolo_dets.csv").string() + " --val-list " +
                                   (dir_ / "val.txt").string() + " --out " + out);
  ASSERT_EQ(result.exitCode, 0) << result.err;
  const YAML::Node report = YAML::LoadFile(out + "/report.json");
  EXPECT_EQ(report["measures"]["tp"].as<int>(), 1);
  EXPECT_EQ(report["measures"]["fn"].as<int>(), 2);  // b_2's second car and c_3's
  EXPECT_EQ(report["measures"]["fn_cut_by_border"].as<int>(), 1);
  EXPECT_NE(readText(out + "/report.md").find("false negatives cut by the image border | 1"),
            std::string::npos);
}

// A false box reaching the frame's edge (the detections file's at_frame_edge) is counted apart,
// with the precision without such boxes; a format 1 file cannot say, and the rows are left out.
TEST_F(EvaluateYolo, FalseBoxesAtTheFrameEdgeAreCountedApart) {
  writeImageDetections(
      "edge_dets.csv",
      {imageRow("a_1", 0, 0.9F, {31.5, 23.5, 24, 16, kPi / 2}),   // a_1's car: a true positive
       imageRow("a_1", 1, 0.8F, {3.5, 40.5, 20, 10, 0.0}, true),  // no label, reaching the edge
       imageRow("a_1", 2, 0.7F, {50.5, 8.5, 12, 8, 0.0})});       // no label, inside
  std::ofstream(dir_ / "val.txt") << "a_1\n";
  const std::string out = (dir_ / "report").string();
  const std::string args = "--yolo " + (dir_ / "yolo").string() + " --val-list " +
                           (dir_ / "val.txt").string() + " --out " + out + " --detections ";
  CommandResult result = run(args + (dir_ / "edge_dets.csv").string());
  ASSERT_EQ(result.exitCode, 0) << result.err;
  YAML::Node report = YAML::LoadFile(out + "/report.json");
  EXPECT_EQ(report["measures"]["fp"].as<int>(), 2);
  EXPECT_EQ(report["measures"]["fp_at_frame_edge"].as<int>(), 1);
  EXPECT_DOUBLE_EQ(report["measures"]["precision"].as<double>(), 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(report["measures"]["precision_inside"].as<double>(), 0.5);
  EXPECT_NE(readText(out + "/report.md").find("false positives at the frame edge"),
            std::string::npos);

  // The same rows in format 1: no frame-edge rows in the report.
  std::ofstream(dir_ / "old_dets.csv")
      << "# format_version: 1\n"
         "image,det_id,score,box_cx_px,box_cy_px,box_length_px,box_width_px,box_angle_rad,"
         "direction_known,type,p_estate,p_compact,p_sports,p_sedan,p_suv,p_van,p_large,"
         "lift_status,east_m,north_m,up_m,lat_deg,lon_deg,height_m,heading_enu_rad,length_m,"
         "width_m,height_m_vehicle\n"
         "a_1,0,0.9,3.5,40.5,20,10,0,0,estate,1,0,0,0,0,0,0,not_lifted,,,,,,,,,,\n";
  result = run(args + (dir_ / "old_dets.csv").string());
  ASSERT_EQ(result.exitCode, 0) << result.err;
  report = YAML::LoadFile(out + "/report.json");
  EXPECT_EQ(report["measures"]["fp"].as<int>(), 1);
  EXPECT_FALSE(report["measures"]["fp_at_frame_edge"].IsDefined());
}

TEST_F(EvaluateYolo, ValidationListSelectsImages) {
  std::ofstream(dir_ / "val.txt") << "# validation stems\na_1\n";
  const std::string out = (dir_ / "report").string();
  CommandResult result = run("--yolo " + (dir_ / "yolo").string() + " --detections " +
                             (dir_ / "yolo_dets.csv").string() + " --val-list " +
                             (dir_ / "val.txt").string() + " --out " + out);
  ASSERT_EQ(result.exitCode, 0) << result.err;
  YAML::Node report = YAML::LoadFile(out + "/report.json");
  EXPECT_EQ(report["mode"].as<std::string>(), "yolo");
  EXPECT_EQ(report["counts"]["images"].as<int>(), 1);
  EXPECT_EQ(report["measures"]["tp"].as<int>(), 1);
  EXPECT_DOUBLE_EQ(report["measures"]["f1"].as<double>(), 1.0);
  EXPECT_NEAR(report["measures"]["mean_matched_iou"].as<double>(), 1.0, 1e-12);
  EXPECT_EQ(report["inputs"][0]["skipped_rows"].as<int>(), 1);

  // Without a list: every image; b_2 has 2 cars and 1 detection.
  result = run("--yolo " + (dir_ / "yolo").string() + " --detections " +
               (dir_ / "yolo_dets.csv").string() + " --out " + out);
  ASSERT_EQ(result.exitCode, 0) << result.err;
  report = YAML::LoadFile(out + "/report.json");
  EXPECT_EQ(report["measures"]["tp"].as<int>(), 2);
  EXPECT_EQ(report["measures"]["fn"].as<int>(), 1);
  EXPECT_NEAR(report["measures"]["recall"].as<double>(), 2.0 / 3.0, 1e-12);
  EXPECT_NE(readText(out + "/report.md").find("not a held-out split"), std::string::npos);

  // A JSON split with the stems, and one without them (train.py's split.json today).
  std::ofstream(dir_ / "split.json") << "{\"val\": 1, \"val_stems\": [\"b_2\"]}\n";
  result = run("--yolo " + (dir_ / "yolo").string() + " --detections " +
               (dir_ / "yolo_dets.csv").string() + " --val-list " + (dir_ / "split.json").string() +
               " --out " + out);
  ASSERT_EQ(result.exitCode, 0) << result.err;
  report = YAML::LoadFile(out + "/report.json");
  EXPECT_EQ(report["measures"]["tp"].as<int>(), 1);
  EXPECT_EQ(report["measures"]["fn"].as<int>(), 1);
  std::ofstream(dir_ / "counts.json") << "{\"train\": 1, \"val\": 1}\n";
  result = run("--yolo " + (dir_ / "yolo").string() + " --detections " +
               (dir_ / "yolo_dets.csv").string() + " --val-list " +
               (dir_ / "counts.json").string() + " --out " + out);
  EXPECT_EQ(result.exitCode, 1);
  EXPECT_NE(result.err.find("counts.json: no \"val_stems\" list"), std::string::npos) << result.err;
  std::ofstream(dir_ / "missing.txt") << "c_3\n";
  result = run("--yolo " + (dir_ / "yolo").string() + " --detections " +
               (dir_ / "yolo_dets.csv").string() + " --val-list " +
               (dir_ / "missing.txt").string() + " --out " + out);
  EXPECT_EQ(result.exitCode, 1);
  EXPECT_NE(result.err.find("validation image 'c_3' not in"), std::string::npos) << result.err;
}

TEST_F(EvaluateYolo, LabelErrorsNameTheLine) {
  std::ofstream(dir_ / "yolo/labels/b_2.txt") << "0 0.25 0.25 0.25 0.25\n0 0.75 x 0.25 0.25\n";
  const CommandResult result =
      run("--yolo " + (dir_ / "yolo").string() + " --detections " +
          (dir_ / "yolo_dets.csv").string() + " --out " + (dir_ / "o").string());
  EXPECT_EQ(result.exitCode, 1);
  EXPECT_NE(result.err.find("labels/b_2.txt:2: cy: not a number 'x'"), std::string::npos)
      << result.err;
}

TEST(EvaluateArguments, ParsesPairsAndRejectsMixes) {
  EvaluateOptions options;
  std::string why;
  const std::vector<std::string> ok{"--sequence", "a", "--detections", "a.csv",
                                    "--sequence", "b", "--detections", "b.csv",
                                    "--out",      "o", "--iou",        "0.7"};
  ASSERT_TRUE(parseArguments(ok, &options, &why)) << why;
  ASSERT_EQ(options.sequences.size(), 2U);
  EXPECT_EQ(options.sequences[1].detectionsFile, "b.csv");
  EXPECT_DOUBLE_EQ(options.iouThreshold, 0.7);
  const std::vector<std::string> mixed{"--yolo",       "y", "--sequence", "a",
                                       "--detections", "d", "--out",      "o"};
  EXPECT_FALSE(parseArguments(mixed, &options, &why));
  EXPECT_NE(why.find("cannot be mixed"), std::string::npos) << why;
  const std::vector<std::string> badIou{"--sequence", "a", "--detections", "d",
                                        "--out",      "o", "--iou",        "1.5"};
  EXPECT_FALSE(parseArguments(badIou, &options, &why));
  EXPECT_NE(why.find("--iou: must be in (0, 1]"), std::string::npos) << why;
}

}  // namespace
}  // namespace vp::evaluate
