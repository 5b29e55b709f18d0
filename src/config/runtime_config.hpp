// config/runtime_config: the typed sections of the configuration that drive the firmware app's
// loop: `perception:` (models, backend, preprocessing, decoding), `pose:` (pose buffer),
// `tracking:` (the tracker values worth tuning), `source:` (replay or V4L2 camera),
// `telemetry:` (where the drone pose comes from) and `app:` (frame pool, queue, real-time
// settings, statistics, file outputs).
//
// Contract: plain values with the documented defaults (docs/configuration.md, config/default.yaml),
// no types of the modules they configure (the app maps them), so the configuration library
// keeps its few dependencies. config.cpp reads and checks them (ConfigError naming the file and
// the full key path); paths are absolute after loading (relative ones resolved against the
// configuration file's directory). Start-up only.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace vp::config {

enum class InferenceBackend : std::uint8_t { Int8, Fp32, OpenCv };
const char* toString(InferenceBackend backend);  // "int8", "fp32", "opencv"

struct PerceptionConfig {
  // Default values are relative to the configuration file's directory: the repository's
  // (and the package's) layout with config/ beside models/.
  static constexpr const char* kDefaultDetectorModel = "../models/detector/detector_int8.onnx";
  static constexpr const char* kDefaultCropModel = "../models/detector/crop_int8.onnx";
  static constexpr const char* kDefaultAsm = "../models/asm/default_asm.yaml";

  std::string detectorModel;  // absolute after loading
  std::string cropModel;      // absolute; empty = no second stage (`crop_model: none`)
  std::string asmPath;        // absolute
  InferenceBackend backend = InferenceBackend::Int8;
  int threads = 1;         // detector engine and preprocessing row threads, [1, 16]
  int cropThreads = 1;     // crop network threads, [1, 16]
  bool undistort = false;  // the shipped detector is trained on raw (distorted) frames
  bool whiteBalance = false;
  int whiteBalanceRegionRows = 3;  // seed 001's 3 x 4 regions
  int whiteBalanceRegionCols = 4;
  int whiteBalanceSampleStridePx = 4;
  double whiteBalanceWhiteShare = 0.10;
  double whiteBalanceMaxGain = 4.0;
  double workingScale = 648.0 / 2592.0;  // working px per frame px
  int tileOverlapPx = 96;                // working px
  double scoreThreshold = 0.4;           // heatmap probability
  int topKPerTile = 200;
  double nmsIou = 0.5;
  double duplicateOverlap = 0.5;
  double cutEdgeMarginPx = 4.0;  // working px
  int maxCrops = 512;
  bool applyFlip = true;
  bool applyRefine = true;
  bool cropMirrorAverage = true;     // second crop-network run on the mirrored crop, type averaged
  bool cropMirrorRefine = true;      // ... and the box refinement
  bool cropLargeVehicleEnds = true;  // front/back of a most-likely-large vehicle from its ends
  // The crop network's verifier: detections it gives a lower vehicle probability are dropped;
  // [0, 1], 0 = keep all (also what a crop network without the verifier output does). 0.3:
  // chosen on the tuning seeds (docs/model_card.md, round 8).
  double cropMinVehicleProbability = 0.3;
  double fixedGsd_m = 0.0;  // m per frame px; 0 = from the pose and DTM / estimated
  double nominalCarLength_m = 4.5;
  double liftHeightShare = 0.5;  // boxes lifted at this share of the vehicle's height, [0, 1]
};

struct PoseConfig {
  double maxAge_s = 0.2;     // nearest sample further from the frame time -> stale
  int bufferCapacity = 256;  // samples kept (25 s of 10 Hz telemetry)
};

