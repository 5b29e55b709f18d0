// perception/frame_pipeline: one camera frame and the drone's pose in, vehicles in the world
// out — the stages of docs/perception.md composed in their fixed order, in fixed memory.
//
// Contract: init() builds, in this order, the preprocessor (undistortion, white balance,
// working-resolution tiles), the detection stage (detector + second-stage crop network), the
// Lifter on the camera of the *corrected* frame (the pinhole camera when undistortion runs)
// and the detection lifter; it fails with *why naming the part and the problem. process()
// then runs per frame: camera pose at the frame time (from the pose estimate the caller took
// from its telemetry::PoseBuffer) -> working scale for the GSD at the image centre
// (Preprocessor::adaptToGsd, when the options ask for it) -> preprocess -> detection, with the
// second stage's crops cut at the ground sample distance computed from that pose and the DTM at
// each detection (PoseGsdProvider; without a usable pose the detection stage's own estimate) ->
// lifting -> the footprint's size as evidence on each car's type (footprint_type.hpp). Every
// detection is kept as a VehicleObservation, lifted or with the status saying why
// not (no/stale/invalid pose, off the DTM, ...); with a camera pose the frame's ground footprint
// (frameFootprint(): its corners on the DTM) is computed too. process() never throws and performs
// no heap allocation after init(); a refused frame (wrong size/type, engine failure) returns a
// status and lastError() names the problem, and the next frame is processed normally. The terrain,
// world frame and ASM are borrowed and must outlive the pipeline; so is the ground view when one
// is given (telemetry off, ground control points: georef/georeference): the pipeline then lifts
// through a lifting::PlaneLifter on the corrected frame's camera, every frame has the view's
// camera (the pose is not used) and the GSDs and the footprint come from the ground plane; the
// pipeline itself must not move after init() (its parts point at each other).
// Two halves: process() is detect() then finish() on one DetectedFrame. detect() runs the pose,
// the working scale, preprocessing and the detector with its decoding into a DetectedFrame;
// finish() runs the second stage (crops), lifting and the footprint from one and publishes the
// frame's results (observations() ... correctedFrame()). The pipelined loop runs detect() of a
// frame on one thread while finish() of the frame before runs on another, each DetectedFrame used
// by one half at a time (the caller hands it over): detect() touches only the preprocessor, the
// detector and the decoder, finish() only the crop network and the published results; the
// Lifter, the detection lifter and the options are read-only after init(). Otherwise not
// thread-safe. A DetectedFrame borrows the caller's frame when the preprocessor does not copy it
// (no undistortion, no white balance): that frame must stay unchanged until finish() is done.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>

#include <opencv2/core.hpp>

#include "camera/camera_model.hpp"
#include "detection/detection.hpp"
#include "detection/detection_stage.hpp"
#include "detection/ground_sample_distance.hpp"
#include "geodesy/attitude.hpp"
#include "geodesy/geodesy.hpp"
#include "georef/georeference.hpp"
#include "lifting/lifting.hpp"
#include "lifting/plane_lifter.hpp"
#include "perception/detection_lifter.hpp"
#include "perception/footprint_type.hpp"
#include "preprocess/preprocessor.hpp"
#include "shape/vehicle_model.hpp"
#include "telemetry/pose_buffer.hpp"
#include "terrain/terrain_model.hpp"

namespace vp::perception {

struct PipelineOptions {
  preprocess::PreprocessOptions preprocess{};
  detection::DetectionStageOptions detection{};
  DetectionLifterOptions lift{};
  FootprintTypeOptions footprintType{};
};

// Wall time of each stage of the last processed frame, ms.
struct PipelineTimings {
  double preprocess_ms = 0.0;
  double detector_ms = 0.0;
  double decode_ms = 0.0;
  double crops_ms = 0.0;
  double lift_ms = 0.0;
  double total_ms = 0.0;
};

enum class PipelineStatus : std::uint8_t {
  Ok,
  NotInitialised,
  PreprocessFailed,  // the frame was refused (lastError() says why)
  DetectionFailed,   // the detector could not run on the frame
};
const char* toString(PipelineStatus status);

// GSD (m per corrected-frame pixel) at a detection's centre from the camera pose and the
// DTM: the ground area one pixel covers there, lifted through the Lifter (square root of
// the area of the lifted pixel's parallelogram). <= 0 when the pose is not set or the
// ray misses the DTM, so the detection stage falls back to its own estimate.
// GSD (m per pixel) at one pixel of the corrected frame: the square root of the ground area the
// pixel covers, lifted through the Lifter; <= 0 when a ray misses the DTM.
double groundSampleDistanceAt_m(const lifting::Lifter& lifter, const lifting::CameraPoseWorld& pose,
                                const Eigen::Vector2d& pixel);

class PoseGsdProvider final : public detection::GsdProvider {
 public:
  void setPose(const lifting::Lifter* lifter, const lifting::CameraPoseWorld* pose) {
    lifter_ = lifter;
    pose_ = pose;
    plane_ = nullptr;
  }
  // A fixed view: the GSD on the ground plane (null: none).
  void setPlane(const lifting::PlaneLifter* plane) {
    lifter_ = nullptr;
    pose_ = nullptr;
    plane_ = plane;
  }
  double groundSampleDistance_m(const detection::Detection& detection) const override;

