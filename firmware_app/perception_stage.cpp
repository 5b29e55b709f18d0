#include "perception_stage.hpp"

#include <filesystem>

namespace vp::app {

perception::PipelineOptions pipelineOptions(const config::PerceptionConfig& config) {
  perception::PipelineOptions options;
  preprocess::PreprocessOptions& pre = options.preprocess;
  pre.undistort = config.undistort;
  pre.whiteBalance = config.whiteBalance;
  pre.whiteBalanceOptions.regionRows = config.whiteBalanceRegionRows;
  pre.whiteBalanceOptions.regionCols = config.whiteBalanceRegionCols;
  pre.whiteBalanceOptions.sampleStridePx = config.whiteBalanceSampleStridePx;
  pre.whiteBalanceOptions.whitePointShare = config.whiteBalanceWhiteShare;
  pre.whiteBalanceOptions.maxGain = config.whiteBalanceMaxGain;
  pre.workingScale = config.workingScale;
  pre.tileOverlapPx = config.tileOverlapPx;
  pre.threads = config.threads;

  detection::DetectionStageOptions& det = options.detection;
  det.detectorModelPath = config.detectorModel;
  det.cropModelPath = config.cropModel;
  switch (config.backend) {
    case config::InferenceBackend::Int8:
      det.engine.backend = inference::Backend::XnnpackInt8;
      break;
    case config::InferenceBackend::Fp32:
      det.engine.backend = inference::Backend::XnnpackFp32;
      break;
    case config::InferenceBackend::OpenCv:
      det.engine.backend = inference::Backend::OpenCvFp32;
      break;
  }
  det.engine.threads = config.threads;
  det.cropEngineThreads = config.cropThreads;
  det.decoder.scoreThreshold = static_cast<float>(config.scoreThreshold);
  det.decoder.topKPerTile = config.topKPerTile;
  det.decoder.nmsIou = config.nmsIou;
  det.decoder.duplicateOverlap = config.duplicateOverlap;
  det.decoder.cutEdgeMarginPx = config.cutEdgeMarginPx;
  det.maxCrops = config.maxCrops;
  det.secondStage.applyFlip = config.applyFlip;
  det.secondStage.applyRefine = config.applyRefine;
  det.secondStage.mirrorAverage = config.cropMirrorAverage;
  det.secondStage.mirrorRefine = config.cropMirrorRefine;
  det.secondStage.largeVehicleEnds = config.cropLargeVehicleEnds;
  det.secondStage.minVehicleProbability = static_cast<float>(config.cropMinVehicleProbability);
  det.gsd.fixedGsd_m = config.fixedGsd_m;
  det.gsd.nominalCarLength_m = config.nominalCarLength_m;
  options.lift.boxHeightShare = config.liftHeightShare;
  return options;
}

bool PipelinePerception::init(const config::PerceptionConfig& config,
                              const camera::CameraModel& rawCamera,
                              const geodesy::CameraMount& mount,
                              const terrain::TerrainModel& terrain,
                              const geodesy::LocalFrame& frame,
                              const shape::ActiveShapeModel& shapeModel, std::string* why) {
  // The model's file name and backend identify it in the drone status.
  modelId_ = std::filesystem::path(config.detectorModel).stem().string() + " (" +
             config::toString(config.backend) + ")";
  return pipeline_.init(pipelineOptions(config), rawCamera, mount, terrain, frame, shapeModel, why);
}

}  // namespace vp::app
