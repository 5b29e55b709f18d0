// fuzz/mavlink_stream: the MAVLink 2 parser, the message decoder and the pose assembler
// (src/input/mavlink) on an arbitrary byte stream. Byte 0 chooses the transport: 0 a serial
// stream (one parse of everything), otherwise datagrams of (byte 0) bytes each, ended with
// endOfDatagram(). The rest of the input is the link's bytes; the receive time advances 10 ms
// per frame.
// Contract checked: no crash, no allocation beyond the parser's fixed storage (ASan), the
// parser's frame counter equals the frames delivered, and every
// decoded message survives encode -> parse -> decode -> encode with identical bytes; pose
// samples carry a unit quaternion and finite positions.
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <span>
#include <string>

#include "fuzz_support.hpp"
#include "mavlink/mavlink_parser.hpp"
#include "mavlink/messages.hpp"
#include "mavlink/pose_assembler.hpp"

namespace {

constexpr const char* kTarget = "mavlink_stream";

// Encodes `message`, parses the bytes with a fresh parser and encodes what comes back: both
// encodings must be identical (the decoder and encoder are exact inverses on their own output).
void checkRoundTrip(const vp::mavlink::Message& message, const vp::mavlink::MavlinkFrame& frame) {
  const vp::mavlink::FrameHeader header{frame.sequence, frame.systemId, frame.componentId};
  std::array<std::uint8_t, vp::mavlink::kMaxFrameBytes> first{};
  const std::size_t firstLength = vp::mavlink::encode(message, header, first);
  vp::fuzz::expect(firstLength > 0, kTarget, "encode() of a decoded message failed");
  vp::mavlink::MavlinkParser parser;
  int frames = 0;
  std::optional<vp::mavlink::Message> again;
  parser.parse(std::span<const std::uint8_t>(first.data(), firstLength),
               [&](const vp::mavlink::MavlinkFrame& parsed) {
                 ++frames;
                 again = vp::mavlink::decode(parsed);
               });
  vp::fuzz::expect(frames == 1 && again.has_value(), kTarget,
                   "an encoded message does not parse back to one frame");
  std::array<std::uint8_t, vp::mavlink::kMaxFrameBytes> second{};
  const std::size_t secondLength = vp::mavlink::encode(*again, header, second);
  vp::fuzz::expect(
      secondLength == firstLength && std::memcmp(first.data(), second.data(), firstLength) == 0,
      kTarget, "encode(decode(encode(m))) differs from encode(m)");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) {
    return 0;
  }
  const std::size_t datagram = data[0];
  const std::span<const std::uint8_t> stream(data + 1, size - 1);

  vp::mavlink::MavlinkParser parser;
  vp::mavlink::MavlinkPoseAssembler assembler;
  std::uint64_t delivered = 0;
  std::int64_t now_ns = 1'000'000'000;
  const auto onFrame = [&](const vp::mavlink::MavlinkFrame& frame) {
    ++delivered;
    now_ns += 10'000'000;
    vp::fuzz::expect(frame.payloadLength <= vp::mavlink::kMaxPayloadBytes, kTarget,
                     "payload length beyond the maximum");
    const std::optional<vp::mavlink::Message> message = vp::mavlink::decode(frame);
    if (!message) {
      return;
    }
    vp::fuzz::expect(vp::mavlink::messageId(*message) == frame.messageId, kTarget,
                     "decoded message of another id");
    checkRoundTrip(*message, frame);
    if (assembler.add(*message, frame.systemId, now_ns)) {
      const vp::mavlink::PoseSample& sample = assembler.sample();
      vp::fuzz::expect(std::abs(sample.bodyToNed.norm() - 1.0) < 1e-6, kTarget,
                       "pose sample with a non-unit quaternion");
      vp::fuzz::expect(std::isfinite(sample.position.latitude_deg) &&
                           std::isfinite(sample.position.longitude_deg) &&
                           std::isfinite(sample.position.height_m),
                       kTarget, "pose sample with a non-finite position");
    }
  };
  if (datagram == 0) {
    parser.parse(stream, onFrame);
  } else {
    for (std::size_t at = 0; at < stream.size(); at += datagram) {
      parser.parse(stream.subspan(at, std::min(datagram, stream.size() - at)), onFrame);
      parser.endOfDatagram();
    }
  }
  vp::fuzz::note(kTarget, std::to_string(delivered) + " frames, " +
                              std::to_string(parser.counters().badCrc) + " bad CRC");
  vp::fuzz::expect(parser.counters().frames == delivered, kTarget,
                   "frames counter differs from the frames delivered");
  return 0;
}
