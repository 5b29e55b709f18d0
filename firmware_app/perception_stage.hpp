// firmware_app/perception_stage: the loop's view of "one frame and its pose in, vehicle
// observations out", so that the loop runs the shipped pipeline on the drone and, in tests, a
// stage that injects known detections (the seam that makes the loop's tests independent of the
// detector's accuracy).
//
// Contract: process() is called on the processing thread once per frame after init, never
// throws and allocates nothing; a refused frame returns a status other than Ok and lastError()
// names the problem. The results stay valid until the next process(). PipelinePerception is
// the product's stage: perception::FramePipeline (preprocess -> detect -> lift) with the
// `perception:` section's options.
#pragma once

#include <span>
#include <string>

#include <opencv2/core.hpp>

#include "config/config.hpp"
#include "perception/frame_pipeline.hpp"

namespace vp::app {

class FramePerception {
 public:
  virtual ~FramePerception() = default;
  virtual perception::PipelineStatus process(const cv::Mat& bgrFrame, std::int64_t timestamp_ns,
                                             const telemetry::PoseEstimate& pose) = 0;
  virtual std::span<const perception::VehicleObservation> observations() const = 0;
  virtual const perception::FrameLiftSummary& liftSummary() const = 0;
  // The ground the frame shows (perception::frameFootprint; empty without a camera pose): the
  // occupancy grid's observed area, computed by perception so the loop never lifts itself.
  virtual const perception::FrameFootprint& footprint() const = 0;
  virtual const perception::PipelineTimings& timings() const = 0;
  virtual const char* lastError() const = 0;
  // The frame the observations' pixels refer to, and the Lifter on its camera (annotation).
  virtual const cv::Mat& correctedFrame() const = 0;
  virtual const lifting::Lifter& lifter() const = 0;
  // The DetectionLifter the observations were lifted with (the lane prior lifts a turned one
  // again); null where the stage has none (the tests' injecting stages).
  virtual const perception::DetectionLifter* detectionLifter() const { return nullptr; }
  virtual const char* modelId() const = 0;  // for the drone status, e.g. "detector_int8"
  // Working px per frame px of the last frame and the GSD (m/px) at its image centre that chose
  // it (perception.working_gsd_m); 0 where the stage has none (the tests' injecting stages).
  virtual double workingScale() const { return 0.0; }
  virtual double frameGsd_m() const { return 0.0; }
  // Lifted cars of the last frame whose most likely type their footprint changed
  // (perception.footprint_type); 0 where the stage has none.
  virtual std::size_t retyped() const { return 0; }

  // The two halves (see the contract). Start-up: slots in [1, kMaxHandOffSlots]; false + *why.
  static constexpr std::size_t kMaxHandOffSlots = 2;
  virtual bool prepareHandOff(std::size_t slots, std::string* why);
  virtual perception::PipelineStatus detect(std::size_t slot, const cv::Mat& bgrFrame,
                                            std::int64_t timestamp_ns,
                                            const telemetry::PoseEstimate& pose);
  virtual perception::PipelineStatus finish(std::size_t slot);

 private:
  struct PendingFrame {
    cv::Mat frame;  // borrowed until finish()
    std::int64_t timestamp_ns = 0;
    telemetry::PoseEstimate pose{};
  };
  std::array<PendingFrame, kMaxHandOffSlots> pending_{};
};

class PipelinePerception final : public FramePerception {
 public:
  // options: the `perception:` section (config::AppConfig::perception); groundView: the
  // georeferenced fixed view when there is no telemetry (null: pose and DTM).
  bool init(const perception::PipelineOptions& options, const camera::CameraModel& rawCamera,
            const geodesy::CameraMount& mount, const terrain::TerrainModel& terrain,
            const geodesy::LocalFrame& frame, const shape::ActiveShapeModel& shapeModel,
            const georef::GroundView* groundView, std::string* why);

  perception::PipelineStatus process(const cv::Mat& bgrFrame, std::int64_t timestamp_ns,
                                     const telemetry::PoseEstimate& pose) override {
    return pipeline_.process(bgrFrame, timestamp_ns, pose);
  }
  std::span<const perception::VehicleObservation> observations() const override {
    return pipeline_.observations();
  }
  const perception::FrameLiftSummary& liftSummary() const override {
    return pipeline_.liftSummary();
  }
  const perception::FrameFootprint& footprint() const override { return pipeline_.footprint(); }
  const perception::PipelineTimings& timings() const override { return pipeline_.timings(); }
  const char* lastError() const override { return pipeline_.lastError(); }
  const cv::Mat& correctedFrame() const override { return pipeline_.correctedFrame(); }
  const lifting::Lifter& lifter() const override { return pipeline_.lifter(); }
  const perception::DetectionLifter* detectionLifter() const override {
    return &pipeline_.detectionLifter();
  }
  const char* modelId() const override { return modelId_.c_str(); }
  double workingScale() const override { return pipeline_.workingScale(); }
  double frameGsd_m() const override { return pipeline_.frameGsd_m(); }
  std::size_t retyped() const override { return pipeline_.footprintTypeScreening().retyped; }

  bool prepareHandOff(std::size_t slots, std::string* why) override;
  perception::PipelineStatus detect(std::size_t slot, const cv::Mat& bgrFrame,
                                    std::int64_t timestamp_ns,
                                    const telemetry::PoseEstimate& pose) override {
    return pipeline_.detect(bgrFrame, timestamp_ns, pose, *handOff_[slot]);
  }
  perception::PipelineStatus finish(std::size_t slot) override {
    return pipeline_.finish(*handOff_[slot]);
  }

 private:
  perception::FramePipeline pipeline_;
  std::array<std::unique_ptr<perception::DetectedFrame>, kMaxHandOffSlots> handOff_{};
  std::string modelId_;
};

}  // namespace vp::app
