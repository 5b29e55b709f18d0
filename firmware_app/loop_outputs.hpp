// firmware_app/loop_outputs: the loop's files: the trajectory file (sequence/trajectory_file:
// tracking/trajectory_csv's rows), the detections file (sequence/detections_file) and the
// optional annotated video.
//
// Contract: open() creates every configured file (start-up: allocates the row and pending-row
// buffers and the annotation image; fails naming the file). The per-frame writes format into
// preallocated buffers; endFrame() then writes each file's rows of the frame with one write(2)
// (no buffering across frames: a kill loses at most the frame being written, and a file always
// ends with a complete row). The CSV outputs allocate nothing per frame, errors included; the
// annotated video goes through cv::VideoWriter (MJPG in AVI), which allocates per frame
// (documented; off by default). A failed write (disk full, I/O error) or a refused row is
// counted when it happens (errors()) and logged the first time per file with the file, the
// frame and the reason; the loop goes on (the app's exit status is then 1). close() commits and
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
#include "output_files/traffic_files.hpp"
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
  // The traffic files (app.traffic_dir, output_files/traffic_files) of the analysis' features,
  // after open(); start-up. Their rows go out with the frame's (endFrame()); a refused row or a
  // failed write is counted and logged once like the other files'.
  bool openTraffic(const std::string& dir, const output_files::TrafficFeatureIds& ids,
                   const geodesy::LocalFrame& world, std::string* why);
  void writeTrafficEvent(const traffic::TrafficEvent& event);
  void writeTrafficStatistics(const traffic::TrafficStatistics& statistics);
  // Published tracks of one frame; states[i] (its WGS84 position) is tracks[i]'s message.
  void writeTracks(std::int64_t frameId, std::span<const tracking::TrackState> tracks,
                   std::span<const messages::VehicleState> states);
  void writeDetections(std::int64_t frameId,
                       std::span<const perception::VehicleObservation> observations);
  // Writes the frame's rows of each file (one write(2) per file); errors counted and logged.
  void endFrame(std::int64_t frameId);
  bool wantsVideo() const { return video_.isOpened(); }
  void writeVideo(const cv::Mat& correctedFrame,
                  std::span<const perception::VehicleObservation> observations,
                  const lifting::Lifter* lifter, const lifting::CameraPoseWorld* cameraPose);
  bool close(std::string* why);

  std::uint64_t errors() const { return errors_; }
  std::uint64_t trajectoryRows() const { return trajectoryRows_; }
  std::uint64_t trafficErrors() const { return trafficErrors_.count; }

 private:
  // One output file's error state: the first error is logged, every one counted.
  struct FileErrors {
    std::string logPath;  // the path shortened for messages (made at open, no allocation later)
    std::uint64_t count = 0;
  };
  void rowRefused(FileErrors& file, std::int64_t frameId);
  void writeFailed(FileErrors& file, std::int64_t frameId, int error);
  void trafficFailed(output_files::TrafficWriteStatus status, const char* at, std::int64_t value);

  OutputSpec spec_{};
  output_files::TrajectoryFileWriter trajectory_;
  std::uint64_t trajectoryRows_ = 0;
  output_files::DetectionsFileWriter detections_;
  cv::VideoWriter video_;
  annotation::Annotator annotator_;
  cv::Mat annotated_;
  FileErrors trajectoryErrors_;
  FileErrors detectionsErrors_;
  output_files::TrafficFilesWriter traffic_;
  FileErrors trafficErrors_;
  std::uint64_t errors_ = 0;
};

}  // namespace vp::app
