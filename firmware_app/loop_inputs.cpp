#include "loop_inputs.hpp"

#include <cstdio>
#include <filesystem>

#include "loop_log.hpp"

namespace vp::app {

// --- frames ----------------------------------------------------------------------------------

bool ReplayFrameSource::open(const std::string& directory, bool paced, bool loop,
                             std::string* why) {
  platform::replay::ReplayOptions options;
  options.paced = paced;
  options.loop = loop;
  if (!replay_.open(directory, options, why)) {
    return false;
  }
  message_.reserve(512);
  return true;
}

SourceStatus ReplayFrameSource::next(Frame& out) {
  using platform::replay::ReplayStatus;
  switch (replay_.next(out, &message_)) {
    case ReplayStatus::Frame:
      return SourceStatus::Frame;
    case ReplayStatus::BadFrame:
      return SourceStatus::BadFrame;
    case ReplayStatus::End:
      return SourceStatus::End;
    case ReplayStatus::Stopped:
      return SourceStatus::Retry;  // the capture loop sees the stop at its next check
    case ReplayStatus::Error:
      break;  // a pool frame of the wrong size: a wiring bug, reported and ended
  }
  return SourceStatus::End;
}

bool VideoFrameSource::open(const config::SourceConfig& config, std::string* why) {
  const config::VideoSourceConfig& v = config.video;
  const auto fail = [why](std::string message) {
    if (why != nullptr) {
      *why = std::move(message);
    }
    return false;
  };
  if (v.path.empty()) {
    return fail("source.video.path: no video to replay");
  }
  if (v.srt.empty() == v.telemetryCsv.empty()) {
    return fail("source.video: give one of srt (the drone's subtitle file) and telemetry_csv");
  }
  platform::replay::ReplayOptions options;
  options.paced = config.paced;
  options.loop = config.loop;
  std::string problem;
  if (!video_.open(v.path, options, &problem)) {
    return fail("source.video.path: " + problem);
  }
  if (!v.srt.empty()) {
    subtitle::SubtitleFile subtitles;
    if (!subtitle::readSubtitleFile(v.srt, subtitles, &problem)) {
      return fail("source.video.srt: " + problem);
    }
    subtitle::SubtitleTelemetry t = subtitle::toTelemetry(subtitles, v.subtitles, v.srt);
    warnings_ = subtitles.problems;
    warnings_.insert(warnings_.end(), t.problems.begin(), t.problems.end());
    if (t.nadirAssumed > 0) {
      warnings_.push_back(v.srt + ": " + std::to_string(t.nadirAssumed) + " of " +
                          std::to_string(t.records.size()) +
                          " telemetry rows have no gimbal angles: the camera is assumed to look "
                          "straight down, yaw along the motion (" +
                          std::to_string(t.yawFromMotion) + " rows) or 0");
    }
    telemetry_ = std::move(t.records);
    telemetryPath_ = v.srt;
  } else {
    if (!sequence::readTelemetryFile(v.telemetryCsv, telemetry_, &problem)) {
      return fail("source.video.telemetry_csv: " + problem);
    }
    telemetryPath_ = v.telemetryCsv;
  }
  message_.reserve(512);
  return true;
}

SourceStatus VideoFrameSource::next(Frame& out) {
  using platform::replay::ReplayStatus;
  switch (video_.next(out, &message_)) {
    case ReplayStatus::Frame:
      return SourceStatus::Frame;
    case ReplayStatus::BadFrame:
      return SourceStatus::BadFrame;
    case ReplayStatus::End:
      return SourceStatus::End;
    case ReplayStatus::Stopped:
      return SourceStatus::Retry;
    case ReplayStatus::Error:
      break;
  }
  return SourceStatus::End;
}

bool CameraFrameSource::open(const config::V4l2SourceConfig& config, std::string* why) {
  platform::v4l2::V4l2CameraConfig camera;
  camera.devicePath = config.busInfo.empty() ? config.device : "";
  camera.busInfo = config.busInfo;
  camera.width_px = config.width_px;
  camera.height_px = config.height_px;
  camera.preferredFormats.clear();
  for (const config::CameraPixelFormat format : config.formats) {
    switch (format) {
      case config::CameraPixelFormat::Yuyv:
        camera.preferredFormats.push_back(platform::v4l2::PixelFormat::Yuyv);
        break;
      case config::CameraPixelFormat::Nv12:
        camera.preferredFormats.push_back(platform::v4l2::PixelFormat::Nv12);
        break;
      case config::CameraPixelFormat::Mjpeg:
        camera.preferredFormats.push_back(platform::v4l2::PixelFormat::Mjpeg);
        break;
    }
  }
  camera.bufferCount = static_cast<unsigned>(config.buffers);
  camera.dequeueTimeout_ms = config.dequeueTimeout_ms;
  return camera_.open(camera, why);
}

SourceStatus CameraFrameSource::next(Frame& out) {
  using platform::v4l2::CaptureStatus;
  const CaptureStatus status = camera_.capture(out);
  switch (status) {
    case CaptureStatus::Frame:
      if (out.status == FrameStatus::Damaged) {
        std::snprintf(message_.data(), message_.size(),
                      "%s: frame %lld flagged damaged by the driver (V4L2_BUF_FLAG_ERROR)",
                      camera_.format().path.c_str(), static_cast<long long>(out.frameId));
        return SourceStatus::BadFrame;
      }
      return SourceStatus::Frame;
    case CaptureStatus::Error:
      std::snprintf(message_.data(), message_.size(), "%s", camera_.lastError());
      return SourceStatus::BadFrame;
    case CaptureStatus::Timeout:
    case CaptureStatus::DeviceLost:
    case CaptureStatus::Reopened:
      std::snprintf(message_.data(), message_.size(), "camera %s: %s",
                    camera_.format().path.c_str(), platform::v4l2::toString(status));
      return SourceStatus::Retry;
  }
  return SourceStatus::Retry;
}

SourceEvents CameraFrameSource::events() const {
  const platform::v4l2::CameraCounters& c = camera_.counters();
  return SourceEvents{c.timeouts, c.deviceLosses, c.reopens};
}

// --- pose ------------------------------------------------------------------------------------

telemetry::PushResult PoseInput::push(const telemetry::PoseSample& sample,
                                      telemetry::PoseBuffer& buffer, const char* where) {
  ++counters_.received;
  if (tap_ != nullptr) {
    tap_->onSample(sample);
  }
  const telemetry::PushResult result = buffer.push(sample);
  if (result == telemetry::PushResult::Accepted) {
    return result;
  }
  ++counters_.bufferRejected;
  bool& logged = logged_[static_cast<std::size_t>(result)];
  if (!logged) {
    logged = true;
    std::array<char, 256> reason{};
    telemetry::formatRejection(reason, buffer.lastRejection());
    logLine(
        "telemetry %s: sample refused (%s): %s; further samples refused for this reason are "
        "only counted",
        where != nullptr ? where : name(), telemetry::toString(result), reason.data());
  }
  return result;
}

namespace {

telemetry::PoseSample toPoseSample(const sequence::TelemetryRecord& record) {
  telemetry::PoseSample sample;
  sample.timestamp_ns = record.timestamp_ns;
  sample.position = record.position;
  sample.bodyToNed = record.bodyToNed;
  sample.gimbal = record.gimbal;
  return sample;
}

}  // namespace

void RecordingPoseInput::open(const platform::replay::SequenceReplay& replay, bool loop,
                              double lookahead_s, const telemetry::PoseLimits& limits) {
  open(replay.reader().telemetry(),
       (std::filesystem::path(replay.reader().directory()) / "telemetry.csv").string(), loop,
       replay.loopPeriod_ns(), lookahead_s, limits);
}

void RecordingPoseInput::open(std::span<const sequence::TelemetryRecord> records,
                              const std::string& path, bool loop, std::int64_t loopPeriod_ns,
                              double lookahead_s, const telemetry::PoseLimits& limits) {
  telemetry_.open(records, loop, loopPeriod_ns);
  lookaheadNs_ = static_cast<std::int64_t>(lookahead_s * 1e9);
  path_ = path;
  pass_ = 0;
  // The rows the buffer will refuse, found now with the same checks in the same order (the
  // newest accepted row is the one each row is judged against), so that a bad recording is
  // reported at start-up with its lines, not only by the counters at the end.
  warnings_.clear();
  rowsRefused_ = 0;
  telemetry::PoseSample previous;
  bool havePrevious = false;
  for (std::size_t i = 0; i < records.size(); ++i) {
    const telemetry::PoseSample sample = toPoseSample(records[i]);
    telemetry::PoseCheck check = telemetry::checkSample(sample, limits);
    if (check.ok() && havePrevious) {
      check = telemetry::checkStep(previous, sample, limits);
    }
    if (check.ok()) {
      previous = sample;
      previous.bodyToNed.normalize();
      havePrevious = true;
      continue;
    }
    ++rowsRefused_;
    if (warnings_.size() < kMaxWarnings) {
      std::array<char, 256> reason{};
      telemetry::formatRejection(reason, check);
      warnings_.push_back(path_ + ":" + std::to_string(i + 2) + ": " + reason.data() +
                          ": sample refused (" + telemetry::toString(check.result) + ")");
    }
  }
  if (rowsRefused_ > warnings_.size()) {
    warnings_.push_back(path_ + ": " + std::to_string(rowsRefused_ - warnings_.size()) +
                        " more rows refused");
  }
}

void RecordingPoseInput::poll(std::int64_t frameTime_ns, telemetry::PoseBuffer& buffer) {
  // Interpolating to the frame time needs the sample after it: the recording is pushed ahead.
  while (const sequence::TelemetryRecord* record =
             telemetry_.nextDue(frameTime_ns + lookaheadNs_)) {
    if (telemetry_.lastPass() != pass_) {
      // Looping: the recording starts over where it began, a jump that is no fault of it.
      pass_ = telemetry_.lastPass();
      buffer.markDiscontinuity();
    }
    std::snprintf(where_.data(), where_.size(), "%s:%zu", path_.c_str(),
                  telemetry_.lastIndex() + 2);  // line 1 is the header
    push(toPoseSample(*record), buffer, where_.data());
  }
}

bool MavlinkPoseInput::open(const config::TelemetryLinkConfig& config, std::string* why) {
  mavlink::PoseAssemblerConfig assembler;
  assembler.geoidSeparation_m = config.geoidSeparation_m;
  assembler.linkLatency_ns = static_cast<std::int64_t>(config.linkLatency_s * 1e9);
  assembler.systemId = static_cast<std::uint8_t>(config.systemId);
  assembler_ = std::make_unique<mavlink::MavlinkPoseAssembler>(assembler);
  if (config.source == config::TelemetrySourceKind::MavlinkSerial) {
    return serial_.open(config.serialDevice, config.serialBaud, why);
  }
  return udp_.open(config.udpBindAddress, static_cast<std::uint16_t>(config.udpPort), why);
}

void MavlinkPoseInput::poll(std::int64_t /*frameTime_ns*/, telemetry::PoseBuffer& buffer) {
  const std::int64_t receive_ns = clock_.now_ns();
  const std::uint64_t rejectedBefore = assembler_->counters().rejected;
  const auto onFrame = [&](const mavlink::MavlinkFrame& frame) {
    const std::optional<mavlink::Message> message = mavlink::decode(frame);
    if (!message || !assembler_->add(*message, frame.systemId, receive_ns)) {
      return;
    }
    const mavlink::PoseSample& in = assembler_->sample();
    telemetry::PoseSample sample;
    sample.timestamp_ns = in.timestamp_ns;
    sample.position = in.position;
    sample.bodyToNed = in.bodyToNed;
    sample.gimbal = in.hasGimbal ? in.gimbal : defaultGimbal_;
    push(sample, buffer);
  };
  const std::span<std::uint8_t> scratch(scratch_);
  const long result = serial_.isOpen()
                          ? platform::mavlink::drainSerial(serial_, parser_, scratch, onFrame)
                          : platform::mavlink::drainUdp(udp_, parser_, scratch, onFrame);
  if (result < 0) {
    ++counters_.readErrors;
  }
  counters_.linkRejected += assembler_->counters().rejected - rejectedBefore;
}

}  // namespace vp::app