 private:
  const lifting::Lifter* lifter_ = nullptr;
  const lifting::CameraPoseWorld* pose_ = nullptr;
  const lifting::PlaneLifter* plane_ = nullptr;
};

// One frame between the two halves (detect() -> finish()): everything finish() needs, in memory
// allocated by FramePipeline::prepare() at start-up.
struct DetectedFrame {
  PipelineStatus status = PipelineStatus::NotInitialised;
  std::int64_t timestamp_ns = 0;
  FrameCameraPose camera{};
  // The corrected frame the detections' pixels refer to: a view of the caller's frame, of the
  // preprocessor's buffer (serial use), or of `copy` (prepared for a hand-off across threads).
  cv::Mat corrected;
  cv::Mat copy;
  preprocess::FrameGeometry geometry{};
  int frameWidth_px = 0;
  int frameHeight_px = 0;
  std::array<detection::Detection, detection::kMaxDetectionsPerFrame> detections{};
  detection::FirstStageOutput first{};
  PipelineTimings timings{};  // preprocess_ms, detector_ms, decode_ms
  double frameGsd_m = 0.0;
  double workingScale = 0.0;
  std::uint64_t workingScaleChanges = 0;
  std::array<char, 256> error{};
};

class FramePipeline {
 public:
  FramePipeline() = default;
  FramePipeline(const FramePipeline&) = delete;
  FramePipeline& operator=(const FramePipeline&) = delete;

  // Start-up. rawCamera is the camera's calibration (its image size is the frame size).
  bool init(const PipelineOptions& options, const camera::CameraModel& rawCamera,
            const geodesy::CameraMount& mount, const terrain::TerrainModel& terrain,
            const geodesy::LocalFrame& frame, const shape::ActiveShapeModel& shapeModel,
            std::string* why);
  // The same with a georeferenced fixed view (null: pose and DTM, as above).
  bool init(const PipelineOptions& options, const camera::CameraModel& rawCamera,
            const geodesy::CameraMount& mount, const terrain::TerrainModel& terrain,
            const geodesy::LocalFrame& frame, const shape::ActiveShapeModel& shapeModel,
            const georef::GroundView* groundView, std::string* why);

  // Real-time path. The pose estimate is the one at timestamp_ns (PoseBuffer::poseAt).
  PipelineStatus process(const cv::Mat& bgrFrame, std::int64_t timestamp_ns,
                         const telemetry::PoseEstimate& pose);

  // Start-up, after init(): makes `frame` ready to carry a frame from detect() on one thread to
  // finish() on another (the corrected frame is copied into it when the preprocessor writes its
  // own buffer, which the next frame's preprocessing overwrites).
  void prepare(DetectedFrame& frame) const;
  // The halves of process() (see the contract); detect() returns the frame's status so far and
  // finish() the final one (a refused frame: detect()'s status, lastError() set from the frame).
  PipelineStatus detect(const cv::Mat& bgrFrame, std::int64_t timestamp_ns,
                        const telemetry::PoseEstimate& pose, DetectedFrame& out);
  PipelineStatus finish(DetectedFrame& frame);

  std::span<const VehicleObservation> observations() const {
    return {observations_.data(), liftSummary_.written};
  }
  const FrameLiftSummary& liftSummary() const { return liftSummary_; }
  // What the footprint type evidence did to the last frame's observations.
  const FootprintTypeScreening& footprintTypeScreening() const { return footprintTypeScreening_; }
  // The ground the last processed frame shows (empty without a camera pose).
  const FrameFootprint& footprint() const { return footprint_; }
  const detection::DetectionStats& detectionStats() const { return detection_.stats(); }
  const PipelineTimings& timings() const { return timings_; }
  // Working px per frame px of the last frame (preprocess options: fixed, or from the GSD).
  double workingScale() const { return workingScale_; }
  // The backend the detector network runs on (Auto resolved at load).
  inference::Backend detectorBackend() const { return detection_.detectorBackend(); }
  // GSD at the image centre of the last frame with a camera pose (0 before the first), and how
  // often the working scale changed since init().
  double frameGsd_m() const { return frameGsd_m_; }
  std::uint64_t workingScaleChanges() const { return workingScaleChanges_; }
  // The corrected full-resolution frame of the last process() (what the detections' pixels
  // refer to; for annotation) and the Lifter on its camera.
  const cv::Mat& correctedFrame() const { return corrected_; }
  const lifting::Lifter& lifter() const { return lifter_; }
  const DetectionLifter& detectionLifter() const { return detectionLifter_; }
  const char* lastError() const { return lastError_.data(); }

 private:
  static void setError(std::array<char, 256>& error, const char* stage, const char* detail);

  bool initialised_ = false;
  preprocess::Preprocessor preprocessor_;
  detection::DetectionStage detection_;
  lifting::Lifter lifter_;
  lifting::PlaneLifter plane_;
  bool planar_ = false;  // lifting through plane_
  DetectionLifter detectionLifter_;
  FootprintType footprintType_;
  PoseGsdProvider gsd_;
  lifting::CameraPoseWorld cameraPose_{};
  DetectedFrame serial_{};  // process()'s own
  // detect()'s state across frames (the detector half's)
  double detectGsd_m_ = 0.0;
  std::uint64_t detectScaleChanges_ = 0;
  bool ownsCorrected_ = false;  // the preprocessor writes its own corrected frame
  // the last finished frame's (the finish half's)
  cv::Mat corrected_;
  double workingScale_ = 0.0;
  std::array<VehicleObservation, detection::kMaxDetectionsPerFrame> observations_{};
  FrameLiftSummary liftSummary_{};
  FootprintTypeScreening footprintTypeScreening_{};
  FrameFootprint footprint_{};
  PipelineTimings timings_{};
  double frameGsd_m_ = 0.0;
  std::uint64_t workingScaleChanges_ = 0;
  std::array<char, 256> lastError_{};
};

}  // namespace vp::perception
