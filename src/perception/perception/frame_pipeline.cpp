#include "perception/frame_pipeline.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>

namespace vp::perception {

namespace {

double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

}  // namespace

const char* toString(PipelineStatus status) {
  switch (status) {
    case PipelineStatus::Ok:
      return "ok";
    case PipelineStatus::NotInitialised:
      return "not initialised";
    case PipelineStatus::PreprocessFailed:
      return "preprocessing refused the frame";
    case PipelineStatus::DetectionFailed:
      return "detection failed";
  }
  return "unknown";
}

double groundSampleDistanceAt_m(const lifting::Lifter& lifter, const lifting::CameraPoseWorld& pose,
                                const Eigen::Vector2d& pixel) {
  const auto p0 = lifter.pixelToWorld(pose, pixel);
  const auto pu = lifter.pixelToWorld(pose, pixel + Eigen::Vector2d(1.0, 0.0));
  const auto pv = lifter.pixelToWorld(pose, pixel + Eigen::Vector2d(0.0, 1.0));
  if (!p0 || !pu || !pv) {
    return 0.0;
  }
  // Ground area covered by one pixel; its square root is the isotropic GSD the crop uses.
  const double area = (*pu - *p0).cross(*pv - *p0).norm();
  return area > 0.0 && std::isfinite(area) ? std::sqrt(area) : 0.0;
}

double PoseGsdProvider::groundSampleDistance_m(const detection::Detection& detection) const {
  if (plane_ != nullptr) {
    return plane_->groundSampleDistance_m(Eigen::Vector2d(detection.box.cx, detection.box.cy));
  }
  if (lifter_ == nullptr || pose_ == nullptr) {
    return 0.0;
  }
  return groundSampleDistanceAt_m(*lifter_, *pose_,
                                  Eigen::Vector2d(detection.box.cx, detection.box.cy));
}

void FramePipeline::setError(std::array<char, 256>& error, const char* stage, const char* detail) {
  std::snprintf(error.data(), error.size(), "%s: %s", stage, detail);
}

bool FramePipeline::init(const PipelineOptions& options, const camera::CameraModel& rawCamera,
                         const geodesy::CameraMount& mount, const terrain::TerrainModel& terrain,
                         const geodesy::LocalFrame& frame,
                         const shape::ActiveShapeModel& shapeModel, std::string* why) {
  return init(options, rawCamera, mount, terrain, frame, shapeModel, nullptr, why);
}

bool FramePipeline::init(const PipelineOptions& options, const camera::CameraModel& rawCamera,
                         const geodesy::CameraMount& mount, const terrain::TerrainModel& terrain,
                         const geodesy::LocalFrame& frame,
                         const shape::ActiveShapeModel& shapeModel,
                         const georef::GroundView* groundView, std::string* why) {
  initialised_ = false;
  planar_ = groundView != nullptr;
  std::string detail;
  if (!detection_.init(options.detection, preprocess::kMaxTiles, &detail)) {
    if (why)
      *why = detail;  // DetectionStage names itself ("detection stage: ...")
    return false;
  }
  // The tiles must be exactly the detector's input.
  preprocess::PreprocessOptions pre = options.preprocess;
  pre.networkWidth_px = detection_.detectorInputWidth();
  pre.networkHeight_px = detection_.detectorInputHeight();
  const cv::Size frameSize(rawCamera.intrinsics().width_px, rawCamera.intrinsics().height_px);
  if (!preprocessor_.init(pre, rawCamera, frameSize, &detail)) {
    if (why)
      *why = "preprocessing: " + detail;
    return false;
  }
  if (!lifter_.init(preprocessor_.frameCamera(), mount, terrain, frame, &detail)) {
    if (why)
      *why = "lifting: " + detail;
    return false;
  }
  // The ground view's homography is between ideal pixels: the plane lifter undistorts the
  // corrected frame's pixels when that frame still has the lens's distortion.
  if (planar_ && !plane_.init(groundView->homography, groundView->camera,
                              preprocessor_.frameCamera(), frame, &detail)) {
    if (why)
      *why = "lifting: " + detail;
    return false;
  }
  if (!(planar_ ? detectionLifter_.init(plane_, frame, shapeModel, options.lift, &detail)
                : detectionLifter_.init(terrain, frame, shapeModel, options.lift, &detail))) {
    if (why)
      *why = "detection lifter: " + detail;
    return false;
  }
  if (!footprintType_.init(options.footprintType, &detectionLifter_, &detail)) {
    if (why)
      *why = "perception.footprint_type: " + detail;
    return false;
  }
  // The preprocessor writes a corrected frame of its own when it undistorts or balances;
  // otherwise its output is a view of the caller's frame.
  ownsCorrected_ = preprocessor_.undistorts() || pre.whiteBalance;
  workingScale_ = preprocessor_.workingScale();
  detectGsd_m_ = 0.0;
  detectScaleChanges_ = 0;
  frameGsd_m_ = 0.0;
  workingScaleChanges_ = 0;
  corrected_ = cv::Mat();
  lastError_[0] = '\0';
  initialised_ = true;
  return true;
}

void FramePipeline::prepare(DetectedFrame& frame) const {
  frame = DetectedFrame{};
  if (initialised_ && ownsCorrected_) {
    const camera::Intrinsics& k = preprocessor_.frameCamera().intrinsics();
    frame.copy.create(k.height_px, k.width_px, CV_8UC3);
  }
}

PipelineStatus FramePipeline::process(const cv::Mat& bgrFrame, std::int64_t timestamp_ns,
                                      const telemetry::PoseEstimate& pose) {
  detect(bgrFrame, timestamp_ns, pose, serial_);
  return finish(serial_);
}

PipelineStatus FramePipeline::detect(const cv::Mat& bgrFrame, std::int64_t timestamp_ns,
                                     const telemetry::PoseEstimate& pose, DetectedFrame& out) {
  out.timings = PipelineTimings{};
  out.first = detection::FirstStageOutput{};
  out.timestamp_ns = timestamp_ns;
  out.frameWidth_px = bgrFrame.cols;
  out.frameHeight_px = bgrFrame.rows;
  out.error[0] = '\0';
  if (!initialised_) {
    setError(out.error, "pipeline", "process() before a successful init()");
    out.camera = FrameCameraPose{};
    return out.status = PipelineStatus::NotInitialised;
  }
  const auto start = std::chrono::steady_clock::now();
  // The camera pose at the frame time, computed once: the working scale, the second stage's GSD
  // and lifting use it.
  out.camera = detectionLifter_.cameraPoseFor(lifter_, pose.status, toDronePose(pose.pose));
  if (out.camera.status == LiftStatus::Ok) {
    // The working scale follows the height: the GSD where the optical axis meets the ground.
    const camera::Intrinsics& k = preprocessor_.frameCamera().intrinsics();
    const Eigen::Vector2d centre(0.5 * (k.width_px - 1), 0.5 * (k.height_px - 1));
    detectGsd_m_ = planar_ ? plane_.groundSampleDistance_m(centre)
                           : groundSampleDistanceAt_m(lifter_, out.camera.pose, centre);
    if (preprocessor_.adaptToGsd(detectGsd_m_)) {
      ++detectScaleChanges_;
    }
  }
  out.frameGsd_m = detectGsd_m_;
  out.workingScaleChanges = detectScaleChanges_;
  out.workingScale = preprocessor_.workingScale();
  const preprocess::PreprocessStatus pre = preprocessor_.process(bgrFrame);
  if (pre != preprocess::PreprocessStatus::Ok) {
    out.timings.preprocess_ms = msSince(start);
    setError(out.error, "preprocessing", preprocessor_.lastError());
    return out.status = PipelineStatus::PreprocessFailed;
  }
  const preprocess::PreprocessedFrame& frame = preprocessor_.output();
  out.geometry = frame.geometry;
  // The next frame's preprocessing overwrites the preprocessor's own buffer: a frame prepared
  // for the hand-off keeps a copy (a view of the caller's frame needs none).
  if (!out.copy.empty() && frame.frame.data != bgrFrame.data) {
    frame.frame.copyTo(out.copy);
    out.corrected = out.copy;
  } else {
    out.corrected = frame.frame;
  }
  out.timings.preprocess_ms = msSince(start);

  const detection::DetectionStatus det = detection_.detect(frame, out.detections, &out.first);
  out.timings.detector_ms = out.first.stats.detector_ms;
  out.timings.decode_ms = out.first.stats.decode_ms;
  if (det != detection::DetectionStatus::Ok) {
    setError(out.error, "detection", detection::toString(det));
    out.timings.total_ms = msSince(start);
    return out.status = PipelineStatus::DetectionFailed;
  }
  out.timings.total_ms = msSince(start);
  return out.status = PipelineStatus::Ok;
}

PipelineStatus FramePipeline::finish(DetectedFrame& in) {
  timings_ = in.timings;
  liftSummary_ = FrameLiftSummary{};
  footprint_ = FrameFootprint{};
  frameGsd_m_ = in.frameGsd_m;
  workingScaleChanges_ = in.workingScaleChanges;
  if (in.status != PipelineStatus::NotInitialised) {
    workingScale_ = in.workingScale;
  }
  if (in.status != PipelineStatus::Ok) {
    std::snprintf(lastError_.data(), lastError_.size(), "%s", in.error.data());
    return in.status;
  }
  corrected_ = in.corrected;
  const auto start = std::chrono::steady_clock::now();
  const PoseGsdProvider* gsd = nullptr;
  if (in.camera.status == LiftStatus::Ok) {
    cameraPose_ = in.camera.pose;
    if (planar_) {
      gsd_.setPlane(&plane_);
    } else {
      gsd_.setPose(&lifter_, &cameraPose_);
    }
    gsd = &gsd_;
  }
  std::size_t count = 0;
  const detection::DetectionStatus det =
      detection_.refine(in.corrected, in.geometry, in.first, in.detections, &count, gsd);
  gsd_.setPose(nullptr, nullptr);
  timings_.crops_ms = detection_.stats().crops_ms;
  if (det != detection::DetectionStatus::Ok) {
    setError(lastError_, "detection", detection::toString(det));
    timings_.total_ms = in.timings.total_ms + msSince(start);
    return PipelineStatus::DetectionFailed;
  }

  const auto liftStart = std::chrono::steady_clock::now();
  liftSummary_ = detectionLifter_.liftFrame(
      lifter_, in.timestamp_ns, in.camera,
      std::span<const detection::Detection>(in.detections.data(), count), observations_);
  footprintTypeScreening_ = footprintType_.apply(
      std::span<VehicleObservation>(observations_.data(), liftSummary_.written), lifter_,
      liftSummary_.cameraPose);
  footprint_ = planar_ ? frameFootprint(plane_, in.frameWidth_px, in.frameHeight_px)
                       : frameFootprint(lifter_, liftSummary_, in.frameWidth_px, in.frameHeight_px);
  timings_.lift_ms = msSince(liftStart);
  // Work time of the frame (the two halves; not the wait between them when pipelined).
  timings_.total_ms = in.timings.total_ms + msSince(start);
  lastError_[0] = '\0';
  return PipelineStatus::Ok;
}

}  // namespace vp::perception
