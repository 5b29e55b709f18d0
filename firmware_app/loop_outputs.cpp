#include "loop_outputs.hpp"

#include <cstring>

#include "csv/csv_io.hpp"
#include "loop_log.hpp"

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
  record.atFrameEdge = d.atFrameEdge;
  record.vehicleProbability = d.vehicleProbability;
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

void LoopOutputs::rowRefused(FileErrors& file, std::int64_t frameId) {
  ++errors_;
  if (file.count++ == 0) {
    logLine(
        "%s: a row of frame %lld was refused (a value out of the file's range); further "
        "errors of this file are only counted",
        file.logPath.c_str(), static_cast<long long>(frameId));
  }
}

void LoopOutputs::writeFailed(FileErrors& file, std::int64_t frameId, int error) {
  ++errors_;
  if (file.count++ == 0) {
    logLine(
        "%s: write failed at frame %lld: %s (the rows of that frame are lost; further "
        "errors of this file are only counted, the exit status will be 1)",
        file.logPath.c_str(), static_cast<long long>(frameId), std::strerror(error));
  }
}

bool LoopOutputs::open(const OutputSpec& spec, std::string* why) {
  spec_ = spec;
  trajectoryErrors_ = {csv::shortened(spec.trajectoryCsv), 0};
  detectionsErrors_ = {csv::shortened(spec.detectionsCsv), 0};
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
        *why = csv::shortened(spec.annotatedVideo) +
               ": cannot open the annotated video (MJPG/AVI, " +
               std::to_string(spec.frameSize.width) + "x" + std::to_string(spec.frameSize.height) +
               ")";
      }
      return false;
    }
  }
  return true;
}

bool LoopOutputs::openTraffic(const std::string& dir, const output_files::TrafficFeatureIds& ids,
                              const geodesy::LocalFrame& world, std::string* why) {
  trafficErrors_ = {csv::shortened(dir) + "/traffic_*.csv", 0};
  return traffic_.open(dir, ids, world, why);
}

void LoopOutputs::trafficFailed(output_files::TrafficWriteStatus status, const char* at,
                                std::int64_t value) {
  ++errors_;
  if (trafficErrors_.count++ == 0) {
    logLine("%s: rows not written (%s %lld): %s; further errors of these files are only counted",
            trafficErrors_.logPath.c_str(), at, static_cast<long long>(value),
            output_files::toString(status));
  }
}

void LoopOutputs::writeTrafficEvent(const traffic::TrafficEvent& event) {
  if (!traffic_.isOpen()) {
    return;
  }
  const output_files::TrafficWriteStatus status = traffic_.writeEvent(event);
  if (status != output_files::TrafficWriteStatus::Ok) {
    trafficFailed(status, "event time_ns", event.time_ns);
  }
}

void LoopOutputs::writeTrafficStatistics(const traffic::TrafficStatistics& statistics) {
  if (!traffic_.isOpen()) {
    return;
  }
  const output_files::TrafficWriteStatus status = traffic_.writeStatistics(statistics);
  if (status != output_files::TrafficWriteStatus::Ok) {
    trafficFailed(status, "period", static_cast<std::int64_t>(statistics.sequence));
  }
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
    const messages::VehicleState& state = states[i];
    tracking::TrajectoryPlace place;
    place.utmZone = state.utmZone;
    place.utmNorth = state.utmNorthernHemisphere;
    place.utmEasting_m = state.utmEasting_m;
    place.utmNorthing_m = state.utmNorthing_m;
    place.hasRearAxle = true;
    place.rearAxle = {state.rearAxlePosition.latitude_deg, state.rearAxlePosition.longitude_deg,
                      state.rearAxlePosition.height_m};
    const std::int64_t lost = trajectory_.rowsLost();
    if (!trajectory_.writeRow(frameId, tracks[i], &wgs84, nullptr, &place)) {
      // Refused by the checks, or the pending rows were full and their write failed.
      if (trajectory_.rowsLost() != lost) {
        writeFailed(trajectoryErrors_, frameId, trajectory_.lastErrno());
      } else {
        rowRefused(trajectoryErrors_, frameId);
        continue;
      }
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
    const std::int64_t lost = detections_.rowsLost();
    if (!detections_.writeRow(record, nullptr)) {
      if (detections_.rowsLost() != lost) {
        writeFailed(detectionsErrors_, frameId, detections_.lastErrno());
      } else {
        rowRefused(detectionsErrors_, frameId);
      }
    }
  }
}

void LoopOutputs::endFrame(std::int64_t frameId) {
  if (trajectory_.isOpen() && !trajectory_.commit()) {
    writeFailed(trajectoryErrors_, frameId, trajectory_.lastErrno());
  }
  if (detections_.isOpen() && !detections_.commit()) {
    writeFailed(detectionsErrors_, frameId, detections_.lastErrno());
  }
  if (traffic_.isOpen()) {
    const output_files::TrafficWriteStatus status = traffic_.commit();
    if (status != output_files::TrafficWriteStatus::Ok) {
      trafficFailed(status, "frame", frameId);
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
  // A failure already counted and logged during the run is not reported again; close()
  // reports only what failed at the end (the last commit, close(2)).
  bool ok = true;
  std::string problem;
  if (trajectory_.isOpen() && !trajectory_.close(&problem) && trajectoryErrors_.count == 0) {
    ok = false;
  }
  if (detections_.isOpen() && !detections_.close(&problem) && detectionsErrors_.count == 0) {
    ok = false;
  }
  if (traffic_.isOpen() && !traffic_.close(&problem) && trafficErrors_.count == 0) {
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
