// platform/replay/sequence_replay: a recorded sequence (docs/recorded_sequence.md) played back
// as the app's frame source and telemetry source, in place of the camera and the autopilot.
//
// Contract: SequenceReplay::open() reads the sequence (SequenceReader: every text file is
// checked at start-up) and fails with the reader's message. next() decodes the next frame
// into the caller's pool frame (CV_8UC3 of the rig's camera size, filled in place) with the
// recorded frame id and capture timestamp. Paced, it first waits until the frame is due on
// the given clock: t0 + (t_i - t_first), t0 being the time of the first next(); unpaced it
// returns as fast as frames decode. The wait is the clock's, so the clock's stop condition
// cuts it short: next() then returns Stopped, delivers nothing, and a later call tries the same
// frame again. (The reader refuses a recording whose timestamps jump further than
// sequence::kMaxTimestampGap_ns, so a paced wait is never longer than that.) Looping, the sequence
// starts over after its last frame and timestamps and frame ids keep increasing (each loop adds
// loopPeriod_ns(), the recorded span plus one mean frame interval, and the id span). A missing,
// corrupt or truncated image is a BadFrame status whose message names the file and the frame; the
// next call goes on with the next frame. Nothing throws.
//
// Allocation: decoding an image file (cv::imread inside SequenceReader::loadFrame) allocates
// for every frame. That is accepted here: replay stands in for the camera thread in tests and
// offline runs, and the frame is still copied into the pool's preallocated buffer, so the
// pipeline after it sees the same memory as with a camera.
//
// TelemetryReplay hands out the sequence's telemetry records as they fall due (timestamp <=
// a given time, the frames' clock), shifted by the same loop period when looping; it never
// allocates (records are copied into one member).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "core/frame_pool.hpp"
#include "platform/clock/monotonic_clock.hpp"
#include "sequence/recorded_sequence.hpp"

namespace vp::platform::replay {

struct ReplayOptions {
  bool paced = true;  // wait until each frame is due (recorded timing); false: as fast as possible
  bool loop = false;  // start over after the last frame
};

enum class ReplayStatus : std::uint8_t {
  Frame,     // `out` holds the next frame
  BadFrame,  // this frame's image could not be read (see why); the next call goes on
  End,       // no more frames (never when looping a non-empty sequence)
  Stopped,   // a stop request cut the paced wait short; nothing delivered (see the contract)
  Error,     // the call was wrong (output frame of the wrong size/type); nothing advanced
};
const char* toString(ReplayStatus status);

struct ReplayCounters {
  std::uint64_t frames = 0;
  std::uint64_t badFrames = 0;
  std::uint64_t loops = 0;  // completed passes over the sequence
};

// The shift of one loop: recorded span of the frames plus their mean interval (1 / frame rate
// of sequence.yaml for a one-frame sequence).
std::int64_t loopPeriod_ns(const sequence::SequenceReader& reader);

class SequenceReplay {
 public:
  explicit SequenceReplay(Clock& clock) : clock_(clock) {}

  bool open(const std::string& directory, const ReplayOptions& options, std::string* why);

  ReplayStatus next(Frame& out, std::string* why);

  const sequence::SequenceReader& reader() const { return reader_; }
  int width_px() const { return reader_.rig().intrinsics.width_px; }
  int height_px() const { return reader_.rig().intrinsics.height_px; }
  std::int64_t loopPeriod_ns() const { return loopPeriodNs_; }
  std::size_t position() const { return next_; }  // index of the next frame in frames.csv
  const ReplayCounters& counters() const { return counters_; }

 private:
  Clock& clock_;
  sequence::SequenceReader reader_;
  ReplayOptions options_{};
  std::size_t next_ = 0;
  std::uint64_t loop_ = 0;
  bool started_ = false;
  std::int64_t startNs_ = 0;  // clock time of the first frame
  std::int64_t loopPeriodNs_ = 0;
  std::int64_t idSpan_ = 0;  // added to frame ids per loop
  ReplayCounters counters_{};
};

class TelemetryReplay {
 public:
  // Borrows the records (e.g. SequenceReplay::reader().telemetry()); they must outlive this.
  void open(std::span<const sequence::TelemetryRecord> records, bool loop,
            std::int64_t loopPeriod_ns);

  // The next record with timestamp <= time_ns, or nullptr when none is due yet (or all were
  // given out). The pointer is valid until the next call.
  const sequence::TelemetryRecord* nextDue(std::int64_t time_ns);

  bool finished() const { return !loop_ && next_ >= records_.size(); }
  // Where the record nextDue() returned last comes from: its index in the records (telemetry.csv
  // line index + 2) and the loop pass (0 for the first); valid after a non-null nextDue().
  std::size_t lastIndex() const { return lastIndex_; }
  std::uint64_t lastPass() const { return lastPass_; }

 private:
  std::span<const sequence::TelemetryRecord> records_;
  bool loop_ = false;
  std::int64_t loopPeriodNs_ = 0;
  std::size_t next_ = 0;
  std::uint64_t pass_ = 0;
  bool delivered_ = false;
  std::int64_t lastTimestampNs_ = 0;
  sequence::TelemetryRecord current_{};
  std::size_t lastIndex_ = 0;
  std::uint64_t lastPass_ = 0;
};

}  // namespace vp::platform::replay
