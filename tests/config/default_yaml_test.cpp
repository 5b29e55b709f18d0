// The shipped config/default.yaml and the modules' options structs define the same defaults:
// each knob has one definition in code (beside its module), and the reference file must load to
// exactly it, so that neither can drift from the other.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "config/config.hpp"

namespace vp::config {
namespace {

namespace fs = std::filesystem;

AppConfig shippedDefaults() {
  return loadConfig(std::string(VP_SOURCE_DIR) + "/config/default.yaml");
}

std::string model(const char* relative) {
  return (fs::path(VP_SOURCE_DIR) / "config" / relative).lexically_normal().string();
}

TEST(DefaultYaml, PerceptionIsThePipelinesDefaults) {
  const AppConfig config = shippedDefaults();
  EXPECT_TRUE(config.warnings.empty());
  const perception::PipelineOptions code;
  const perception::PipelineOptions& file = config.perception;

  const preprocess::PreprocessOptions& pre = file.preprocess;
  EXPECT_EQ(pre.undistort, code.preprocess.undistort);
  EXPECT_EQ(pre.whiteBalance, code.preprocess.whiteBalance);
  const preprocess::WhiteBalanceOptions& wb = pre.whiteBalanceOptions;
  const preprocess::WhiteBalanceOptions& wbCode = code.preprocess.whiteBalanceOptions;
  EXPECT_EQ(wb.regionRows, wbCode.regionRows);
  EXPECT_EQ(wb.regionCols, wbCode.regionCols);
  EXPECT_EQ(wb.sampleStride_px, wbCode.sampleStride_px);
  EXPECT_EQ(wb.whitePointShare, wbCode.whitePointShare);
  EXPECT_EQ(wb.minRegionDeviation, wbCode.minRegionDeviation);
  EXPECT_EQ(wb.maxGain, wbCode.maxGain);
  EXPECT_EQ(pre.workingScale, code.preprocess.workingScale);
  EXPECT_EQ(pre.workingGsd_m, code.preprocess.workingGsd_m);
  EXPECT_EQ(pre.minWorkingScale, code.preprocess.minWorkingScale);
  EXPECT_EQ(pre.maxWorkingScale, code.preprocess.maxWorkingScale);
  EXPECT_EQ(pre.maxWorkingGsd_m, code.preprocess.maxWorkingGsd_m);
  EXPECT_EQ(pre.networkWidth_px, code.preprocess.networkWidth_px);
  EXPECT_EQ(pre.networkHeight_px, code.preprocess.networkHeight_px);
  EXPECT_EQ(pre.tileOverlap_px, code.preprocess.tileOverlap_px);
  EXPECT_EQ(pre.padValue, code.preprocess.padValue);
  EXPECT_EQ(pre.threads, code.preprocess.threads);

  const detection::DetectionStageOptions& det = file.detection;
  const detection::DetectionStageOptions& detCode = code.detection;
  // The model files: the file names them relative to itself (the code leaves them to it).
  EXPECT_EQ(det.detectorModelPath, model(kDefaultDetectorModel));
  EXPECT_EQ(det.cropModelPath, model(kDefaultCropModel));
  EXPECT_EQ(config.asmPath, model(kDefaultAsm));
  EXPECT_EQ(det.engine.backend, detCode.engine.backend);
  EXPECT_EQ(det.engine.threads, detCode.engine.threads);
  EXPECT_EQ(det.engine.planMemory, detCode.engine.planMemory);
  EXPECT_EQ(det.engine.imageOrder, detCode.engine.imageOrder);
  EXPECT_EQ(det.engine.normalization.has_value(), detCode.engine.normalization.has_value());
  EXPECT_EQ(det.cropEngineThreads, detCode.cropEngineThreads);
  EXPECT_EQ(det.cropBackend, detCode.cropBackend);
  EXPECT_EQ(det.decoder.scoreThreshold, detCode.decoder.scoreThreshold);
  EXPECT_EQ(det.decoder.topKPerTile, detCode.decoder.topKPerTile);
  EXPECT_EQ(det.decoder.nmsIou, detCode.decoder.nmsIou);
  EXPECT_EQ(det.decoder.duplicateOverlap, detCode.decoder.duplicateOverlap);
  EXPECT_EQ(det.decoder.cutEdgeMargin_px, detCode.decoder.cutEdgeMargin_px);
  EXPECT_EQ(det.decoder.dropCentresOutsideFrame, detCode.decoder.dropCentresOutsideFrame);
  const detection::SecondStageOptions& second = det.secondStage;
  const detection::SecondStageOptions& secondCode = detCode.secondStage;
  EXPECT_EQ(second.applyFlip, secondCode.applyFlip);
  EXPECT_EQ(second.applyRefine, secondCode.applyRefine);
  EXPECT_EQ(second.refineSize, secondCode.refineSize);
  EXPECT_EQ(second.shapeForLargeVehicles, secondCode.shapeForLargeVehicles);
  EXPECT_EQ(second.refineLargeVehicleLength, secondCode.refineLargeVehicleLength);
  EXPECT_EQ(second.mirrorAverage, secondCode.mirrorAverage);
  EXPECT_EQ(second.turnAverage, secondCode.turnAverage);
  EXPECT_EQ(second.turnTypeAverage, secondCode.turnTypeAverage);
  EXPECT_EQ(second.turnTypeWeight, secondCode.turnTypeWeight);
  EXPECT_EQ(second.mirrorRefine, secondCode.mirrorRefine);
  EXPECT_EQ(second.largeVehicleEnds, secondCode.largeVehicleEnds);
  EXPECT_EQ(second.minVehicleProbability, secondCode.minVehicleProbability);
  EXPECT_EQ(second.frameEdgeKeepBox, secondCode.frameEdgeKeepBox);
  EXPECT_EQ(second.frameEdgeMinVehicleProbability, secondCode.frameEdgeMinVehicleProbability);
  EXPECT_EQ(second.frameEdgeOwnVerifier, secondCode.frameEdgeOwnVerifier);
  EXPECT_EQ(det.gsd.fixedGsd_m, detCode.gsd.fixedGsd_m);
  EXPECT_EQ(det.gsd.nominalCarLength_m, detCode.gsd.nominalCarLength_m);
  EXPECT_EQ(det.gsd.minGsd_m, detCode.gsd.minGsd_m);
  EXPECT_EQ(det.gsd.maxGsd_m, detCode.gsd.maxGsd_m);
  EXPECT_EQ(det.maxCrops, detCode.maxCrops);

  EXPECT_EQ(file.lift.boxHeightShare, code.lift.boxHeightShare);
  EXPECT_EQ(file.lift.nominalHeight_m, code.lift.nominalHeight_m);
}

TEST(DefaultYaml, TerrainIsTheDtmLoadersDefaults) {
  const AppConfig config = shippedDefaults();
  EXPECT_EQ(config.terrain.load.maxSamples, io::DtmLoadOptions{}.maxSamples);
  EXPECT_EQ(config.terrain.load.maxSamples, io::kDefaultDtmMaxSamples);
}

TEST(DefaultYaml, PoseIsThePoseBuffersDefaults) {
  const telemetry::PoseBufferConfig code;
  const telemetry::PoseBufferConfig file = shippedDefaults().pose;
  EXPECT_EQ(file.capacity, code.capacity);
  EXPECT_EQ(file.maxAge_ns, code.maxAge_ns);
  EXPECT_EQ(file.startTolerance_ns, code.startTolerance_ns);
  const telemetry::PoseLimits& l = file.limits;
  const telemetry::PoseLimits& lc = code.limits;
  EXPECT_EQ(l.minHeight_m, lc.minHeight_m);
  EXPECT_EQ(l.maxHeight_m, lc.maxHeight_m);
  EXPECT_EQ(l.quaternionNormTolerance, lc.quaternionNormTolerance);
  EXPECT_EQ(l.maxTilt_deg, lc.maxTilt_deg);
  EXPECT_EQ(l.minGimbalRoll_deg, lc.minGimbalRoll_deg);
  EXPECT_EQ(l.maxGimbalRoll_deg, lc.maxGimbalRoll_deg);
  EXPECT_EQ(l.minGimbalPitch_deg, lc.minGimbalPitch_deg);
  EXPECT_EQ(l.maxGimbalPitch_deg, lc.maxGimbalPitch_deg);
  EXPECT_EQ(l.minGimbalYaw_deg, lc.minGimbalYaw_deg);
  EXPECT_EQ(l.maxGimbalYaw_deg, lc.maxGimbalYaw_deg);
  EXPECT_EQ(l.maxHorizontalSpeed_mps, lc.maxHorizontalSpeed_mps);
  EXPECT_EQ(l.maxVerticalSpeed_mps, lc.maxVerticalSpeed_mps);
  EXPECT_EQ(l.maxAngularRate_degps, lc.maxAngularRate_degps);
  EXPECT_EQ(l.jumpTolerance_m, lc.jumpTolerance_m);
  EXPECT_EQ(l.jumpTolerance_deg, lc.jumpTolerance_deg);
  EXPECT_EQ(l.consistencyWindow_ns, lc.consistencyWindow_ns);
}

TEST(DefaultYaml, TrackingIsTheTrackersDefaults) {
  const tracking::TrackerConfig code;
  const tracking::TrackerConfig file = shippedDefaults().tracking;
  EXPECT_EQ(file.maxTracks, code.maxTracks);
  EXPECT_EQ(file.maxDetections, code.maxDetections);
  EXPECT_EQ(file.confirmHits, code.confirmHits);
  EXPECT_EQ(file.confirmWholeHits, code.confirmWholeHits);
  EXPECT_EQ(file.confirmHitsAnyway, code.confirmHitsAnyway);
  EXPECT_EQ(file.confirmHitsStanding, code.confirmHitsStanding);
  EXPECT_EQ(file.confirmHitsLarge, code.confirmHitsLarge);
  EXPECT_EQ(file.confirmMinScore, code.confirmMinScore);
  EXPECT_EQ(file.maxTentativeGap_s, code.maxTentativeGap_s);
  EXPECT_EQ(file.maxLost_s, code.maxLost_s);
  EXPECT_EQ(file.maxLostAtFrameEdge_s, code.maxLostAtFrameEdge_s);
  EXPECT_EQ(file.maxCoast_s, code.maxCoast_s);
  EXPECT_EQ(file.movingSpeed_mps, code.movingSpeed_mps);
  EXPECT_EQ(file.flipVotes, code.flipVotes);
  EXPECT_EQ(file.typeEvidenceWeight, code.typeEvidenceWeight);
  EXPECT_EQ(file.typeFloor, code.typeFloor);
  EXPECT_EQ(file.shapeMaxWeight, code.shapeMaxWeight);
  EXPECT_EQ(file.scoreMemory, code.scoreMemory);
  EXPECT_EQ(file.partialInsideShare, code.partialInsideShare);
  EXPECT_EQ(file.partialAlongNoiseFactor, code.partialAlongNoiseFactor);
  EXPECT_EQ(file.longVehicleLength_m, code.longVehicleLength_m);
  EXPECT_EQ(file.maxOverlap, code.maxOverlap);
  EXPECT_EQ(file.frameEdgeShapeWeight, code.frameEdgeShapeWeight);
  EXPECT_EQ(file.asmModel, code.asmModel);

  const tracking::AssociationParams& gate = file.association;
  EXPECT_EQ(gate.maxDistance_m, code.association.maxDistance_m);
  EXPECT_EQ(gate.maxAxisAngle_rad, code.association.maxAxisAngle_rad);
  EXPECT_EQ(gate.mahalanobisGate, code.association.mahalanobisGate);
  EXPECT_EQ(gate.mahalanobisWeight, code.association.mahalanobisWeight);
  EXPECT_EQ(gate.iouWeight, code.association.iouWeight);
  EXPECT_EQ(gate.highScore, code.association.highScore);
  EXPECT_EQ(gate.lowScore, code.association.lowScore);

  const tracking::MotionNoise& noise = file.noise;
  const tracking::MotionNoise& noiseCode = code.noise;
  EXPECT_EQ(noise.positionDiffusion_mPerSqrtS, noiseCode.positionDiffusion_mPerSqrtS);
  EXPECT_EQ(noise.headingDiffusion_radPerSqrtS, noiseCode.headingDiffusion_radPerSqrtS);
  EXPECT_EQ(noise.jerk_mPerS3, noiseCode.jerk_mPerS3);
  EXPECT_EQ(noise.steeringRate_radPerS, noiseCode.steeringRate_radPerS);
  EXPECT_EQ(noise.accelerationDecay_s, noiseCode.accelerationDecay_s);
  EXPECT_EQ(noise.steeringDecay_s, noiseCode.steeringDecay_s);
  EXPECT_EQ(noise.maxSteering_rad, noiseCode.maxSteering_rad);
  EXPECT_EQ(noise.standstillSpeed_mps, noiseCode.standstillSpeed_mps);
  EXPECT_EQ(noise.standstillDecay_s, noiseCode.standstillDecay_s);
  EXPECT_EQ(noise.measurementPosition_m, noiseCode.measurementPosition_m);
  EXPECT_EQ(noise.measurementHeading_rad, noiseCode.measurementHeading_rad);
  EXPECT_EQ(noise.initialSpeed_mps, noiseCode.initialSpeed_mps);
  EXPECT_EQ(noise.initialAcceleration_mps2, noiseCode.initialAcceleration_mps2);
  EXPECT_EQ(noise.initialSteering_rad, noiseCode.initialSteering_rad);
}

TEST(DefaultYaml, DdsOutputsAreTheWritersDefaults) {
  const AppConfig config = shippedDefaults();
  const DdsConfig code;
  EXPECT_EQ(config.dds.native.enabled, code.native.enabled);
  EXPECT_EQ(config.dds.ros2.enabled, code.ros2.enabled);
  EXPECT_EQ(config.dds.ros2.topicNamespace, code.ros2.topicNamespace);
  EXPECT_EQ(config.dds.ros2.frameId, code.ros2.frameId);
  EXPECT_EQ(config.dds.autoware.enabled, code.autoware.enabled);
  EXPECT_EQ(config.dds.autoware.topic, code.autoware.topic);
  EXPECT_EQ(config.dds.autoware.frameId, code.autoware.frameId);
  EXPECT_EQ(config.dds.autoware.stationarySpeed_mps, code.autoware.stationarySpeed_mps);
}

TEST(DefaultYaml, GeorefIsTheGroundViewsDefaults) {
  const georef::GeorefOptions code;
  const georef::GeorefOptions file = shippedDefaults().georef;
  EXPECT_EQ(file.gcpFile, code.gcpFile);
  EXPECT_EQ(file.maxResidual_m, code.maxResidual_m);
}

TEST(DefaultYaml, SiteIsTheSiteMapsDefaults) {
  const site::SiteOptions code;
  const site::SiteOptions file = shippedDefaults().site;
  EXPECT_EQ(file.file, code.file);
  EXPECT_EQ(file.offRoad, code.offRoad);
}

TEST(DefaultYaml, TrafficIsTheAnalyzersDefaults) {
  const traffic::TrafficAnalyzerOptions code;
  const traffic::TrafficAnalyzerOptions file = shippedDefaults().traffic;
  EXPECT_EQ(file.enabled, code.enabled);
  EXPECT_EQ(file.period_s, code.period_s);
  EXPECT_EQ(file.stopSpeed_mps, code.stopSpeed_mps);
  EXPECT_EQ(file.laneHeadingTolerance_deg, code.laneHeadingTolerance_deg);
  EXPECT_EQ(file.wrongWayAngle_deg, code.wrongWayAngle_deg);
  EXPECT_EQ(file.wrongWaySpeed_mps, code.wrongWaySpeed_mps);
  EXPECT_EQ(file.wrongWay_s, code.wrongWay_s);
  EXPECT_EQ(file.boxJunctionStop_s, code.boxJunctionStop_s);
  EXPECT_EQ(file.maxTracks, code.maxTracks);
  EXPECT_EQ(file.maxEventsPerStep, code.maxEventsPerStep);
  EXPECT_EQ(file.maxLaneSamples, code.maxLaneSamples);
}

TEST(DefaultYaml, LoopIsTheLoopsDefaults) {
  const LoopConfig code;
  const LoopConfig file = shippedDefaults().app;
  EXPECT_EQ(file.queueDepth, code.queueDepth);
  EXPECT_EQ(file.pipeline, code.pipeline);
  EXPECT_EQ(file.framePoolSize, code.framePoolSize);
  EXPECT_EQ(file.lockMemory, code.lockMemory);
  EXPECT_EQ(file.realtimePriority, code.realtimePriority);
  EXPECT_EQ(file.statsPeriod_s, code.statsPeriod_s);
  EXPECT_EQ(file.annotatedVideoFps, code.annotatedVideoFps);
}

// Every key of the file is one the loader reads (else it would keep a default the file only
// pretends to set).
TEST(DefaultYaml, RecordIsTheRecordersDefaults) {
  const RecordConfig code;
  const RecordConfig file = shippedDefaults().app.record;
  EXPECT_EQ(file.dir, code.dir);  // off unless --record DIR or app.record.dir
  EXPECT_TRUE(file.dir.empty());
  EXPECT_EQ(file.jpegQuality, code.jpegQuality);
  EXPECT_EQ(file.everyNthFrame, code.everyNthFrame);
  EXPECT_EQ(file.queueFrames, code.queueFrames);
  EXPECT_EQ(file.maxDisk_mib, code.maxDisk_mib);
  EXPECT_EQ(file.minFreeDisk_mib, code.minFreeDisk_mib);
  EXPECT_EQ(file.onFull, code.onFull);
}

TEST(DefaultYaml, EveryKeyIsRead) {
  EXPECT_TRUE(shippedDefaults().warnings.empty());
}

}  // namespace
}  // namespace vp::config
