// sequence/recorded_sequence: the one on-disk format of recorded sequences (field recordings
// and the simulator), its reader and its writer. The format is documented in
// docs/recorded_sequence.md.
//
// Contract: a sequence is a directory holding rig.yaml (the application configuration
// schema: origin, camera, mount, terrain -> the DTM file beside it), sequence.yaml (format
// version, name, frame rate, source), frames.csv + the frame images, telemetry.csv, and
// optionally ground_truth/objects.csv and ground_truth/keypoints.csv. SequenceReader::open()
// reads and checks every text part at once (start-up) and reports the first problem naming
// the file, line and field ("telemetry.csv:17: qw: not a number 'x'"; timestamps going back
// or jumping more than kMaxTimestampGap_ns included); frame images are read
// one at a time by loadFrame(), which reports a missing or corrupt image as an error value,
// never an exception. SequenceWriter writes the same format (used by the simulator and by the
// firmware app's recorder): incrementally (open, frames and telemetry rows as they come,
// close writes sequence.yaml last), every image through a temporary file renamed into place,
// optionally every CSV row flushed at once (flushRows), and with removeOldestFrame() for a
// recorder that keeps within a disk budget (frames.csv then lists the kept frames only).
// rig.yaml's rig sections are read with the configuration's own rig reader
// (config::loadRigConfig: the same checks and messages as config::loadConfig) and handed out as
// a Rig, so that a reader of recordings (the replay frame source) needs none of the loop's
// configuration types; a program that needs a config::AppConfig copies the Rig into one.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "camera/camera_model.hpp"
#include "geodesy/attitude.hpp"
#include "geodesy/geodesy.hpp"
#include "geometry/rotated_box.hpp"
#include "shape/vehicle_model.hpp"
#include "terrain/terrain_model.hpp"

namespace vp::sequence {

constexpr int kFormatVersion = 1;

// The longest pause between two consecutive frames, or two consecutive telemetry samples, that
// a recording may hold. A recording is one continuous flight segment; a larger jump means a
// corrupt or spliced file, and a paced replay would wait that long for the next frame, so the
// reader refuses it at start-up naming the file and line.
constexpr std::int64_t kMaxTimestampGap_ns = 60'000'000'000;  // 60 s

struct SequenceInfo {
  int formatVersion = kFormatVersion;
  std::string name;
  double frameRate_hz = 10.0;
  std::string source;  // "simulator <version> seed <n> scene <name>", or a recorder's name
  std::string notes;   // optional free text; not written when empty
};

// What rig.yaml says (the sections origin, camera, mount and terrain of the configuration
// schema, docs/configuration.md), in the types of the modules that use them.
struct Rig {
  std::string sourcePath;           // rig.yaml
  geodesy::GeodeticPoint origin{};  // world ENU origin
  camera::Intrinsics intrinsics{};  // camera
  camera::Distortion distortion{};
  geodesy::CameraMount mount{};         // mount
  geodesy::GimbalState gimbal{};        // default gimbal state when telemetry has none
  std::string dtmPath;                  // terrain: absolute, an existing file
  std::optional<terrain::CrsSpec> crs;  // required only for world-file DTMs
  std::string sitePath;                 // site.file: the site map, absolute; empty without one
  std::string dsmPath;  // terrain.dsm_path: the surface model, absolute, existing; empty: none
  std::vector<std::string> warnings;  // unknown keys and other non-fatal remarks
};

struct FrameRecord {
  std::int64_t frameId = 0;
  std::int64_t timestamp_ns = 0;  // capture time, monotonic clock of the recording
  std::string file;               // relative to the sequence directory
};

struct TelemetryRecord {
  std::int64_t timestamp_ns = 0;  // same clock as the frames
  geodesy::GeodeticPoint position{};
  Eigen::Quaterniond bodyToNed{Eigen::Quaterniond::Identity()};
  geodesy::GimbalState gimbal{};
};

struct ObjectTruth {
  std::int64_t frameId = 0;
  int trackId = 0;
  shape::VehicleType type = shape::VehicleType::Sedan;
  shape::ShapeParams shape{};             // ASM gamma (count 0 for large vehicles)
  Eigen::Vector3d dimensions_m{0, 0, 0};  // length, width, height of the 3D bounding box
  Eigen::Vector3d positionEnu{0, 0, 0};   // vehicle-frame origin in the world (ENU), m
  double headingEnu_rad = 0.0;            // driving direction, counter-clockwise from east
  double speed_mps = 0.0;
  double yawRate_radps = 0.0;
  geometry::RotatedBox imageBox{};  // image rotated box (angle = driving direction)
  double truncation = 0.0;          // share of the vehicle outside the image, [0, 1]
  double occlusion = 0.0;           // share of the visible silhouette hidden, [0, 1]
  bool parked = false;
};

struct KeypointTruth {
  std::int64_t frameId = 0;
  int trackId = 0;
  int keypoint = 0;             // index into shape::keypointNames()
  Eigen::Vector2d pixel{0, 0};  // distorted image coordinates
  bool visible = false;         // not self-occluded, not occluded, inside the image
  Eigen::Vector3d worldEnu{0, 0, 0};
};

// A telemetry.csv on its own (e.g. beside a video replayed directly), with the reader's checks
// and messages; false and *why naming the file and line.
bool readTelemetryFile(const std::string& path, std::vector<TelemetryRecord>& out,
                       std::string* why);

class SequenceReader {
 public:
  SequenceReader() = default;

