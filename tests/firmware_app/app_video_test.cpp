// Drone videos end to end: a simulated sequence written as an MP4 (cv::VideoWriter, mp4v) plus a
// DJI-style subtitle file from its telemetry (6-decimal latitude/longitude, abs_alt, 1-decimal
// gimbal angles, as the drones write them), imported with vp_import_video's library and replayed
// through the app, and the same video replayed by the app directly (source.kind video). The
// vehicles are the ground truth injected as detections (TruthPerception), lifted with the pose
// the app gets from the subtitles: their centres must lie within 0.5 m of the truth. A damaged
// subtitle file imports with the bad subtitle named and skipped.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <opencv2/videoio.hpp>

#include <pthread.h>

#include "alloc_counter.hpp"
#include "app.hpp"
#include "app_test_support.hpp"
#include "geodesy/geodesy.hpp"
#include "video_import.hpp"

namespace vp::app {
namespace {

namespace fs = std::filesystem;

constexpr double kGeoidSeparation_m = -33.5;  // the SRT's abs_alt is above mean sea level
constexpr double kMaxLiftError_m = 0.5;

struct VideoFixture {
  std::string truthDir;  // the simulated sequence
  std::string video;     // its frames as MP4
  std::string srt;       // its telemetry as a DJI-style subtitle file
  std::int64_t firstFrame_ns = 0;
};

// The camera head's attitude relative to NED (what a DJI gimbal reports as gb_*), and the
// camera centre's position, from a recorded telemetry row and the rig.
void cameraPose(const sequence::TelemetryRecord& r, const sequence::Rig& rig,
                const geodesy::LocalFrame& world, geodesy::EulerAnglesDeg& head,
                geodesy::GeodeticPoint& centre) {
  const Eigen::Matrix3d gimbal = geodesy::rotationFromEuler(r.gimbal.angles);
  const Eigen::Matrix3d body = r.bodyToNed.normalized().toRotationMatrix();
  const Eigen::Matrix3d nedFromHead =
      r.gimbal.reference == geodesy::GimbalReference::Earth
          ? gimbal
          : Eigen::Matrix3d(body * geodesy::rotationFromEuler(rig.mount.bodyToBase) * gimbal);
  head = geodesy::eulerFromRotation(nedFromHead);
  const Eigen::Vector3d lever = geodesy::enuFromNed() * (body * rig.mount.leverArm_m);
  centre = world.toGeodetic(world.toEnu(r.position) + lever);
}

const VideoFixture& fixture() {
  static const VideoFixture f = [] {
    VideoFixture out;
    out.truthDir = test::loopSequence();
    sequence::SequenceReader reader;
    std::string why;
    EXPECT_TRUE(reader.open(out.truthDir, &why)) << why;
    const std::string dir = test::scratchDir("video_fixture");
    out.video = dir + "/DJI_0001.MP4";
    out.srt = dir + "/DJI_0001.SRT";
    out.firstFrame_ns = reader.frames().front().timestamp_ns;
    const sequence::Rig& rig = reader.rig();
    cv::VideoWriter writer(out.video, cv::CAP_FFMPEG, cv::VideoWriter::fourcc('m', 'p', '4', 'v'),
                           reader.info().frameRate_hz,
                           cv::Size(rig.intrinsics.width_px, rig.intrinsics.height_px));
    EXPECT_TRUE(writer.isOpened()) << "cv::VideoWriter cannot write MP4 (mp4v)";
    cv::Mat image;
    for (std::size_t i = 0; i < reader.frames().size(); ++i) {
      EXPECT_TRUE(reader.loadFrame(i, image, &why)) << why;
      writer.write(image);
    }
    writer.release();

    // One subtitle per frame; the simulator records one telemetry row at each frame's time.
    const geodesy::LocalFrame world(rig.origin);
    std::ofstream srt(out.srt);
    const auto& rows = reader.telemetry();
    EXPECT_EQ(rows.size(), reader.frames().size());
    for (std::size_t i = 0; i < rows.size(); ++i) {
      geodesy::EulerAnglesDeg head;
      geodesy::GeodeticPoint centre;
      cameraPose(rows[i], rig, world, head, centre);
      const long long start_ms = (rows[i].timestamp_ns - out.firstFrame_ns) / 1'000'000;
      const long long end_ms = start_ms + 100;
      char text[640];
      std::snprintf(
          text, sizeof(text),
          "%zu\n%02lld:%02lld:%02lld,%03lld --> %02lld:%02lld:%02lld,%03lld\n"
          "<font size=\"28\">FrameCnt: %zu, DiffTime: 100ms\n2024-06-01 10:00:%02lld.%03lld\n"
          "[iso: 100] [shutter: 1/1000.0] [fnum: 2.8] [ev: 0] [color_md: default] "
          "[focal_len: 24.00] [latitude: %.6f] [longitude: %.6f] [rel_alt: %.3f abs_alt: %.3f] "
          "[gb_yaw: %.1f gb_pitch: %.1f gb_roll: %.1f] [ct: 5600] </font>\n\n",
          i + 1, start_ms / 3600000, start_ms / 60000 % 60, start_ms / 1000 % 60, start_ms % 1000,
          end_ms / 3600000, end_ms / 60000 % 60, end_ms / 1000 % 60, end_ms % 1000, i + 1,
          start_ms / 1000 % 60, start_ms % 1000, centre.latitude_deg, centre.longitude_deg,
          centre.height_m - rig.origin.height_m, centre.height_m - kGeoidSeparation_m, head.yaw_deg,
          head.pitch_deg, head.roll_deg);
      srt << text;
    }
    return out;
  }();
  return f;
}

importer::ImportOptions importOptions(const VideoFixture& f, const std::string& outDir) {
  importer::ImportOptions options;
  options.videoPath = f.video;
  options.srtPath = f.srt;
  options.outDir = outDir;
  options.calibrationPath = f.truthDir + "/rig.yaml";  // its camera: section, the lens included
  options.dtmPath = f.truthDir + "/dtm.tif";
  options.telemetry.altitude = subtitle::AltitudeSource::Absolute;
  options.telemetry.geoidSeparation_m = kGeoidSeparation_m;
  return options;
}

config::AppConfig quietConfig(config::AppConfig config) {
  config.dds.enabled = false;
  config.source.paced = false;
  config.app.statsPeriod_s = 3600.0;
  return config;
}

// Runs the app with the fixture's truth injected; the app (which owns the perception) is kept
// so that the caller can read what the perception measured.
struct TruthRun {
  std::unique_ptr<App> app = std::make_unique<App>();
  test::TruthPerception* truth = nullptr;
};

TruthRun runWithTruth(const config::AppConfig& config, const test::TruthReplay& replay,
                      LoopObserver* observer = nullptr) {
  TruthRun run;
  auto perception = std::make_unique<test::TruthPerception>();
  run.truth = perception.get();
  std::string why;
  // The truth's image boxes are the projected 3D boxes: lifted at half the vehicle's height.
  const perception::DetectionLifterOptions lift{.boxHeightShare = 0.5};
  EXPECT_TRUE(perception->init(fixture().truthDir, nullptr, lift, &why, replay)) << why;
  AppSeams seams;
  seams.perception = std::move(perception);
  seams.observer = observer;
  EXPECT_TRUE(run.app->init(quietConfig(config), test::everyFrame(), std::move(seams), &why))
      << why;
  EXPECT_TRUE(run.app->run(&why)) << why;
  return run;
}

// The same vehicles lifted with the simulator's exact pose (the recorded sequence replayed):
// the reference the video's pose chain is compared with.
const TruthRun& exactPoseRun() {
  static const TruthRun run = runWithTruth(test::defaultConfigFor(fixture().truthDir), {});
  return run;
}

struct LiftComparison {
  std::size_t pairs = 0;
  double max_m = 0.0;
  double mean_m = 0.0;
};

// Horizontal distance between the two lifts of each truth vehicle both lifted.
LiftComparison compareLifts(const test::TruthPerception& a, const test::TruthPerception& b) {
  sequence::SequenceReader reader;
  std::string why;
  EXPECT_TRUE(reader.open(fixture().truthDir, &why)) << why;
  const geodesy::LocalFrame world(reader.rig().origin);
  LiftComparison c;
  for (std::size_t f = 0; f < a.frameCount(); ++f) {
    for (std::size_t o = 0; o < a.objectCount(f); ++o) {
      const geodesy::GeodeticPoint* pa = a.liftedCentre(f, o);
      const geodesy::GeodeticPoint* pb = b.liftedCentre(f, o);
      if (pa == nullptr || pb == nullptr) {
        continue;
      }
      const double d = (world.toEnu(*pa) - world.toEnu(*pb)).head<2>().norm();
      c.max_m = std::max(c.max_m, d);
      c.mean_m += d;
      ++c.pairs;
    }
  }
  c.mean_m = c.pairs > 0 ? c.mean_m / static_cast<double>(c.pairs) : 0.0;
  return c;
}

// The checks of a replayed video against the truth: every vehicle lifted from the video's pose
// within 0.5 m of its true centre and of its lift with the exact pose.
void expectWithinHalfAMetre(const test::TruthPerception& video, const char* what) {
  const test::TruthPerception& exact = *exactPoseRun().truth;
  const LiftComparison c = compareLifts(video, exact);
  EXPECT_GT(c.pairs, 20U);
  EXPECT_EQ(c.pairs, exact.liftChecked())
      << "vehicles lifted with the exact pose were not from the video";
  EXPECT_LT(c.max_m, kMaxLiftError_m);
  EXPECT_LT(video.maxLiftError_m(), kMaxLiftError_m);
  std::printf(
      "[ figure ] %s: %zu vehicles; from the exact pose: mean %.3f m, max %.3f m; from "
      "the true centre: mean %.3f m, max %.3f m (exact pose: mean %.3f m, max %.3f m)\n",
      what, c.pairs, c.mean_m, c.max_m, video.meanLiftError_m(), video.maxLiftError_m(),
      exact.meanLiftError_m(), exact.maxLiftError_m());
}

TEST(AppVideo, ImportedDroneVideoReplaysWithLiftedVehiclesWithinHalfAMetreOfTheTruth) {
  const VideoFixture& f = fixture();
  const std::string imported = test::scratchDir("imported") + "/seq";
  importer::ImportSummary summary;
  std::string why;
  ASSERT_TRUE(importer::importVideo(importOptions(f, imported), summary, &why)) << why;
  EXPECT_TRUE(summary.errors.empty()) << summary.errors.front();
  EXPECT_EQ(summary.framesWritten, test::kLoopFrames);
  EXPECT_EQ(summary.telemetryRows, static_cast<std::size_t>(test::kLoopFrames));
  EXPECT_EQ(summary.nadirAssumed, 0U);
  EXPECT_EQ(summary.indexTimestamps, 0U);

  sequence::SequenceReader reader;
  ASSERT_TRUE(reader.open(imported, &why)) << why;
  EXPECT_EQ(reader.frames().size(), static_cast<std::size_t>(test::kLoopFrames));
  EXPECT_EQ(reader.frames()[3].timestamp_ns, 300'000'000);

  const TruthRun run =
      runWithTruth(test::defaultConfigFor(imported), {&reader.rig(), f.firstFrame_ns});
  EXPECT_EQ(run.app->counters().framesProcessed, static_cast<std::uint64_t>(test::kLoopFrames));
  expectWithinHalfAMetre(*run.truth, "imported video");
}

// The app replays the MP4 itself (source.kind video) with the subtitles as telemetry; camera,
// mount and DTM come from the configuration (here the simulated rig's).
config::AppConfig directVideoConfig(const VideoFixture& f) {
  config::AppConfig config = test::defaultConfigFor("");
  const config::RigConfig rig = config::loadRigConfig(f.truthDir + "/rig.yaml");
  config.origin = rig.origin;
  config.camera = rig.camera;
  config.terrain.dtmPath = rig.terrain.dtmPath;
  config.terrain.crs = rig.terrain.crs;
  // The subtitles give the camera head's attitude in NED: an earth gimbal, no lever arm.
  config.mount = config::MountConfig{};
  config.mount.gimbal.reference = geodesy::GimbalReference::Earth;
  config.source.kind = config::FrameSourceKind::Video;
  config.source.sequenceDir.clear();
  config.source.video.path = f.video;
  config.source.video.srt = f.srt;
  config.source.video.subtitles.geoidSeparation_m = kGeoidSeparation_m;
  return config;
}

TEST(AppVideo, DirectlyReplayedVideoLiftsVehiclesWithinHalfAMetreOfTheTruth) {
  const VideoFixture& f = fixture();
  const config::AppConfig config = directVideoConfig(f);
  sequence::Rig rig;
  rig.origin = config.origin;
  rig.intrinsics = config.camera.intrinsics;
  rig.distortion = config.camera.distortion;
  rig.mount = config.mount.mount;
  rig.gimbal = config.mount.gimbal;
  rig.dtmPath = config.terrain.dtmPath;
  rig.crs = config.terrain.crs;
  test::AllocationWindow window(4, test::kLoopFrames);
  const TruthRun run = runWithTruth(config, {&rig, f.firstFrame_ns}, &window);
  EXPECT_EQ(run.app->counters().framesProcessed, static_cast<std::uint64_t>(test::kLoopFrames));
  EXPECT_EQ(run.app->counters().framesIn, static_cast<std::uint64_t>(test::kLoopFrames));
  // The capture thread decodes (and allocates); the processing thread does not.
  ASSERT_TRUE(window.counted());
  EXPECT_EQ(window.count(), 0U) << "heap allocations on the processing thread";
  expectWithinHalfAMetre(*run.truth, "video replayed directly");
}

TEST(AppVideo, DirectVideoStartUpErrorsNameTheKey) {
  const VideoFixture& f = fixture();
  config::AppConfig config = directVideoConfig(f);
  config.source.video.path = f.video + ".missing";
  App app;
  std::string why;
  EXPECT_FALSE(app.init(quietConfig(config), test::everyFrame(), {}, &why));
  EXPECT_EQ(why, "source.video.path: " + f.video + ".missing: video file not found");

  config = directVideoConfig(f);
  config.source.video.srt.clear();
  App app2;
  EXPECT_FALSE(app2.init(quietConfig(config), test::everyFrame(), {}, &why));
  EXPECT_EQ(why, "source.video: give one of srt (the drone's subtitle file) and telemetry_csv");

  config = directVideoConfig(f);
  config.camera.intrinsics.width_px = 640;
  App app3;
  EXPECT_FALSE(app3.init(quietConfig(config), test::everyFrame(), {}, &why));
  EXPECT_NE(why.find("but the source delivers 320x256"), std::string::npos) << why;
}

TEST(AppVideo, MalformedSubtitlesAreNamedSkippedAndTheImportGoesOn) {
  const VideoFixture& f = fixture();
  // Subtitle 5's latitude is garbage, subtitle 9 has lost its time range.
  std::ostringstream original;
  original << std::ifstream(f.srt).rdbuf();
  std::string text = original.str();
  const std::size_t lat5 = text.find("[latitude: ", text.find("FrameCnt: 5,"));
  text.replace(lat5, 11, "[latitude: x");
  const std::size_t block9 = text.find("\n9\n") + 3;
  text.replace(block9, text.find('\n', block9) - block9, "00:00:00,800 -> 00:00:00,900");
  const std::string dir = test::scratchDir("malformed_srt");
  const std::string damaged = dir + "/damaged.SRT";
  std::ofstream(damaged) << text;

  importer::ImportOptions options = importOptions(f, dir + "/seq");
  options.srtPath = damaged;
  importer::ImportSummary summary;
  std::string why;
  ASSERT_TRUE(importer::importVideo(options, summary, &why)) << why;
  ASSERT_EQ(summary.errors.size(), 2U);
  // Each subtitle of the fixture takes 6 lines (number, range, 3 text lines, an empty line).
  EXPECT_EQ(summary.errors[0].rfind(damaged + ":29: latitude: not a number 'x", 0), 0U)
      << summary.errors[0];
  EXPECT_EQ(summary.errors[1],
            damaged +
                ":50: expected a time range 'HH:MM:SS,mmm --> HH:MM:SS,mmm', got "
                "'00:00:00,800 -> 00:00:00,900'; subtitle 9 skipped");
  EXPECT_EQ(summary.subtitleBlocks, static_cast<std::size_t>(test::kLoopFrames));
  EXPECT_EQ(summary.telemetryRows, static_cast<std::size_t>(test::kLoopFrames - 2));
  EXPECT_EQ(summary.framesWritten, test::kLoopFrames);  // every frame still imported
  sequence::SequenceReader reader;
  ASSERT_TRUE(reader.open(dir + "/seq", &why)) << why;
  EXPECT_EQ(reader.telemetry().size(), static_cast<std::size_t>(test::kLoopFrames - 2));
}

}  // namespace
}  // namespace vp::app
