#include "platform/replay/sequence_replay.hpp"

#include <cmath>

namespace vp::platform::replay {

const char* toString(ReplayStatus status) {
  switch (status) {
    case ReplayStatus::Frame:
      return "frame";
    case ReplayStatus::BadFrame:
      return "bad frame";
    case ReplayStatus::End:
      return "end";
    case ReplayStatus::Stopped:
      return "stopped";
    case ReplayStatus::Error:
      return "error";
  }
  return "?";
}

std::int64_t loopPeriod_ns(const sequence::SequenceReader& reader) {
  const auto& frames = reader.frames();
  const double rate_hz = reader.info().frameRate_hz > 0 ? reader.info().frameRate_hz : 10.0;
  if (frames.size() < 2) {
    return static_cast<std::int64_t>(std::llround(1e9 / rate_hz));
  }
  const std::int64_t span = frames.back().timestamp_ns - frames.front().timestamp_ns;
  return span + span / static_cast<std::int64_t>(frames.size() - 1);
}

bool SequenceReplay::open(const std::string& directory, const ReplayOptions& options,
                          std::string* why) {
  if (!reader_.open(directory, why)) {
    return false;
  }
  options_ = options;
  next_ = 0;
  loop_ = 0;
  started_ = false;
  counters_ = ReplayCounters{};
  loopPeriodNs_ = replay::loopPeriod_ns(reader_);
  const auto& frames = reader_.frames();
  idSpan_ = frames.empty() ? 0 : frames.back().frameId - frames.front().frameId + 1;
  return true;
}

ReplayStatus SequenceReplay::next(Frame& out, std::string* why) {
  const auto& frames = reader_.frames();
  if (out.image.type() != CV_8UC3 || out.image.cols != width_px() ||
      out.image.rows != height_px()) {
    if (why != nullptr) {
      *why = reader_.directory() + ": output frame is " + std::to_string(out.image.cols) + "x" +
             std::to_string(out.image.rows) + " type " + std::to_string(out.image.type()) +
             ", the sequence's camera gives " + std::to_string(width_px()) + "x" +
             std::to_string(height_px()) + " BGR8";
    }
    return ReplayStatus::Error;
  }
  if (next_ >= frames.size()) {
    if (!options_.loop || frames.empty()) {
      return ReplayStatus::End;
    }
    next_ = 0;
    ++loop_;
    ++counters_.loops;
  }
  const std::size_t index = next_++;
  const sequence::FrameRecord& record = frames[index];
  const std::int64_t shift_ns = static_cast<std::int64_t>(loop_) * loopPeriodNs_;
  const std::int64_t timestamp_ns = record.timestamp_ns + shift_ns;
  if (!started_) {
    started_ = true;
    startNs_ = clock_.now_ns();
  }

  // loadFrame copies into out.image in place: its size and type match the rig (checked above).
  const uchar* before = out.image.data;
  std::string problem;
  if (!reader_.loadFrame(index, out.image, &problem) || out.image.data != before) {
    ++counters_.badFrames;
    if (why != nullptr) {
      // The recorded id and line, which is what finds the file again; the loop when looping.
      *why = problem + " (frame " + std::to_string(record.frameId) + ", frames.csv line " +
             std::to_string(index + 2) +
             (loop_ > 0 ? ", loop " + std::to_string(loop_) : std::string()) + ")";
    }
    return ReplayStatus::BadFrame;
  }
  if (options_.paced &&
      !clock_.sleepUntil_ns(startNs_ + (timestamp_ns - frames.front().timestamp_ns))) {
    next_ = index;  // not delivered: the next call tries this frame again
    return ReplayStatus::Stopped;
  }
  out.timestamp_ns = timestamp_ns;
  out.frameId = record.frameId + static_cast<std::int64_t>(loop_) * idSpan_;
  out.status = FrameStatus::Ok;
  ++counters_.frames;
  return ReplayStatus::Frame;
}

void TelemetryReplay::open(std::span<const sequence::TelemetryRecord> records, bool loop,
                           std::int64_t loopPeriod_ns) {
  records_ = records;
  loop_ = loop && !records.empty() && loopPeriod_ns > 0;
  loopPeriodNs_ = loopPeriod_ns;
  next_ = 0;
  pass_ = 0;
  delivered_ = false;
  lastTimestampNs_ = 0;
}

const sequence::TelemetryRecord* TelemetryReplay::nextDue(std::int64_t time_ns) {
  for (;;) {
    if (next_ >= records_.size()) {
      if (!loop_) {
        return nullptr;
      }
      next_ = 0;
      ++pass_;
    }
    const std::int64_t timestamp_ns =
        records_[next_].timestamp_ns + static_cast<std::int64_t>(pass_) * loopPeriodNs_;
    // Telemetry reaching past the last frame overlaps the next loop's start: keep the stream
    // non-decreasing by skipping what would go back in time.
    if (delivered_ && timestamp_ns < lastTimestampNs_) {
      ++next_;
      continue;
    }
    if (timestamp_ns > time_ns) {
      return nullptr;
    }
    lastIndex_ = next_;
    lastPass_ = pass_;
    current_ = records_[next_++];
    current_.timestamp_ns = timestamp_ns;
    delivered_ = true;
    lastTimestampNs_ = timestamp_ns;
    return &current_;
  }
}

}  // namespace vp::platform::replay
