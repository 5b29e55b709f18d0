// config/loop_config: the firmware app's own sections of the configuration: `source:` (replay,
// V4L2 camera or a drone video), `telemetry:` (where the drone pose comes from) and `app:` (frame
// pool, queue, real-time settings, statistics, file outputs, `app.record:` the recording of what
// the loop sees). The sections that configure modules
// of src/ (perception, pose, tracking) are those modules' own options structs (config.hpp).
//
// Contract: plain values with the documented defaults (docs/configuration.md,
// config/default.yaml); the app maps them onto its platform wrappers. The section readers
// (source_section.cpp, telemetry_section.cpp, app_section.cpp) check them (ConfigError naming
// the file and the full key path); paths are absolute after loading (relative ones resolved
// against the configuration file's directory). Start-up only.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "subtitle_telemetry/subtitle_telemetry.hpp"

namespace vp::config {

enum class FrameSourceKind : std::uint8_t { Replay, V4l2, Video };
const char* toString(FrameSourceKind kind);  // "replay", "v4l2", "video"

enum class CameraPixelFormat : std::uint8_t { Yuyv, Nv12, Mjpeg };
const char* toString(CameraPixelFormat format);         // "yuyv", "nv12", "mjpeg"
std::vector<CameraPixelFormat> defaultCameraFormats();  // yuyv, nv12, mjpeg

struct V4l2SourceConfig {
  std::string device = "/dev/video0";
  std::string busInfo;  // when set, the device whose VIDIOC_QUERYCAP bus_info matches
  int width_px = 2592;
  int height_px = 2048;
  std::vector<CameraPixelFormat> formats = defaultCameraFormats();  // tried in order
  int buffers = 4;
  int dequeueTimeout_ms = 1000;
};

// A drone video replayed directly (platform/replay/video_replay.hpp); the camera and the DTM
// are the configuration's own sections.
struct VideoSourceConfig {
  std::string path;          // the video file (absolute); empty: none given
  std::string srt;           // its telemetry subtitles (absolute), or
  std::string telemetryCsv;  // a telemetry.csv on the video's clock (absolute); one of the two
  subtitle::SubtitleTelemetryOptions subtitles{};  // heights and the nadir yaw of the SRT
};

struct SourceConfig {
  FrameSourceKind kind = FrameSourceKind::Replay;
  std::string sequenceDir;  // replay: the recorded sequence (absolute); empty: --sequence
  bool paced = true;        // replay at the recorded frame rate
  bool loop = false;        // replay: start over after the last frame
  V4l2SourceConfig v4l2{};
  VideoSourceConfig video{};
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

// What to do when the recording reaches its disk budget (RecordConfig).
enum class RecordFullPolicy : std::uint8_t {
  Stop,  // finish the sequence (sequence.yaml written) and record nothing more
  Ring,  // delete the oldest frame images to make room; frames.csv lists the kept ones
};
const char* toString(RecordFullPolicy policy);  // "stop", "ring"

// `app.record:` the loop writes what it sees (frames as JPEG, their timestamps, the pose samples
// as received, the rig) as a recorded sequence (docs/field_data.md, docs/recorded_sequence.md).
struct RecordConfig {
  std::string dir;            // absolute; empty = not recording (--record DIR sets it)
  int jpegQuality = 90;       // [1, 100]
  int everyNthFrame = 1;      // record one frame in n taken from the source, [1, 1000]
  int queueFrames = 4;        // preallocated camera-size buffers waiting for the writer, [1, 64]
  int maxDisk_mib = 0;        // disk budget of the recording (MiB, 2^20 bytes); 0 = none
  int minFreeDisk_mib = 256;  // the file system keeps at least this much free (MiB); 0 = off
  RecordFullPolicy onFull = RecordFullPolicy::Stop;
};

// How the processing of a frame is spread over threads (app.pipeline, docs/firmware_app.md).
enum class PipelineMode : std::uint8_t {
  Off,  // one processing thread: each frame's whole work, one frame after the other
  On,   // a detector thread (pose, preprocess, detector, decoding) overlapped with the
        // processing thread (crops, lifting, tracker, outputs) one frame behind it
};
const char* toString(PipelineMode mode);  // "off", "on"

struct LoopConfig {
  int queueDepth = 1;  // frames waiting between capture and processing, [1, 8]
  PipelineMode pipeline = PipelineMode::Off;
  // 0 = queueDepth + 2 (waiting + processing + capturing), + 1 with the pipeline on (the frame
  // between its two threads)
  int framePoolSize = 0;
  bool lockMemory = false;          // mlockall
  int realtimePriority = 0;         // SCHED_FIFO priority of the processing thread; 0 = off
  std::vector<int> captureCpus;     // CPU affinity of the capture thread; empty = any
  std::vector<int> processingCpus;  // CPU affinity of the processing thread; empty = any
  double statsPeriod_s = 5.0;       // one statistics line per period
  std::string trajectoryCsv;        // absolute; empty = not written
  std::string detectionsCsv;        // absolute; empty = not written
  std::string trafficDir;  // the traffic files' folder (must exist), absolute; empty = not written
  std::string annotatedVideo;  // absolute; empty = not written (MJPG AVI)
  double annotatedVideoFps = 10.0;
  RecordConfig record{};
};

}  // namespace vp::config
