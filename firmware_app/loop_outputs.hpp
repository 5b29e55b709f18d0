// firmware_app/loop_outputs: the loop's files: the trajectory file (sequence/trajectory_file:
// tracking/trajectory_csv's rows), the detections file (sequence/detections_file) and the
// optional annotated video.
//
// Contract: open() creates every configured file (start-up: allocates the stdio buffers, the
// row buffers and the annotation image; fails naming the file). The per-frame writes format
// into preallocated buffers and hand the bytes to stdio with its preallocated buffer, so the
// CSV outputs allocate nothing per frame; the annotated video goes through cv::VideoWriter
// (MJPG in AVI), which allocates per frame (documented; off by default). Write errors are
// counted (errors()) and the first is kept in lastError(); the loop goes on. close() flushes and
// closes (also done by the destructor). Trajectory rows: the published tracks (confirmed and
// lost, with their status), one row per track per frame. Detection rows: every observation of
// the frame, lifted or not, with perception::LiftStatus as the file's lift_status word.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include "annotation/annotator.hpp"
#include "config/config.hpp"
#include "messages/messages.hpp"
#include "output_files/detections_file.hpp"
#include "output_files/trajectory_file.hpp"
#include "perception/detection_lifter.hpp"

namespace vp::app {

output_files::LiftStatus toFileStatus(perception::LiftStatus status);
// One detections-file row from an observation (frame id and detection index given).
output_files::DetectionRecord toDetectionRecord(std::int64_t frameId, int detId,
                                                const perception::VehicleObservation& observation);

struct OutputSpec {
  std::string trajectoryCsv;   // empty = off
  std::string detectionsCsv;   // empty = off
  std::string annotatedVideo;  // empty = off
  double videoFps = 10.0;
  cv::Size frameSize{};
  int gammaColumns = 3;
  std::string model;   // "# model:" of the detections file
  std::string source;  // "# source:" of the detections file
};

class LoopOutputs {
 public:
  LoopOutputs() = default;
  ~LoopOutputs();
  LoopOutputs(const LoopOutputs&) = delete;
  LoopOutputs& operator=(const LoopOutputs&) = delete;

  bool open(const OutputSpec& spec, std::string* why);
  // Published tracks of one frame; states[i] (its WGS84 position) is tracks[i]'s message.
  void writeTracks(std::int64_t frameId, std::span<const tracking::TrackState> tracks,
                   std::span<const messages::VehicleState> states);
  void writeDetections(std::int64_t frameId,
                       std::span<const perception::VehicleObservation> observations);
  bool wantsVideo() const { return video_.isOpened(); }
  void writeVideo(const cv::Mat& correctedFrame,
                  std::span<const perception::VehicleObservation> observations,
                  const lifting::Lifter* lifter, const lifting::CameraPoseWorld* cameraPose);
  bool close(std::string* why);

  std::uint64_t errors() const { return errors_; }
  std::uint64_t trajectoryRows() const { return trajectoryRows_; }
  const std::string& lastError() const { return lastError_; }

 private:
  void fail(const std::string& what);

  OutputSpec spec_{};
  output_files::TrajectoryFileWriter trajectory_;
  std::uint64_t trajectoryRows_ = 0;
  output_files::DetectionsFileWriter detections_;
  cv::VideoWriter video_;
  annotation::Annotator annotator_;
  cv::Mat annotated_;
  std::uint64_t errors_ = 0;
  std::string lastError_;
};

}  // namespace vp::app
