// mavlink/mavlink_parser: MAVLink 2 frames out of a byte stream (serial) or datagrams (UDP).
//
// Contract: a byte-at-a-time state machine with fixed storage; push() and parse() never
// allocate, never throw and hand every valid frame to the caller's callback as a
// `const MavlinkFrame&` (valid during the call). A frame starts with STX 0xFD; its header
// gives the payload length (the sender may have truncated trailing zero bytes: the payload
// reads as zero beyond it), the incompat flags (0x01: a 13-byte signature follows the
// checksum; it is skipped, not verified) and the 24-bit message id. The checksum is
// CRC-16/MCRF4XX over the bytes after STX, seeded with the message's CRC_EXTRA.
//
// Errors are counted, never fatal:
//  - badCrc: the checksum does not match. The bytes after that STX are scanned again, so a
//    frame cut short on a serial line loses only itself, not the good frame it swallowed.
//  - unknownMessage: a header with a message id this library has no CRC_EXTRA for (it
//    cannot be checked). Autopilots send many such messages; this counts what was ignored
//    rather than a fault (a 0xFD inside such a payload may be counted once more).
//  - unsupportedFlags: incompat flags other than "signed"; the spec says drop the frame.
//    Neither kind of header is trusted with a length: the bytes after its STX are scanned on
//    as unframed data (counted in skippedBytes), so a damaged header or a message of another
//    dialect never hides the frame after it.
//  - truncated: a datagram ended inside a frame (endOfDatagram()).
//  - skippedBytes: bytes outside any frame (line noise, MAVLink 1 traffic).
// Serial streams have no datagram boundaries: a frame cut short there shows up as badCrc.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "mavlink/messages.hpp"

namespace vp::mavlink {

struct ParserCounters {
  std::uint64_t frames = 0;  // valid frames delivered
  std::uint64_t badCrc = 0;
  std::uint64_t unknownMessage = 0;
  std::uint64_t unsupportedFlags = 0;
  std::uint64_t truncated = 0;
  std::uint64_t skippedBytes = 0;
};

class MavlinkParser {
 public:
  MavlinkParser() = default;

  // Feeds one byte; calls onFrame(const MavlinkFrame&) for each frame it completes (usually
  // zero or one; more when a failed frame is scanned again).
  template <class OnFrame>
  void push(std::uint8_t byte, OnFrame&& onFrame) {
    if (step(byte)) {
      onFrame(static_cast<const MavlinkFrame&>(frame_));
    }
    while (replayPos_ < replayLength_) {
      if (step(replay_[replayPos_++])) {
        onFrame(static_cast<const MavlinkFrame&>(frame_));
      }
    }
    replayPos_ = 0;
    replayLength_ = 0;
  }

  template <class OnFrame>
  void parse(std::span<const std::uint8_t> bytes, OnFrame&& onFrame) {
    for (const std::uint8_t byte : bytes) {
      push(byte, onFrame);
    }
  }

  // A datagram ended: a frame still incomplete is counted as truncated and dropped.
  void endOfDatagram();
  // Forgets a partial frame (e.g. after the link was reopened), counters stay.
  void reset();

  const ParserCounters& counters() const { return counters_; }

 private:
  // Consumes one byte; true when frame_ now holds a valid frame.
  bool step(std::uint8_t byte);
  bool finishFrame();
  void rescanAfterStx();

  enum class State { Idle, Collecting };
  State state_ = State::Idle;
  std::size_t length_ = 0;    // bytes of the current frame in buffer_
  std::size_t expected_ = 0;  // its total length once the header is complete (0 before)
  std::uint8_t buffer_[kMaxFrameBytes] = {};
  // Bytes to scan again after a bad frame, consumed before the next input byte.
  std::uint8_t replay_[kMaxFrameBytes] = {};
  std::size_t replayPos_ = 0;
  std::size_t replayLength_ = 0;
  MavlinkFrame frame_{};
  ParserCounters counters_{};
};

}  // namespace vp::mavlink
