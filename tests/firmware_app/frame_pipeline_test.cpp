// perception/frame_pipeline (the app's per-frame chain) on a simulated frame with the shipped
// models: a refused frame names the problem and the next frame goes on; without a pose every
// detection is kept image-only with NoPose; with the recorded pose the same detections are
// lifted (the lift summary and each observation agree) and their footprints weigh the cars'
// types; no heap allocation per frame; the two halves (detect, finish) with the next frame
// detected in between give process()'s results.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "app_test_support.hpp"
#include "io/dtm_file.hpp"
#include "perception/frame_pipeline.hpp"
#include "perception_stage.hpp"

namespace vp::perception {
namespace {

// The loop fixture sequence's world: its rig, DTM, camera, the default configuration and ASM.
class FramePipelineTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = test::loopSequence();
    ASSERT_FALSE(dir.empty());
    ASSERT_TRUE(reader.open(dir, &why)) << why;
    const sequence::Rig& rig = reader.rig();
    world = geodesy::LocalFrame(rig.origin);
    terrain::TerrainGrid grid;
    ASSERT_TRUE(io::loadDtm(rig.dtmPath, rig.crs, grid, &why)) << why;
    ASSERT_TRUE(terrain.init(std::move(grid), world, &why)) << why;
    ASSERT_TRUE(camera.init(rig.intrinsics, rig.distortion, &why)) << why;
    defaults = test::defaultConfigFor(dir);
    ASSERT_TRUE(shapeModel.load(defaults.asmPath, &why)) << why;
  }

  std::string dir;
  std::string why;
  sequence::SequenceReader reader;
  geodesy::LocalFrame world;
  terrain::TerrainModel terrain;
  camera::CameraModel camera;
  config::AppConfig defaults;
  shape::ActiveShapeModel shapeModel;
};

TEST_F(FramePipelineTest, RefusesABadFrameLiftsWithAPoseAndAllocatesNothing) {
  const sequence::Rig& rig = reader.rig();
  perception::PipelineOptions options = defaults.perception;
  options.preprocess.workingScale = 1.0;
  options.preprocess.workingGsd_m = 0.0;  // one scale with and without a pose
  // The crop scale comes from the pose when there is one, else from the boxes: the verifier's
  // vote on a doubtful box may differ between the two, and this test compares the detections
  // with and without a pose.
  options.detection.secondStage.minVehicleProbability = 0.0F;
  FramePipeline pipeline;
  ASSERT_TRUE(pipeline.init(options, camera, rig.mount, terrain, world, shapeModel, &why)) << why;

  cv::Mat frame(rig.intrinsics.height_px, rig.intrinsics.width_px, CV_8UC3);
  ASSERT_TRUE(reader.loadFrame(0, frame, &why)) << why;
  const std::int64_t t = reader.frames()[0].timestamp_ns;

  // A frame of the wrong size is refused with a message naming both sizes.
  const cv::Mat wrong(100, 120, CV_8UC3, cv::Scalar(0, 0, 0));
  EXPECT_EQ(pipeline.process(wrong, t, telemetry::PoseEstimate{}),
            PipelineStatus::PreprocessFailed);
  EXPECT_NE(std::string(pipeline.lastError()).find("120x100"), std::string::npos)
      << pipeline.lastError();

  // No pose: detections kept, none lifted, each with NoPose.
  ASSERT_EQ(pipeline.process(frame, t, telemetry::PoseEstimate{}), PipelineStatus::Ok)
      << pipeline.lastError();
  const std::size_t detected = pipeline.observations().size();
  EXPECT_EQ(pipeline.liftSummary().lifted, 0U);
  for (const VehicleObservation& observation : pipeline.observations()) {
    EXPECT_EQ(observation.liftStatus, LiftStatus::NoPose);
  }
  EXPECT_EQ(pipeline.footprintTypeScreening().weighed, 0U);  // no footprint without a lift

  // The recorded pose: the same detections, lifted where the DTM is.
  telemetry::PoseBuffer poses;
  ASSERT_TRUE(poses.init(telemetry::PoseBufferConfig{}, &why)) << why;
  for (const sequence::TelemetryRecord& record : reader.telemetry()) {
    telemetry::PoseSample sample;
    sample.timestamp_ns = record.timestamp_ns;
    sample.position = record.position;
    sample.bodyToNed = record.bodyToNed;
    sample.gimbal = record.gimbal;
    poses.push(sample);
  }
  const telemetry::PoseEstimate pose = poses.poseAt(t);
  ASSERT_EQ(pose.status, telemetry::PoseStatus::Ok);
  test::AllocationCounter counter;
  ASSERT_EQ(pipeline.process(frame, t, pose), PipelineStatus::Ok) << pipeline.lastError();
  ASSERT_EQ(pipeline.process(frame, t, pose), PipelineStatus::Ok) << pipeline.lastError();
  counter.stop();
  EXPECT_EQ(counter.count(), 0U);
  EXPECT_EQ(pipeline.observations().size(), detected);
  EXPECT_EQ(pipeline.liftSummary().poseStatus, LiftStatus::Ok);
  std::size_t lifted = 0;
  for (const VehicleObservation& observation : pipeline.observations()) {
    lifted += observation.liftStatus == LiftStatus::Ok ? 1 : 0;
    if (observation.liftStatus == LiftStatus::Ok) {
      EXPECT_GT(observation.ground.length_m, 0.0);
      EXPECT_TRUE(std::isfinite(observation.ground.centreWgs84.latitude_deg));
    }
  }
  EXPECT_EQ(lifted, pipeline.liftSummary().lifted);
  // The footprint weighs the lifted cars' types (perception.footprint_type, on by default); the
  // observations carry the type their probabilities now put first.
  const FootprintTypeScreening& weighed = pipeline.footprintTypeScreening();
  EXPECT_GT(weighed.weighed, 0U);
  EXPECT_LE(weighed.weighed, lifted);
  EXPECT_LE(weighed.retyped, weighed.weighed);
  for (const VehicleObservation& observation : pipeline.observations()) {
    if (observation.liftStatus == LiftStatus::Ok) {
      EXPECT_EQ(observation.type, mostLikelyType(observation.detection, nullptr));
    }
  }
  EXPECT_GT(pipeline.timings().detector_ms, 0.0);
  std::printf(
      "frame pipeline on a 320 x 256 simulated frame: %zu detections by the shipped "
      "(in-training) detector, %zu lifted; %.1f ms\n",
      detected, lifted, pipeline.timings().total_ms);
}

