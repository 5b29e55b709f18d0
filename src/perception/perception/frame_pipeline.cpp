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

void FramePipeline::setError(const char* stage, const char* detail) {
  std::snprintf(lastError_.data(), lastError_.size(), "%s: %s", stage, detail);
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
  lastError_[0] = '\0';
  initialised_ = true;
  return true;
}

PipelineStatus FramePipeline::process(const cv::Mat& bgrFrame, std::int64_t timestamp_ns,
                                      const telemetry::PoseEstimate& pose) {
  timings_ = PipelineTimings{};
  liftSummary_ = FrameLiftSummary{};
  footprint_ = FrameFootprint{};
  if (!initialised_) {
    setError("pipeline", "process() before a successful init()");
    return PipelineStatus::NotInitialised;
  }
  const auto start = std::chrono::steady_clock::now();
  // The camera pose at the frame time, computed once: the working scale, the second stage's GSD
  // and lifting use it.
  const FrameCameraPose camera =
      detectionLifter_.cameraPoseFor(lifter_, pose.status, toDronePose(pose.pose));
  if (camera.status == LiftStatus::Ok) {
    // The working scale follows the height: the GSD where the optical axis meets the ground.
    const camera::Intrinsics& k = preprocessor_.frameCamera().intrinsics();
    const Eigen::Vector2d centre(0.5 * (k.width_px - 1), 0.5 * (k.height_px - 1));
    frameGsd_m_ = planar_ ? plane_.groundSampleDistance_m(centre)
                          : groundSampleDistanceAt_m(lifter_, camera.pose, centre);
    if (preprocessor_.adaptToGsd(frameGsd_m_)) {
      ++workingScaleChanges_;
    }
  }
  const preprocess::PreprocessStatus pre = preprocessor_.process(bgrFrame);
  timings_.preprocess_ms = msSince(start);
  if (pre != preprocess::PreprocessStatus::Ok) {
    setError("preprocessing", preprocessor_.lastError());
    return PipelineStatus::PreprocessFailed;
  }

  const PoseGsdProvider* gsd = nullptr;
  if (camera.status == LiftStatus::Ok) {
    cameraPose_ = camera.pose;
    if (planar_) {
      gsd_.setPlane(&plane_);
    } else {
      gsd_.setPose(&lifter_, &cameraPose_);
    }
    gsd = &gsd_;
  }
  std::size_t count = 0;
  const detection::DetectionStatus det =
      detection_.run(preprocessor_.output(), detections_, &count, gsd);
  gsd_.setPose(nullptr, nullptr);
  const detection::DetectionStats& stats = detection_.stats();
  timings_.detector_ms = stats.detector_ms;
  timings_.decode_ms = stats.decode_ms;
  timings_.crops_ms = stats.crops_ms;
  if (det != detection::DetectionStatus::Ok) {
    setError("detection", detection::toString(det));
    timings_.total_ms = msSince(start);
    return PipelineStatus::DetectionFailed;
  }

  const auto liftStart = std::chrono::steady_clock::now();
  liftSummary_ = detectionLifter_.liftFrame(
      lifter_, timestamp_ns, camera,
      std::span<const detection::Detection>(detections_.data(), count), observations_);
  footprint_ = planar_ ? frameFootprint(plane_, bgrFrame.cols, bgrFrame.rows)
                       : frameFootprint(lifter_, liftSummary_, bgrFrame.cols, bgrFrame.rows);
  timings_.lift_ms = msSince(liftStart);
  timings_.total_ms = msSince(start);
  lastError_[0] = '\0';
  return PipelineStatus::Ok;
}

}  // namespace vp::perception
