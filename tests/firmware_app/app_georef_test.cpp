// The app without telemetry, georeferenced by ground control points (georef:): a simulated
// hovering drone held at one pose, six GCPs taken from ground-truth world points projected into
// the image with 0.5 px of noise, the ground-truth vehicles injected as detections
// (TruthPerception) and lifted through the GCPs' homography; the tracks' positions and speeds
// against the ground truth (evaluation/tracking_measures), beside the same run lifted with the
// recorded true pose and the DTM. And the real pipeline on the same view: every frame lifted,
// zero heap allocations per frame.
#include <pthread.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "app.hpp"
#include "app_test_support.hpp"
#include "evaluation/tracking_measures.hpp"
#include "output_files/trajectory_file.hpp"
#include "simulator.hpp"

namespace vp::app {
namespace {

constexpr int kWidth_px = 640;
constexpr int kHeight_px = 512;
constexpr int kFrames = 50;
constexpr double kPixelNoise_px = 0.5;

struct HoverScene {
  std::string dir;
  std::string gcpFile;
  std::uint64_t seed = 0;
  double gsd_m = 0.0;
  std::string relief;
};

// Renders (once) a static hover over a planar ground (flat or sloping: a homography sees a
// plane) and writes its GCP file.
const HoverScene& hoverScene() {
  static const HoverScene scene = [] {
    HoverScene s;
    sim::SimOptions options;
    options.scene = sim::SceneKind::Straight;  // traffic that keeps moving: speeds to measure
    options.frames = kFrames;
    options.width = kWidth_px;
    options.height = kHeight_px;
    options.png = true;
    options.supersampling = 1;
    options.staticHover = true;
    options.altitude_m = 70.0;
    options.tilt_deg = 15.0;
    options.asmPath = std::string(VP_SOURCE_DIR) + "/models/asm/default_asm.yaml";
    std::string why;
    sim::Simulator simulator;
    // The first seed from 3 on whose relief is a plane (the draw is fixed: the same every run).
    for (options.seed = 3; options.seed < 40; ++options.seed) {
      if (!simulator.init(options, &why)) {
        ADD_FAILURE() << why;
        return s;
      }
      if (simulator.world().spec().kind != sim::ReliefKind::Undulating) {
        break;
      }
    }
    s.seed = options.seed;
    s.relief = sim::toString(simulator.world().spec().kind);
    s.dir = test::scratchDir("seq_hover");
    options.outDir = s.dir;
    if (!simulator.init(options, &why)) {
      ADD_FAILURE() << why;
      return s;
    }
    // Six surveyed points: ground-truth world points (where six pixels spread over the frame meet
    // the true ground) projected into the image through the true pose, plus pixel noise.
    std::string rows = "id,u_px,v_px,latitude_deg,longitude_deg,height_m\n";
    std::mt19937_64 rng(2024);
    std::normal_distribution<double> noise(0.0, kPixelNoise_px);
    bool pointsWritten = false;
    const auto onFrame = [&](const sim::FrameOutput& frame) {
      if (pointsWritten) {
        return;
      }
      pointsWritten = true;
      const lifting::Lifter& lifter = simulator.lifter();
      const auto pose = lifter.cameraPose(frame.truePose);
      ASSERT_TRUE(pose.hasValue());
      const double fractions[6][2] = {{0.08, 0.1},  {0.9, 0.12}, {0.5, 0.45},
                                      {0.12, 0.88}, {0.85, 0.9}, {0.35, 0.7}};
      int index = 0;
      for (const auto& f : fractions) {
        const Eigen::Vector2d seen(f[0] * (kWidth_px - 1), f[1] * (kHeight_px - 1));
        const auto ground = lifter.pixelToWorld(*pose, seen);
        ASSERT_TRUE(ground.hasValue());
        const auto pixel = lifter.worldToPixel(*pose, *ground);
        ASSERT_TRUE(pixel.hasValue());
        const Eigen::Vector2d clicked = *pixel + Eigen::Vector2d(noise(rng), noise(rng));
        const geodesy::GeodeticPoint p = simulator.world().frame().toGeodetic(*ground);
        char row[200];
        std::snprintf(row, sizeof row, "GCP%d,%.2f,%.2f,%.9f,%.9f,%.3f\n", ++index, clicked.x(),
                      clicked.y(), p.latitude_deg, p.longitude_deg, p.height_m);
        rows += row;
      }
    };
    if (!simulator.write(&why, onFrame)) {
      ADD_FAILURE() << why;
      return s;
    }
    s.gcpFile = s.dir + "/gcp.csv";
    std::ofstream(s.gcpFile) << rows;
    s.gsd_m = 70.0 / simulator.rig().intrinsics.fx_px;
    return s;
  }();
  return scene;
}

config::AppConfig hoverConfig(const HoverScene& scene, const std::string& out) {
  config::AppConfig config = test::defaultConfigFor(scene.dir);
  config.dds.enabled = false;
  config.source.paced = false;
  config.app.statsPeriod_s = 3600.0;
  config.app.trajectoryCsv = out + "/tracks.csv";
  return config;
}

struct Accuracy {
  evaluation::TrackingSummary summary;
  double positionRms_m = 0.0;
  int positionSamples = 0;
};

// Confirmed tracks of the trajectory file against the sequence's ground truth.
Accuracy measure(const std::string& sequenceDir, const std::string& tracksFile) {
  Accuracy result;
  sequence::SequenceReader reader;
  std::string why;
  EXPECT_TRUE(reader.open(sequenceDir, &why)) << why;
  output_files::TrajectoryFile tracks;
  EXPECT_TRUE(output_files::readTrajectoryFile(tracksFile, &tracks, &why)) << why;
  evaluation::TrackingEvaluator evaluator;
  double squared = 0.0;
  for (const sequence::FrameRecord& frame : reader.frames()) {
    std::vector<evaluation::TruthVehicle> truth;
    for (const sequence::ObjectTruth& object : reader.objects(frame.frameId)) {
      evaluation::TruthVehicle t;
      t.id = object.trackId;
      t.positionEnu = object.positionEnu.head<2>();
      t.headingEnu_rad = object.headingEnu_rad;
      t.speed_mps = object.speed_mps;
      t.type = static_cast<int>(object.type);
      // As the evaluation tool: hardly visible vehicles are 'ignore'.
      t.ignore = object.occlusion > 0.7 || object.truncation > 0.3;
      truth.push_back(t);
    }
    std::vector<evaluation::TrackObservation> confirmed;
    for (const output_files::TrajectoryRecord& row : tracks.rows) {
      if (row.frameId != frame.frameId || row.status != tracking::TrackStatus::Confirmed) {
        continue;
      }
      evaluation::TrackObservation track;
      track.id = row.trackId;
      track.centreEnu = row.centreEnu;
      track.headingEnu_rad = row.headingEnu_rad();
      track.speed_mps = row.speed_mps;
      track.type = static_cast<int>(row.type);
      confirmed.push_back(track);
      // Position error: the nearest counted vehicle within the evaluator's gate.
      double best = evaluation::kDefaultTrackMatchDistance_m;
      bool ignored = false;
      bool found = false;
      for (const evaluation::TruthVehicle& t : truth) {
        const double d = (t.positionEnu - row.centreEnu).norm();
        if (d < best) {
          best = d;
          ignored = t.ignore;
          found = true;
        }
      }
      if (found && !ignored) {
        squared += best * best;
        ++result.positionSamples;
      }
    }
    evaluator.addFrame(truth, confirmed);
  }
  result.summary = evaluator.summary();
  result.positionRms_m = result.positionSamples > 0 ? std::sqrt(squared / result.positionSamples)
                                                    : std::numeric_limits<double>::quiet_NaN();
  return result;
}

TEST(AppGeoref, WithoutTelemetryGroundControlPointsGiveTruePositionsAndSpeeds) {
  const HoverScene& scene = hoverScene();
  ASSERT_FALSE(scene.gcpFile.empty());
  // Boxes enclose the whole vehicle (as the detector's): lifted at half its height.
  const perception::DetectionLifterOptions lift{.boxHeightShare = 0.5};

  // Telemetry off, the ground control points on.
  const std::string out = test::scratchDir("georef_gcp");
  config::AppConfig config = hoverConfig(scene, out);
  config.telemetry.source = config::TelemetrySourceKind::None;
  config.georef.gcpFile = scene.gcpFile;
  {
    App app;
    AppSeams seams;
    auto perception = std::make_unique<test::TruthPerception>();
    std::string why;
    ASSERT_TRUE(perception->init(scene.dir, &config.georef, lift, &why)) << why;
    seams.perception = std::move(perception);
    ASSERT_TRUE(app.init(config, test::everyFrame(), std::move(seams), &why)) << why;
    ASSERT_TRUE(app.run(&why)) << why;
    const LoopCounters c = app.counters();
    EXPECT_EQ(c.framesProcessed, static_cast<std::uint64_t>(kFrames));
    EXPECT_EQ(c.noPose + c.stalePose + c.invalidPose, 0U);  // no pose needed, none missed
    EXPECT_EQ(c.telemetrySamples, 0U);
    EXPECT_GT(c.lifted, static_cast<std::uint64_t>(kFrames));
    EXPECT_EQ(c.lifted, c.detections);
  }
  const Accuracy gcp = measure(scene.dir, out + "/tracks.csv");

  // The same run lifted with the recorded (true) pose and the DTM, for comparison.
  const std::string poseOut = test::scratchDir("georef_pose");
  {
    config::AppConfig poseConfig = hoverConfig(scene, poseOut);
    App app;
    AppSeams seams;
    auto perception = std::make_unique<test::TruthPerception>();
    std::string why;
    ASSERT_TRUE(perception->init(scene.dir, nullptr, lift, &why)) << why;
    seams.perception = std::move(perception);
    ASSERT_TRUE(app.init(poseConfig, test::everyFrame(), std::move(seams), &why)) << why;
    ASSERT_TRUE(app.run(&why)) << why;
  }
  const Accuracy pose = measure(scene.dir, poseOut + "/tracks.csv");

  std::printf(
      "static hover (seed %llu, %s ground, %d x %d, %.3f m/px, %d frames), 6 GCPs with %.1f px "
      "noise:\n"
      "  GCPs, no telemetry: position RMS %.3f m (%d track-frames), MOTP %.3f m, speed RMSE "
      "%.3f m/s (%d), MOTA %.3f, id switches %d\n"
      "  true pose + DTM:    position RMS %.3f m (%d track-frames), MOTP %.3f m, speed RMSE "
      "%.3f m/s (%d), MOTA %.3f, id switches %d\n",
      static_cast<unsigned long long>(scene.seed), scene.relief.c_str(), kWidth_px, kHeight_px,
      scene.gsd_m, kFrames, kPixelNoise_px, gcp.positionRms_m, gcp.positionSamples,
      gcp.summary.mot.motp_m, gcp.summary.speedRmse_mps, gcp.summary.speedSamples,
      gcp.summary.mot.mota, gcp.summary.mot.idSwitches, pose.positionRms_m, pose.positionSamples,
      pose.summary.mot.motp_m, pose.summary.speedRmse_mps, pose.summary.speedSamples,
      pose.summary.mot.mota, pose.summary.mot.idSwitches);
  ASSERT_GT(gcp.positionSamples, 100);
  ASSERT_GT(gcp.summary.speedSamples, 50);
  EXPECT_LT(gcp.positionRms_m, 0.3);
  EXPECT_LT(gcp.summary.speedRmse_mps, 0.3);
  EXPECT_GT(gcp.summary.mot.mota, 0.8);
}

TEST(AppGeoref, BadGroundControlFilesStopTheStartWithTheirNames) {
  const HoverScene& scene = hoverScene();
  ASSERT_FALSE(scene.gcpFile.empty());
  const std::string out = test::scratchDir("georef_bad");
  config::AppConfig config = hoverConfig(scene, out);
  config.telemetry.source = config::TelemetrySourceKind::None;
  std::string why;
  {
    // Telemetry on and ground control points: one of the two must go.
    config::AppConfig both = config;
    both.telemetry.source = config::TelemetrySourceKind::Recording;
    both.georef.gcpFile = scene.gcpFile;
    App app;
    EXPECT_FALSE(app.init(both, test::everyFrame(), AppSeams{}, &why));
    EXPECT_NE(why.find("georef.gcp_file: ground control points place a fixed view without "
                       "telemetry: set telemetry.source: none (it is recording)"),
              std::string::npos)
        << why;
  }
  {
    // Three points only.
    const std::string path = out + "/three.csv";
    std::ifstream in(scene.gcpFile);
    std::string line;
    std::string text;
    for (int i = 0; i < 4 && std::getline(in, line); ++i) {
      text += line + "\n";
    }
    std::ofstream(path) << text;
    config.georef.gcpFile = path;
    App app;
    EXPECT_FALSE(app.init(config, test::everyFrame(), AppSeams{}, &why));
    EXPECT_NE(why.find("georef.gcp_file: " + path +
                       ": 3 ground control point(s) ('GCP1', 'GCP2', 'GCP3'): at least 4"),
              std::string::npos)
        << why;
  }
  {
    // A missing file.
    config.georef.gcpFile = out + "/missing.csv";
    App app;
    EXPECT_FALSE(app.init(config, test::everyFrame(), AppSeams{}, &why));
    EXPECT_NE(why.find("georef.gcp_file: " + out + "/missing.csv: cannot open"), std::string::npos)
        << why;
  }
}

TEST(AppGeoref, TheRealPipelineLiftsThroughTheGroundControlPointsWithoutAllocating) {
  const HoverScene& scene = hoverScene();
  ASSERT_FALSE(scene.gcpFile.empty());
  const std::string out = test::scratchDir("georef_pipeline");
  config::AppConfig config = hoverConfig(scene, out);
  config.telemetry.source = config::TelemetrySourceKind::None;
  config.georef.gcpFile = scene.gcpFile;
  constexpr int kRunFrames = 16;
  test::AllocationWindow window(5, kRunFrames);
  App app;
  AppSeams seams;
  seams.observer = &window;
  RunSettings run = test::everyFrame();
  run.maxFrames = kRunFrames;
  std::string why;
  ASSERT_TRUE(app.init(config, run, std::move(seams), &why)) << why;
  ASSERT_TRUE(app.run(&why)) << why;
  const LoopCounters c = app.counters();
  EXPECT_EQ(c.framesProcessed, static_cast<std::uint64_t>(kRunFrames));
  EXPECT_EQ(c.pipelineErrors, 0U);
  EXPECT_EQ(c.noPose + c.stalePose + c.invalidPose, 0U);
  EXPECT_GT(c.detections, 0U);
  EXPECT_EQ(c.lifted, c.detections);  // every detection placed through the ground plane
  std::printf(
      "real pipeline, GCPs, no telemetry: %llu detections, %llu lifted; allocations over "
      "frames 6..%d: %zu\n",
      static_cast<unsigned long long>(c.detections), static_cast<unsigned long long>(c.lifted),
      kRunFrames, window.count());
  ASSERT_TRUE(window.counted());
  EXPECT_EQ(window.count(), 0U);
}

}  // namespace
}  // namespace vp::app