struct TrackingConfig {
  int maxTracks = 256;  // live tracks, [1, 1024] (the publisher's table)
  int confirmHits = 3;
  double maxTentativeGap_s = 0.25;
  double maxLost_s = 3.0;
  double maxLostAtEdge_s = 1.0;  // lost track last seen at the frame's border deleted after this
  double coast_s = 0.3;          // unmatched confirmed tracks stay confirmed this long, then lost
  double movingSpeed_mps = 1.5;
  int flipVotes = 3;
  double typeEvidenceWeight = 0.5;
  double shapeMaxWeight = 30.0;
  double maxDistance_m = 6.0;           // association gate on the centre distance
  double highScore = 0.45;              // first association pass and track birth from here
  double lowScore = 0.1;                // second (ByteTrack) pass from here
  double measurementPosition_m = 0.30;  // 1 sigma of a lifted detection's centre, per axis
  double measurementHeading_deg = 8.0;  // 1 sigma of a detection's heading
  double steeringDecay_s = 2.0;         // steering relaxes to 0 with this time constant; 0 = never
  int confirmWholeHits = 2;             // of the confirm_hits, detections not partial, [0, 100]
  int confirmHitsAnyway = 5;            // matches that confirm a track whatever they were, [1, 100]
  int confirmHitsStanding = 2;          // whole matches that confirm a standing track, [1, 100]
  int confirmHitsLarge = 6;             // matches that confirm a large vehicle's track, [1, 100]
  double confirmMinScore = 0.0;         // mean track score needed to confirm, [0, 1]; 0 = off
  double partialInsideShare = 0.97;     // a detection with less of its box in the frame is partial
  double partialAlongNoiseFactor = 10.0;  // its along-axis position sigma factor, [1, 1000]
};

enum class FrameSourceKind : std::uint8_t { Replay, V4l2 };
const char* toString(FrameSourceKind kind);  // "replay", "v4l2"

enum class CameraPixelFormat : std::uint8_t { Yuyv, Nv12, Mjpeg };
const char* toString(CameraPixelFormat format);         // "yuyv", "nv12", "mjpeg"
std::vector<CameraPixelFormat> defaultCameraFormats();  // yuyv, nv12, mjpeg

struct V4l2SourceConfig {
  std::string device = "/dev/video0";
  std::string busInfo;  // when set, the device whose VIDIOC_QUERYCAP bus_info matches
  int widthPx = 2592;
  int heightPx = 2048;
  std::vector<CameraPixelFormat> formats = defaultCameraFormats();  // tried in order
  int buffers = 4;
  int dequeueTimeoutMs = 1000;
};

struct SourceConfig {
  FrameSourceKind kind = FrameSourceKind::Replay;
  std::string sequenceDir;  // replay: the recorded sequence (absolute); empty: --sequence
  bool paced = true;        // replay at the recorded frame rate
  bool loop = false;        // replay: start over after the last frame
  V4l2SourceConfig v4l2{};
};

enum class TelemetrySourceKind : std::uint8_t { Recording, MavlinkUdp, MavlinkSerial, Dds, None };
const char* toString(TelemetrySourceKind kind);

struct TelemetryLinkConfig {
  TelemetrySourceKind source = TelemetrySourceKind::Recording;
  std::string udpBindAddress = "0.0.0.0";
  int udpPort = 14550;
  std::string serialDevice = "/dev/ttyACM0";
  int serialBaud = 921600;
  int systemId = 0;                // MAVLink system id of the autopilot; 0 = any
  double geoidSeparation_m = 0;    // N of the flying area: ellipsoidal = MSL + N (MAVLink)
  double linkLatency_s = 0.0;      // minimum transport delay subtracted from MAVLink times
  double replayLookahead_s = 0.2;  // recording: samples pushed up to frame time + this
};

struct LoopConfig {
  int queueDepth = 1;               // frames waiting between capture and processing, [1, 8]
  int framePoolSize = 0;            // 0 = queueDepth + 2 (waiting + processing + capturing)
  bool lockMemory = false;          // mlockall
  int realtimePriority = 0;         // SCHED_FIFO priority of the processing thread; 0 = off
  std::vector<int> captureCpus;     // CPU affinity of the capture thread; empty = any
  std::vector<int> processingCpus;  // CPU affinity of the processing thread; empty = any
  double statsPeriod_s = 5.0;       // one statistics line per period
  std::string trajectoryCsv;        // absolute; empty = not written
  std::string detectionsCsv;        // absolute; empty = not written
  std::string annotatedVideo;       // absolute; empty = not written (MJPG AVI)
  double annotatedVideoFps = 10.0;
};

}  // namespace vp::config
