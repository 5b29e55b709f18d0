// firmware_app/loop_inputs: the two inputs of the loop behind small interfaces: where frames
// come from (capture thread) and where the drone's pose comes from (processing thread).
//
// Contract: a FrameSource fills the caller's pool frame in place and reports what happened as
// a value (never throws): a frame, a bad frame (corrupt, truncated, flagged by the driver), a
// retry (timeout, camera lost, camera back) or the end of the source. It runs on the capture
// thread, where allocation is accepted (replay decodes image files; see frame_sources.md).
// A PoseInput moves the samples that have arrived into the loop's PoseBuffer without
// blocking; it runs on the processing thread before each frame and allocates nothing after
// open(). Samples a link refuses (NaN, bad quaternion) and samples the buffer refuses (its
// range and consistency checks, telemetry/pose_check.hpp) are counted, never used; the first
// refusal of each kind is logged with where the sample came from (a recording: its
// telemetry.csv line) and what was wrong, later ones only counted. A recording's telemetry is
// also checked as a whole at open(): each row the buffer will refuse is a start-up warning
// naming the file and line (the recording still plays; those samples are refused). A
// PoseSampleTap set on a PoseInput sees every sample the link delivered, as delivered, before
// the buffer judges it (the recorder writes them). Both are wired
// by the app from the configuration; tests substitute their own (the seams of app.hpp).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "config/config.hpp"
#include "core/frame_pool.hpp"
#include "mavlink/mavlink_parser.hpp"
#include "mavlink/pose_assembler.hpp"
#include "platform/clock/monotonic_clock.hpp"
#include "platform/mavlink/mavlink_link.hpp"
#include "platform/replay/sequence_replay.hpp"
#include "platform/replay/video_replay.hpp"
#include "platform/v4l2/v4l2_camera.hpp"
#include "telemetry/pose_buffer.hpp"

namespace vp::app {

enum class SourceStatus : std::uint8_t {
  Frame,     // the frame was filled
  BadFrame,  // this frame is unusable (message() says why); the next call goes on
  Retry,     // nothing this time (timeout, device lost or back); call again
  End,       // no more frames
};

struct SourceEvents {
  std::uint64_t timeouts = 0;
  std::uint64_t deviceLosses = 0;
  std::uint64_t reopens = 0;
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual SourceStatus next(Frame& out) = 0;
  virtual const char* message() const = 0;  // the last bad frame or event, with context
  virtual SourceEvents events() const { return {}; }
  virtual bool capturesOnMonotonicClock() const = 0;  // frame stamps are CLOCK_MONOTONIC
  virtual double nominalFrameRate_hz() const = 0;
  virtual int width_px() const = 0;  // the size of every frame it delivers (after open())
  virtual int height_px() const = 0;
};

class ReplayFrameSource final : public FrameSource {
 public:
  explicit ReplayFrameSource(platform::Clock& clock) : replay_(clock) {}
  bool open(const std::string& directory, bool paced, bool loop, std::string* why);
  SourceStatus next(Frame& out) override;
  const char* message() const override { return message_.c_str(); }
  bool capturesOnMonotonicClock() const override { return false; }
  double nominalFrameRate_hz() const override { return replay_.reader().info().frameRate_hz; }
  int width_px() const override { return replay_.width_px(); }
  int height_px() const override { return replay_.height_px(); }
  const platform::replay::SequenceReplay& replay() const { return replay_; }

 private:
  platform::replay::SequenceReplay replay_;
  std::string message_;
};

// A drone video replayed directly (source.kind video) and its telemetry on the video's clock,
// read at open() from the subtitles (source.video.srt) or a telemetry.csv.
class VideoFrameSource final : public FrameSource {
 public:
  explicit VideoFrameSource(platform::Clock& clock) : video_(clock) {}
  bool open(const config::SourceConfig& config, std::string* why);
  SourceStatus next(Frame& out) override;
  const char* message() const override { return message_.c_str(); }
  bool capturesOnMonotonicClock() const override { return false; }
  double nominalFrameRate_hz() const override { return video_.frameRate_hz(); }
  int width_px() const override { return video_.width_px(); }
  int height_px() const override { return video_.height_px(); }
  const platform::replay::VideoReplay& video() const { return video_; }
  std::span<const sequence::TelemetryRecord> telemetry() const { return telemetry_; }
  const std::string& telemetryPath() const { return telemetryPath_; }
  // Subtitles skipped and the nadir assumption, for the start-up log.
  const std::vector<std::string>& warnings() const { return warnings_; }

 private:
  platform::replay::VideoReplay video_;
  std::vector<sequence::TelemetryRecord> telemetry_;
  std::string telemetryPath_;
  std::vector<std::string> warnings_;
  std::string message_;
};

class CameraFrameSource final : public FrameSource {
 public:
  CameraFrameSource(platform::v4l2::V4l2Device& device, platform::Clock& clock)
      : camera_(device, clock) {}
  bool open(const config::V4l2SourceConfig& config, std::string* why);
  SourceStatus next(Frame& out) override;
  const char* message() const override { return message_.data(); }
  SourceEvents events() const override;
  bool capturesOnMonotonicClock() const override { return true; }
  double nominalFrameRate_hz() const override { return 10.0; }  // seed 000's camera
  int width_px() const override { return camera_.format().width_px; }
  int height_px() const override { return camera_.format().height_px; }
  const platform::v4l2::V4l2Camera& camera() const { return camera_; }

