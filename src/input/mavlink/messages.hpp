// mavlink/messages: the MAVLink 2 messages the app reads (drone attitude, position, gimbal
// attitude), decoded from and encoded to frames, and the CRC the frames carry.
//
// Contract: pure functions, no I/O, no allocation, no exceptions. decode() turns a valid
// frame (see mavlink_parser.hpp) of one of the four messages into its struct; the payload is
// read little-endian at the offsets of common.xml (fields ordered by size, extensions last),
// with the v2 rule that missing trailing bytes are zero. encode() writes a complete MAVLink 2
// frame (STX 0xFD, header, payload with trailing zeros truncated, CRC-16/MCRF4XX including
// the message's CRC_EXTRA, unsigned) for tests and simulators. Field units are MAVLink's,
// kept as sent (degE7, mm, rad); the pose assembler converts them.
//
// Message layouts and CRC_EXTRA values: MAVLink common.xml (https://mavlink.io/en/messages/
// common.html); the frame format and checksum: https://mavlink.io/en/guide/serialization.html.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <variant>

namespace vp::mavlink {

constexpr std::uint8_t kStxV2 = 0xFD;
constexpr std::size_t kHeaderBytes = 10;  // STX, len, incompat, compat, seq, sys, comp, msgid x3
constexpr std::size_t kChecksumBytes = 2;
constexpr std::size_t kSignatureBytes = 13;
constexpr std::size_t kMaxPayloadBytes = 255;
constexpr std::size_t kMaxFrameBytes =
    kHeaderBytes + kMaxPayloadBytes + kChecksumBytes + kSignatureBytes;  // 280
constexpr std::uint8_t kIncompatFlagSigned = 0x01;  // the only incompat flag MAVLink 2 defines

// CRC-16/MCRF4XX (MAVLink's "X.25" checksum): polynomial 0x1021 reflected, init 0xFFFF.
constexpr std::uint16_t kCrcInit = 0xFFFF;
constexpr std::uint16_t crcAccumulate(std::uint8_t byte, std::uint16_t crc) {
  std::uint8_t tmp = static_cast<std::uint8_t>(byte ^ static_cast<std::uint8_t>(crc & 0xFF));
  tmp = static_cast<std::uint8_t>(tmp ^ static_cast<std::uint8_t>(tmp << 4));
  return static_cast<std::uint16_t>((crc >> 8) ^ (tmp << 8) ^ (tmp << 3) ^ (tmp >> 4));
}
constexpr std::uint16_t crcCalculate(std::span<const std::uint8_t> bytes,
                                     std::uint16_t crc = kCrcInit) {
  for (const std::uint8_t byte : bytes) {
    crc = crcAccumulate(byte, crc);
  }
  return crc;
}

// What the parser must know of a message to check its frame.
struct MessageSpec {
  std::uint32_t id = 0;
  std::uint8_t crcExtra = 0;   // seed of the message's field layout, added to the CRC
  std::uint8_t maxLength = 0;  // payload bytes with every extension field
  const char* name = "";
};
// The messages this library checks (the four below); nullptr for any other id.
const MessageSpec* findMessageSpec(std::uint32_t messageId);

enum : std::uint32_t {
  kMsgIdAttitude = 30,
  kMsgIdAttitudeQuaternion = 31,
  kMsgIdGlobalPositionInt = 33,
  kMsgIdGimbalDeviceAttitudeStatus = 285,
};

// GIMBAL_DEVICE_FLAGS bits that say which frame the gimbal attitude is in.
constexpr std::uint16_t kGimbalFlagYawLock = 16;
constexpr std::uint16_t kGimbalFlagYawInVehicleFrame = 32;
constexpr std::uint16_t kGimbalFlagYawInEarthFrame = 64;

// #30: Euler angles of the body (FRD) in local NED, aerospace ZYX.
struct Attitude {
  std::uint32_t timeBoot_ms = 0;
  float roll_rad = 0, pitch_rad = 0, yaw_rad = 0;
  float rollSpeed_radps = 0, pitchSpeed_radps = 0, yawSpeed_radps = 0;
};

// #31: q = (w, x, y, z) rotating body FRD vectors into NED (q_nb of docs/conventions.md).
struct AttitudeQuaternion {
  std::uint32_t timeBoot_ms = 0;
  std::array<float, 4> q{1, 0, 0, 0};
  float rollSpeed_radps = 0, pitchSpeed_radps = 0, yawSpeed_radps = 0;
  std::array<float, 4> reprOffsetQ{0, 0, 0, 0};  // extension; all zero when not sent
};

// #33: fused global position. Altitude is above mean sea level, not ellipsoidal.
struct GlobalPositionInt {
  std::uint32_t timeBoot_ms = 0;
  std::int32_t latitude_degE7 = 0, longitude_degE7 = 0;
  std::int32_t altitudeMsl_mm = 0, relativeAltitude_mm = 0;
  std::int16_t vx_cmps = 0, vy_cmps = 0, vz_cmps = 0;  // NED ground speed
  std::uint16_t heading_cdeg = 0;                      // 0..35999, UINT16_MAX when unknown
};

// #285: the gimbal head's attitude; its frame depends on `flags` (see the pose assembler).
struct GimbalDeviceAttitudeStatus {
  std::uint32_t timeBoot_ms = 0;  // the gimbal device's own boot clock
  std::array<float, 4> q{1, 0, 0, 0};
  float angularVelocityXRadps = 0, angularVelocityYRadps = 0, angularVelocityZRadps = 0;
  std::uint32_t failureFlags = 0;
  std::uint16_t flags = 0;
  std::uint8_t targetSystem = 0, targetComponent = 0;
  float deltaYaw_rad = 0;  // extension: NaN or absent (0) when unknown
  float deltaYawVelocity_radps = 0;
  std::uint8_t gimbalDeviceId = 0;
  bool hasExtensions = false;  // the sender's payload reached the extension fields
};

using Message =
    std::variant<Attitude, AttitudeQuaternion, GlobalPositionInt, GimbalDeviceAttitudeStatus>;
std::uint32_t messageId(const Message& message);

// A checked frame as the parser delivers it.
struct MavlinkFrame {
  std::uint8_t sequence = 0;
  std::uint8_t systemId = 0;
  std::uint8_t componentId = 0;
  std::uint32_t messageId = 0;
  std::uint8_t payloadLength = 0;  // as received, after the sender's zero truncation
  bool isSigned = false;           // carried a signature (skipped, not verified)
  std::array<std::uint8_t, kMaxPayloadBytes> payload{};  // zero beyond payloadLength
};

// One of the four messages, or nothing for any other message id.
std::optional<Message> decode(const MavlinkFrame& frame);

struct FrameHeader {
  std::uint8_t sequence = 0;
  std::uint8_t systemId = 1;
  std::uint8_t componentId = 1;  // MAV_COMP_ID_AUTOPILOT1; a gimbal device is 154
};

// Writes one frame into `out`; returns its length, or 0 when `out` is too small.
std::size_t encode(const Message& message, const FrameHeader& header, std::span<std::uint8_t> out);

}  // namespace vp::mavlink