// With working_gsd_m (the default) the working scale follows the GSD the pose and the DTM give
// at the image centre: the rung nearest GSD / 0.12, which for a near-nadir camera is about
// height above ground / focal length; without a pose the scale stays at working_scale.
TEST_F(FramePipelineTest, WorkingScaleFollowsTheHeightAboveTheDtm) {
  const sequence::Rig& rig = reader.rig();
  perception::PipelineOptions options = defaults.perception;
  ASSERT_GT(options.preprocess.workingGsd_m, 0.0);
  options.preprocess.workingScale = 0.5;
  FramePipeline pipeline;
  ASSERT_TRUE(pipeline.init(options, camera, rig.mount, terrain, world, shapeModel, &why)) << why;

  cv::Mat frame(rig.intrinsics.height_px, rig.intrinsics.width_px, CV_8UC3);
  ASSERT_TRUE(reader.loadFrame(0, frame, &why)) << why;
  const std::int64_t t = reader.frames()[0].timestamp_ns;
  ASSERT_EQ(pipeline.process(frame, t, telemetry::PoseEstimate{}), PipelineStatus::Ok);
  EXPECT_EQ(pipeline.workingScale(), 0.5);
  EXPECT_EQ(pipeline.frameGsd_m(), 0.0);

  const sequence::TelemetryRecord& record = reader.telemetry().front();
  telemetry::PoseBuffer poses;
  ASSERT_TRUE(poses.init(telemetry::PoseBufferConfig{}, &why)) << why;
  for (const sequence::TelemetryRecord& r : reader.telemetry()) {
    telemetry::PoseSample sample;
    sample.timestamp_ns = r.timestamp_ns;
    sample.position = r.position;
    sample.bodyToNed = r.bodyToNed;
    sample.gimbal = r.gimbal;
    poses.push(sample);
  }
  ASSERT_EQ(pipeline.process(frame, t, poses.poseAt(t)), PipelineStatus::Ok);
  const auto ground = terrain.heightAt(record.position.latitude_deg, record.position.longitude_deg);
  ASSERT_TRUE(ground.hasValue());
  const double nadir_m = (record.position.height_m - *ground) / rig.intrinsics.fx_px;
  EXPECT_GT(pipeline.frameGsd_m(), 0.8 * nadir_m);
  EXPECT_LT(pipeline.frameGsd_m(), 1.5 * nadir_m);
  const double ideal = pipeline.frameGsd_m() / preprocess::kDetectorWorkingGsd_m;
  EXPECT_LT(std::abs(std::log(pipeline.workingScale() / std::min(ideal, 1.0))),
            std::log(preprocess::kScaleStep))
      << "scale " << pipeline.workingScale() << " for GSD " << pipeline.frameGsd_m();
  std::printf("working scale %.3f for a centre GSD of %.3f m (nadir estimate %.3f m)\n",
              pipeline.workingScale(), pipeline.frameGsd_m(), nadir_m);
}