 private:
  platform::v4l2::V4l2Camera camera_;
  std::array<char, 320> message_{};
};

struct PoseInputCounters {
  std::uint64_t received = 0;        // samples the link delivered
  std::uint64_t linkRejected = 0;    // refused by the link's own checks (NaN, quaternion, ...)
  std::uint64_t bufferRejected = 0;  // refused by the PoseBuffer (see its counters)
  std::uint64_t readErrors = 0;      // failed reads of the link
};

// Sees each pose sample as the link delivered it (processing thread; must not allocate).
class PoseSampleTap {
 public:
  virtual ~PoseSampleTap() = default;
  virtual void onSample(const telemetry::PoseSample& sample) = 0;
};

class PoseInput {
 public:
  virtual ~PoseInput() = default;
  // Moves what has arrived (a recording: the samples due up to frameTime_ns + lookahead) into
  // buffer. Non-blocking, no allocation.
  virtual void poll(std::int64_t frameTime_ns, telemetry::PoseBuffer& buffer) = 0;
  virtual const char* name() const = 0;
  const PoseInputCounters& counters() const { return counters_; }
  void setTap(PoseSampleTap* tap) { tap_ = tap; }  // borrowed; nullptr: none

 protected:
  // Pushes one sample into the buffer; `where` names its origin in the first log line of each
  // kind of refusal (nullptr: the input's name()).
  telemetry::PushResult push(const telemetry::PoseSample& sample, telemetry::PoseBuffer& buffer,
                             const char* where = nullptr);
  PoseInputCounters counters_{};

 private:
  PoseSampleTap* tap_ = nullptr;
  std::array<bool, static_cast<std::size_t>(telemetry::PushResult::NotInitialised) + 1> logged_{};
};

// The recorded telemetry.csv of the sequence being replayed (or a replayed video's telemetry).
class RecordingPoseInput final : public PoseInput {
 public:
  // limits: the pose buffer's, to find at start-up the rows it will refuse (warnings()).
  void open(const platform::replay::SequenceReplay& replay, bool loop, double lookahead_s,
            const telemetry::PoseLimits& limits);
  // The same for telemetry records that outlive this (a directly replayed video's); path names
  // them in the messages.
  void open(std::span<const sequence::TelemetryRecord> records, const std::string& path, bool loop,
            std::int64_t loopPeriod_ns, double lookahead_s, const telemetry::PoseLimits& limits);
  void poll(std::int64_t frameTime_ns, telemetry::PoseBuffer& buffer) override;
  const char* name() const override { return "recording"; }
  // "<dir>/telemetry.csv:17: gimbal_pitch_deg 999 outside [-120, 30]: sample refused", at
  // most kMaxWarnings of them, then one line with the count of the rest.
  const std::vector<std::string>& warnings() const { return warnings_; }
  std::size_t rowsRefusedAtOpen() const { return rowsRefused_; }
  static constexpr std::size_t kMaxWarnings = 10;

 private:
  platform::replay::TelemetryReplay telemetry_;
  std::int64_t lookaheadNs_ = 0;
  std::string path_;  // <dir>/telemetry.csv
  std::array<char, 512> where_{};
  std::uint64_t pass_ = 0;
  std::vector<std::string> warnings_;
  std::size_t rowsRefused_ = 0;
};

// MAVLink 2 over UDP or a serial port, through the pose assembler (docs/telemetry.md).
class MavlinkPoseInput final : public PoseInput {
 public:
  MavlinkPoseInput(platform::Clock& clock, const geodesy::GimbalState& defaultGimbal)
      : clock_(clock), defaultGimbal_(defaultGimbal) {}
  bool open(const config::TelemetryLinkConfig& config, std::string* why);
  void poll(std::int64_t frameTime_ns, telemetry::PoseBuffer& buffer) override;
  const char* name() const override { return serial_.isOpen() ? "mavlink serial" : "mavlink udp"; }
  const mavlink::MavlinkPoseAssembler& assembler() const { return *assembler_; }

 private:
  platform::Clock& clock_;
  geodesy::GimbalState defaultGimbal_;
  platform::mavlink::UdpSocket udp_;
  platform::mavlink::SerialPort serial_;
  mavlink::MavlinkParser parser_;
  std::unique_ptr<mavlink::MavlinkPoseAssembler> assembler_;
  std::array<std::uint8_t, platform::mavlink::kLinkScratchBytes> scratch_{};
};

// No telemetry: every frame has NoPose (detections are kept image-only).
class NoPoseInput final : public PoseInput {
 public:
  void poll(std::int64_t, telemetry::PoseBuffer&) override {}
  const char* name() const override { return "none"; }
};

}  // namespace vp::app
