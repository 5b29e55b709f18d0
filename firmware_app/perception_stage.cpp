#include "perception_stage.hpp"

#include <filesystem>

#include "inference/engine.hpp"
#include "loop_log.hpp"

namespace vp::app {

namespace {

bool checkSlots(std::size_t slots, std::string* why) {
  if (slots >= 1 && slots <= FramePerception::kMaxHandOffSlots) {
    return true;
  }
  if (why) {
    *why = "perception stage: " + std::to_string(slots) + " hand-off slots, at most " +
           std::to_string(FramePerception::kMaxHandOffSlots);
  }
  return false;
}

}  // namespace

bool FramePerception::prepareHandOff(std::size_t slots, std::string* why) {
  return checkSlots(slots, why);
}

perception::PipelineStatus FramePerception::detect(std::size_t slot, const cv::Mat& bgrFrame,
                                                   std::int64_t timestamp_ns,
                                                   const telemetry::PoseEstimate& pose) {
  PendingFrame& pending = pending_[slot];
  pending.frame = bgrFrame;
  pending.timestamp_ns = timestamp_ns;
  pending.pose = pose;
  return perception::PipelineStatus::Ok;
}

perception::PipelineStatus FramePerception::finish(std::size_t slot) {
  const PendingFrame& pending = pending_[slot];
  return process(pending.frame, pending.timestamp_ns, pending.pose);
}

bool PipelinePerception::prepareHandOff(std::size_t slots, std::string* why) {
  if (!checkSlots(slots, why)) {
    return false;
  }
  for (std::size_t i = 0; i < slots; ++i) {
    handOff_[i] = std::make_unique<perception::DetectedFrame>();
    pipeline_.prepare(*handOff_[i]);
  }
  return true;
}

bool PipelinePerception::init(const perception::PipelineOptions& options,
                              const camera::CameraModel& rawCamera,
                              const geodesy::CameraMount& mount,
                              const terrain::TerrainModel& terrain,
                              const geodesy::LocalFrame& frame,
                              const shape::ActiveShapeModel& shapeModel,
                              const georef::GroundView* groundView, std::string* why) {
  if (!pipeline_.init(options, rawCamera, mount, terrain, frame, shapeModel, groundView, why)) {
    return false;
  }
  // The model's file name and the backend its engine runs on (auto resolved at load) identify
  // it in the drone status and the start-up log.
  const detection::DetectionStageOptions& detection = options.detection;
  const inference::Backend runs = pipeline_.detectorBackend();
  modelId_ = std::filesystem::path(detection.detectorModelPath).stem().string() + " (" +
             inference::toString(runs) + ")";
  logLine("inference: backend %s%s, %d detector thread(s), %d crop thread(s)",
          inference::toString(runs),
          detection.engine.backend == inference::Backend::Auto
              ? " (auto: chosen by the CPU's features)"
              : "",
          detection.engine.threads, detection.cropEngineThreads);
  return true;
}

}  // namespace vp::app