  bool open(const std::string& directory, std::string* why);

  const std::string& directory() const { return directory_; }
  const SequenceInfo& info() const { return info_; }
  const Rig& rig() const { return rig_; }  // camera, mount, origin, DTM path
  const std::vector<FrameRecord>& frames() const { return frames_; }
  const std::vector<TelemetryRecord>& telemetry() const { return telemetry_; }
  bool hasGroundTruth() const { return hasGroundTruth_; }
  // Ground truth of one frame (empty when none); spans into the reader's storage.
  std::span<const ObjectTruth> objects(std::int64_t frameId) const;
  std::span<const KeypointTruth> keypoints(std::int64_t frameId) const;

  // Decodes frame `index` into `image` (8-bit BGR). False + *why on a missing/corrupt file.
  bool loadFrame(std::size_t index, cv::Mat& image, std::string* why) const;

 private:
  std::string directory_;
  SequenceInfo info_{};
  Rig rig_{};
  std::vector<FrameRecord> frames_;
  std::vector<TelemetryRecord> telemetry_;
  bool hasGroundTruth_ = false;
  std::vector<ObjectTruth> objects_;      // sorted by frame
  std::vector<KeypointTruth> keypoints_;  // sorted by frame
};

// One frame encoded by SequenceWriter::encodeFrame() and written by writeEncodedFrame(): a
// recorder encodes first and decides with the size in hand (its disk budget). `bytes` is reused
// from frame to frame: once its capacity covers a frame, encoding the next one into it does
// not grow it.
struct EncodedFrame {
  FrameRecord record;  // file resolved (frames/<id>.<ext> when it was left empty)
  std::vector<unsigned char> bytes;
};

class SequenceWriter {
 public:
  SequenceWriter();  // defined in the .cpp, where Files is complete
  ~SequenceWriter();

  // Creates the directory layout; rigYaml is the text of rig.yaml, dtmFile an existing DTM
  // that is copied beside it (rig.yaml must name it as terrain.dtm_path: dtm.tif).
  bool open(const std::string& directory, const SequenceInfo& info, const std::string& rigYaml,
            const std::string& dtmFile, std::string* why);
  // imageExtension ".png" (lossless) or ".jpg" (jpegQuality 1..100). = encodeFrame() then
  // writeEncodedFrame().
  bool writeFrame(const FrameRecord& frame, const cv::Mat& image, std::string* why);
  // Checks the record as the reader would (after the frames written so far) and the image
  // (type, the rig's size), then encodes it into out. Writes nothing.
  bool encodeFrame(const FrameRecord& frame, const cv::Mat& image, EncodedFrame& out,
                   std::string* why);
  // Writes the image as <file>.tmp and renames it into place (a stop or a crash never leaves a
  // truncated image under its name), then its frames.csv row.
  bool writeEncodedFrame(const EncodedFrame& frame, std::string* why);
  // Deletes the oldest frame still kept (its image; its row goes when close() rewrites
  // frames.csv). False when no frame is kept or ground truth was written (its rows name the
  // frames).
  bool removeOldestFrame(std::string* why);
  // Replaces the notes written into sequence.yaml by close().
  void setNotes(const std::string& notes);
  // Bytes the writer has put on disk so far: rig.yaml, the DTM copy, the CSV files and the
  // kept images (a removed image no longer counts).
  std::uint64_t bytesOnDisk() const;
  std::size_t framesKept() const;     // frames written and not removed
  std::size_t framesRemoved() const;  // by removeOldestFrame()
  bool writeTelemetry(const TelemetryRecord& record, std::string* why);
  bool writeObjects(std::span<const ObjectTruth> objects, std::string* why);
  bool writeKeypoints(std::span<const KeypointTruth> keypoints, std::string* why);
  // Writes sequence.yaml (with frame_count) last; when frames were removed, frames.csv is first
  // rewritten (temporary file renamed into place) to list the kept frames only.
  bool close(std::string* why);

  std::string imageExtension = ".png";
  int jpegQuality = 92;
  // gamma_i columns of ground_truth/objects.csv (0..8), fixed when the file is created by the
  // first writeObjects(); -1: the largest shape count of that call (8 if it holds no shape).
  int gammaColumns = -1;
  // Flush every CSV row as it is written (one write(2) per row): a recorder that may be killed
  // leaves whole rows only. Off for batch writers (the simulator), which close properly.
  bool flushRows = false;

 private:
  struct Files;
  std::unique_ptr<Files> files_;  // the open CSV streams
  std::string directory_;
};

}  // namespace vp::sequence
