#include "loop_outputs.hpp"

namespace vp::app {

output_files::LiftStatus toFileStatus(perception::LiftStatus status) {
  using In = perception::LiftStatus;
  using Out = output_files::LiftStatus;
  switch (status) {
    case In::Ok:
      return Out::Ok;
    case In::NoPose:
      return Out::NoPose;
    case In::StalePose:
      return Out::StalePose;
    case In::InvalidPose:
      return Out::InvalidPose;
    case In::InvalidBox:
      return Out::InvalidBox;
    case In::OutsideLens:
      return Out::OutsideLens;
    case In::BehindCamera:
      return Out::BehindCamera;
    case In::OutsideDtm:
      return Out::OutsideDtm;
    case In::NoData:
      return Out::NoData;
    case In::NoIntersection:
      return Out::NoIntersection;
  }
  return Out::NotLifted;
}

output_files::DetectionRecord toDetectionRecord(std::int64_t frameId, int detId,
                                                const perception::VehicleObservation& observation) {
  output_files::DetectionRecord record;
  const detection::Detection& d = observation.detection;
  record.frameId = frameId;
  record.detId = detId;
  record.score = d.score;
  record.box = d.box;
  record.directionKnown = d.directionKnown;
  record.typeProbabilities = d.typeProbabilities;
  record.gamma = d.gamma;
  record.liftStatus = toFileStatus(observation.liftStatus);
  if (observation.liftStatus == perception::LiftStatus::Ok) {
    record.positionEnu = observation.ground.centreEnu;
    record.latitude_deg = observation.ground.centreWgs84.latitude_deg;
    record.longitude_deg = observation.ground.centreWgs84.longitude_deg;
    record.height_m = observation.ground.centreWgs84.height_m;
    record.headingEnu_rad = observation.ground.headingEnu_rad;
    record.dimensions_m = Eigen::Vector3d(observation.ground.length_m, observation.ground.width_m,
                                          observation.height_m);
  }
  return record;
}

LoopOutputs::~LoopOutputs() {
  close(nullptr);
}

void LoopOutputs::fail(const std::string& what) {
  ++errors_;
  if (lastError_.empty()) {
    lastError_ = what;
  }
}

bool LoopOutputs::open(const OutputSpec& spec, std::string* why) {
  spec_ = spec;
  if (!spec.trajectoryCsv.empty()) {
    output_files::TrajectoryFileInfo info;
    info.gammaColumns = spec.gammaColumns;
    if (!trajectory_.open(spec.trajectoryCsv, info, why)) {
      return false;
    }
  }
  if (!spec.detectionsCsv.empty()) {
    output_files::DetectionsFileInfo info;
    info.key = output_files::DetectionsKey::FrameId;
    info.gammaColumns = spec.gammaColumns;
    info.model = spec.model;
    info.source = spec.source;
    if (!detections_.open(spec.detectionsCsv, info, why)) {
      return false;
    }
  }
  if (!spec.annotatedVideo.empty()) {
    std::string problem;
    if (!annotator_.init(annotation::AnnotationStyle{}, &problem)) {
      if (why) {
        *why = "annotation: " + problem;
      }
      return false;
    }
    annotated_.create(spec.frameSize, CV_8UC3);
    if (!video_.open(spec.annotatedVideo, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'),
                     spec.videoFps, spec.frameSize, true)) {
      if (why) {
        *why = spec.annotatedVideo + ": cannot open the annotated video (MJPG/AVI, " +
               std::to_string(spec.frameSize.width) + "x" + std::to_string(spec.frameSize.height) +
               ")";
      }
      return false;
    }
  }
  return true;
}

void LoopOutputs::writeTracks(std::int64_t frameId, std::span<const tracking::TrackState> tracks,
                              std::span<const messages::VehicleState> states) {
  if (!trajectory_.isOpen()) {
    return;
  }
  for (std::size_t i = 0; i < tracks.size() && i < states.size(); ++i) {
    const tracking::Wgs84Position wgs84{states[i].position.latitude_deg,
                                        states[i].position.longitude_deg,
                                        states[i].position.height_m};
    if (!trajectory_.writeRow(frameId, tracks[i], &wgs84, nullptr)) {
      fail(spec_.trajectoryCsv + ": a row was not written (frame " + std::to_string(frameId) +
           ", track " + std::to_string(tracks[i].id) + ")");
      continue;
    }
    ++trajectoryRows_;
  }
}

void LoopOutputs::writeDetections(std::int64_t frameId,
                                  std::span<const perception::VehicleObservation> observations) {
  if (!detections_.isOpen()) {
    return;
  }
  int detId = 0;
  for (const perception::VehicleObservation& observation : observations) {
    const output_files::DetectionRecord record = toDetectionRecord(frameId, detId++, observation);
    if (!detections_.writeRow(record, nullptr)) {
      fail(spec_.detectionsCsv + ": row not written");
    }
  }
}

void LoopOutputs::writeVideo(const cv::Mat& correctedFrame,
                             std::span<const perception::VehicleObservation> observations,
                             const lifting::Lifter* lifter,
                             const lifting::CameraPoseWorld* cameraPose) {
  if (!video_.isOpened() || correctedFrame.size() != annotated_.size() ||
      correctedFrame.type() != CV_8UC3) {
    return;
  }
  correctedFrame.copyTo(annotated_);
  annotator_.drawFrame(annotated_, observations, {}, lifter, cameraPose);
  video_.write(annotated_);
}

bool LoopOutputs::close(std::string* why) {
  bool ok = true;
  std::string problem;
  if (trajectory_.isOpen() && !trajectory_.close(&problem)) {
    ok = false;
  }
  if (detections_.isOpen() && !detections_.close(&problem)) {
    ok = false;
  }
  if (video_.isOpened()) {
    video_.release();
  }
  if (!ok && why) {
    *why = problem;
  }
  return ok;
}

}  // namespace vp::app
