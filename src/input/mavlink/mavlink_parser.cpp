#include "mavlink/mavlink_parser.hpp"

#include <cstring>

namespace vp::mavlink {

void MavlinkParser::reset() {
  state_ = State::Idle;
  length_ = 0;
  expected_ = 0;
}

void MavlinkParser::endOfDatagram() {
  if (state_ != State::Idle) {
    ++counters_.truncated;
    reset();
  }
}

bool MavlinkParser::step(std::uint8_t byte) {
  if (state_ == State::Idle) {
    if (byte != kStxV2) {
      ++counters_.skippedBytes;
      return false;
    }
    buffer_[0] = byte;
    length_ = 1;
    expected_ = 0;
    state_ = State::Collecting;
    return false;
  }
  buffer_[length_++] = byte;
  if (length_ == kHeaderBytes) {
    // A header this parser cannot check is not trusted with a length: its bytes are scanned
    // on as unframed data, so it can never hide the frame after it.
    if ((buffer_[2] & ~kIncompatFlagSigned) != 0) {
      ++counters_.unsupportedFlags;
      rescanAfterStx();
      return false;
    }
    const std::uint32_t id = static_cast<std::uint32_t>(buffer_[7]) |
                             (static_cast<std::uint32_t>(buffer_[8]) << 8) |
                             (static_cast<std::uint32_t>(buffer_[9]) << 16);
    if (findMessageSpec(id) == nullptr) {
      ++counters_.unknownMessage;
      rescanAfterStx();
      return false;
    }
    const std::size_t payloadLength = buffer_[1];
    const bool isSigned = (buffer_[2] & kIncompatFlagSigned) != 0;
    expected_ = kHeaderBytes + payloadLength + kChecksumBytes + (isSigned ? kSignatureBytes : 0);
  }
  if (expected_ != 0 && length_ == expected_) {
    return finishFrame();
  }
  return false;
}

bool MavlinkParser::finishFrame() {
  const std::uint8_t payloadLength = buffer_[1];
  const std::uint8_t incompat = buffer_[2];
  const std::uint32_t id = static_cast<std::uint32_t>(buffer_[7]) |
                           (static_cast<std::uint32_t>(buffer_[8]) << 8) |
                           (static_cast<std::uint32_t>(buffer_[9]) << 16);
  const MessageSpec* spec = findMessageSpec(id);  // known: checked with the header
  if (spec == nullptr) {
    reset();
    return false;
  }
  std::uint16_t crc =
      crcCalculate(std::span<const std::uint8_t>(buffer_ + 1, kHeaderBytes - 1 + payloadLength));
  crc = crcAccumulate(spec->crcExtra, crc);
  const std::size_t crcAt = kHeaderBytes + payloadLength;
  const std::uint16_t sent = static_cast<std::uint16_t>(buffer_[crcAt] | (buffer_[crcAt + 1] << 8));
  if (crc != sent) {
    ++counters_.badCrc;
    rescanAfterStx();
    return false;
  }
  frame_.sequence = buffer_[4];
  frame_.systemId = buffer_[5];
  frame_.componentId = buffer_[6];
  frame_.messageId = id;
  frame_.payloadLength = payloadLength;
  frame_.isSigned = (incompat & kIncompatFlagSigned) != 0;
  std::memcpy(frame_.payload.data(), buffer_ + kHeaderBytes, payloadLength);
  std::memset(frame_.payload.data() + payloadLength, 0, kMaxPayloadBytes - payloadLength);
  ++counters_.frames;
  reset();
  return true;
}

void MavlinkParser::rescanAfterStx() {
  // The failed frame's bytes after its STX go before the bytes still waiting to be scanned
  // again; their total never exceeds one frame (each rescan drops at least the STX).
  const std::size_t again = length_ - 1;
  const std::size_t waiting = replayLength_ - replayPos_;
  std::memmove(replay_ + again, replay_ + replayPos_, waiting);
  std::memcpy(replay_, buffer_ + 1, again);
  replayPos_ = 0;
  replayLength_ = again + waiting;
  reset();
}

}  // namespace vp::mavlink
