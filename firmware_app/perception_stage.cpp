#include "perception_stage.hpp"

#include <filesystem>

#include "inference/engine.hpp"

namespace vp::app {

bool PipelinePerception::init(const perception::PipelineOptions& options,
                              const camera::CameraModel& rawCamera,
                              const geodesy::CameraMount& mount,
                              const terrain::TerrainModel& terrain,
                              const geodesy::LocalFrame& frame,
                              const shape::ActiveShapeModel& shapeModel,
                              const georef::GroundView* groundView, std::string* why) {
  // The model's file name and backend identify it in the drone status.
  const detection::DetectionStageOptions& detection = options.detection;
  modelId_ = std::filesystem::path(detection.detectorModelPath).stem().string() + " (" +
             inference::toString(detection.engine.backend) + ")";
  return pipeline_.init(options, rawCamera, mount, terrain, frame, shapeModel, groundView, why);
}

}  // namespace vp::app