// The pipelined loop's order: frame B's detect() runs before frame A's finish(). With
// undistortion on, the preprocessor writes its own corrected frame, which B's preprocessing
// overwrites: a prepared DetectedFrame keeps A's copy, so A's crops and observations are
// process()'s. No heap allocation in either half.
TEST_F(FramePipelineTest, HalvesWithTheNextFrameDetectedBetweenGiveProcessResults) {
  const sequence::Rig& rig = reader.rig();
  perception::PipelineOptions options = defaults.perception;
  options.preprocess.workingScale = 1.0;
  options.preprocess.workingGsd_m = 0.0;  // the one tile of the first test
  options.preprocess.undistort = true;    // the rig's lens has distortion
  FramePipeline serial;
  FramePipeline halves;
  ASSERT_TRUE(serial.init(options, camera, rig.mount, terrain, world, shapeModel, &why)) << why;
  ASSERT_TRUE(halves.init(options, camera, rig.mount, terrain, world, shapeModel, &why)) << why;
  telemetry::PoseBuffer poses;
  ASSERT_TRUE(poses.init(telemetry::PoseBufferConfig{}, &why)) << why;
  for (const sequence::TelemetryRecord& r : reader.telemetry()) {
    telemetry::PoseSample sample;
    sample.timestamp_ns = r.timestamp_ns;
    sample.position = r.position;
    sample.bodyToNed = r.bodyToNed;
    sample.gimbal = r.gimbal;
    poses.push(sample);
  }
  std::array<cv::Mat, 2> frames;
  std::array<std::int64_t, 2> times{};
  const std::array<std::size_t, 2> indices{0, reader.frames().size() - 1};
  for (std::size_t k = 0; k < 2; ++k) {
    frames[k].create(rig.intrinsics.height_px, rig.intrinsics.width_px, CV_8UC3);
    ASSERT_TRUE(reader.loadFrame(indices[k], frames[k], &why)) << why;
    times[k] = reader.frames()[indices[k]].timestamp_ns;
  }
  // Serial references.
  std::array<std::vector<VehicleObservation>, 2> expected;
  std::array<cv::Mat, 2> expectedCorrected;
  for (std::size_t k = 0; k < 2; ++k) {
    ASSERT_EQ(serial.process(frames[k], times[k], poses.poseAt(times[k])), PipelineStatus::Ok)
        << serial.lastError();
    expected[k].assign(serial.observations().begin(), serial.observations().end());
    expectedCorrected[k] = serial.correctedFrame().clone();
    // Undistortion on: the corrected frame is the preprocessor's own buffer, not the frame.
    ASSERT_NE(serial.correctedFrame().data, frames[k].data);
  }
  ASSERT_GT(expected[0].size(), 0U);

  auto first = std::make_unique<DetectedFrame>();
  auto second = std::make_unique<DetectedFrame>();
  halves.prepare(*first);
  halves.prepare(*second);
  // Warm-up through the halves, then counted.
  for (int round = 0; round < 2; ++round) {
    test::AllocationCounter counter;
    ASSERT_EQ(halves.detect(frames[0], times[0], poses.poseAt(times[0]), *first),
              PipelineStatus::Ok);
    ASSERT_EQ(halves.detect(frames[1], times[1], poses.poseAt(times[1]), *second),
              PipelineStatus::Ok);
    ASSERT_EQ(halves.finish(*first), PipelineStatus::Ok) << halves.lastError();
    counter.stop();
    if (round == 1) {
      EXPECT_EQ(counter.count(), 0U);
    }
    ASSERT_EQ(halves.observations().size(), expected[0].size());
    for (std::size_t i = 0; i < expected[0].size(); ++i) {
      const VehicleObservation& got = halves.observations()[i];
      EXPECT_EQ(got.detection.box.cx, expected[0][i].detection.box.cx);
      EXPECT_EQ(got.detection.box.cy, expected[0][i].detection.box.cy);
      EXPECT_EQ(got.detection.box.length, expected[0][i].detection.box.length);
      EXPECT_EQ(got.detection.vehicleProbability, expected[0][i].detection.vehicleProbability);
      EXPECT_EQ(got.liftStatus, expected[0][i].liftStatus);
      EXPECT_EQ(got.ground.centreEnu, expected[0][i].ground.centreEnu);
    }
    EXPECT_EQ(cv::norm(halves.correctedFrame(), expectedCorrected[0], cv::NORM_INF), 0.0);
    ASSERT_EQ(halves.finish(*second), PipelineStatus::Ok) << halves.lastError();
    EXPECT_EQ(halves.observations().size(), expected[1].size());
  }
}

}  // namespace
}  // namespace vp::perception
