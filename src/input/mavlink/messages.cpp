#include "mavlink/messages.hpp"

#include <bit>
#include <cstring>
#include <type_traits>

namespace vp::mavlink {
namespace {

// Full payload length (with extensions) and CRC_EXTRA of each message, from common.xml.
constexpr std::array<MessageSpec, 4> kSpecs{{
    {kMsgIdAttitude, 39, 28, "ATTITUDE"},
    {kMsgIdAttitudeQuaternion, 246, 48, "ATTITUDE_QUATERNION"},
    {kMsgIdGlobalPositionInt, 104, 28, "GLOBAL_POSITION_INT"},
    {kMsgIdGimbalDeviceAttitudeStatus, 137, 49, "GIMBAL_DEVICE_ATTITUDE_STATUS"},
}};

using Payload = std::array<std::uint8_t, kMaxPayloadBytes>;

// Little-endian field access at a byte offset, independent of the host's byte order.
template <class T>
T get(const Payload& payload, std::size_t offset) {
  using U = std::conditional_t<sizeof(T) == 4, std::uint32_t,
                               std::conditional_t<sizeof(T) == 2, std::uint16_t, std::uint8_t>>;
  U raw = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i) {
    raw = static_cast<U>(raw | static_cast<U>(static_cast<U>(payload[offset + i]) << (8 * i)));
  }
  return std::bit_cast<T>(raw);
}

template <class T>
void put(Payload& payload, std::size_t offset, T value) {
  using U = std::conditional_t<sizeof(T) == 4, std::uint32_t,
                               std::conditional_t<sizeof(T) == 2, std::uint16_t, std::uint8_t>>;
  const U raw = std::bit_cast<U>(value);
  for (std::size_t i = 0; i < sizeof(T); ++i) {
    payload[offset + i] = static_cast<std::uint8_t>(raw >> (8 * i));
  }
}

Attitude decodeAttitude(const Payload& p) {
  Attitude m;
  m.timeBoot_ms = get<std::uint32_t>(p, 0);
  m.roll_rad = get<float>(p, 4);
  m.pitch_rad = get<float>(p, 8);
  m.yaw_rad = get<float>(p, 12);
  m.rollSpeed_radps = get<float>(p, 16);
  m.pitchSpeed_radps = get<float>(p, 20);
  m.yawSpeed_radps = get<float>(p, 24);
  return m;
}

std::size_t encodePayload(const Attitude& m, Payload& p) {
  put(p, 0, m.timeBoot_ms);
  put(p, 4, m.roll_rad);
  put(p, 8, m.pitch_rad);
  put(p, 12, m.yaw_rad);
  put(p, 16, m.rollSpeed_radps);
  put(p, 20, m.pitchSpeed_radps);
  put(p, 24, m.yawSpeed_radps);
  return 28;
}

AttitudeQuaternion decodeAttitudeQuaternion(const Payload& p) {
  AttitudeQuaternion m;
  m.timeBoot_ms = get<std::uint32_t>(p, 0);
  for (std::size_t i = 0; i < 4; ++i) {
    m.q[i] = get<float>(p, 4 + 4 * i);
    m.reprOffsetQ[i] = get<float>(p, 32 + 4 * i);
  }
  m.rollSpeed_radps = get<float>(p, 20);
  m.pitchSpeed_radps = get<float>(p, 24);
  m.yawSpeed_radps = get<float>(p, 28);
  return m;
}

std::size_t encodePayload(const AttitudeQuaternion& m, Payload& p) {
  put(p, 0, m.timeBoot_ms);
  for (std::size_t i = 0; i < 4; ++i) {
    put(p, 4 + 4 * i, m.q[i]);
    put(p, 32 + 4 * i, m.reprOffsetQ[i]);
  }
  put(p, 20, m.rollSpeed_radps);
  put(p, 24, m.pitchSpeed_radps);
  put(p, 28, m.yawSpeed_radps);
  return 48;
}

GlobalPositionInt decodeGlobalPositionInt(const Payload& p) {
  GlobalPositionInt m;
  m.timeBoot_ms = get<std::uint32_t>(p, 0);
  m.latitude_degE7 = get<std::int32_t>(p, 4);
  m.longitude_degE7 = get<std::int32_t>(p, 8);
  m.altitudeMsl_mm = get<std::int32_t>(p, 12);
  m.relativeAltitude_mm = get<std::int32_t>(p, 16);
  m.vx_cmps = get<std::int16_t>(p, 20);
  m.vy_cmps = get<std::int16_t>(p, 22);
  m.vz_cmps = get<std::int16_t>(p, 24);
  m.heading_cdeg = get<std::uint16_t>(p, 26);
  return m;
}

std::size_t encodePayload(const GlobalPositionInt& m, Payload& p) {
  put(p, 0, m.timeBoot_ms);
  put(p, 4, m.latitude_degE7);
  put(p, 8, m.longitude_degE7);
  put(p, 12, m.altitudeMsl_mm);
  put(p, 16, m.relativeAltitude_mm);
  put(p, 20, m.vx_cmps);
  put(p, 22, m.vy_cmps);
  put(p, 24, m.vz_cmps);
  put(p, 26, m.heading_cdeg);
  return 28;
}

constexpr std::size_t kGimbalBaseLength = 40;  // without the extension fields

GimbalDeviceAttitudeStatus decodeGimbal(const Payload& p, std::size_t payloadLength) {
  GimbalDeviceAttitudeStatus m;
  m.timeBoot_ms = get<std::uint32_t>(p, 0);
  for (std::size_t i = 0; i < 4; ++i) {
    m.q[i] = get<float>(p, 4 + 4 * i);
  }
  m.angularVelocityXRadps = get<float>(p, 20);
  m.angularVelocityYRadps = get<float>(p, 24);
  m.angularVelocityZRadps = get<float>(p, 28);
  m.failureFlags = get<std::uint32_t>(p, 32);
  m.flags = get<std::uint16_t>(p, 36);
  m.targetSystem = get<std::uint8_t>(p, 38);
  m.targetComponent = get<std::uint8_t>(p, 39);
  m.deltaYaw_rad = get<float>(p, 40);
  m.deltaYawVelocity_radps = get<float>(p, 44);
  m.gimbalDeviceId = get<std::uint8_t>(p, 48);
  m.hasExtensions = payloadLength > kGimbalBaseLength;
  return m;
}

std::size_t encodePayload(const GimbalDeviceAttitudeStatus& m, Payload& p) {
  put(p, 0, m.timeBoot_ms);
  for (std::size_t i = 0; i < 4; ++i) {
    put(p, 4 + 4 * i, m.q[i]);
  }
  put(p, 20, m.angularVelocityXRadps);
  put(p, 24, m.angularVelocityYRadps);
  put(p, 28, m.angularVelocityZRadps);
  put(p, 32, m.failureFlags);
  put(p, 36, m.flags);
  put(p, 38, m.targetSystem);
  put(p, 39, m.targetComponent);
  if (!m.hasExtensions) {
    return kGimbalBaseLength;
  }
  put(p, 40, m.deltaYaw_rad);
  put(p, 44, m.deltaYawVelocity_radps);
  put(p, 48, m.gimbalDeviceId);
  return 49;
}

}  // namespace

const MessageSpec* findMessageSpec(std::uint32_t messageId) {
  for (const MessageSpec& spec : kSpecs) {
    if (spec.id == messageId) {
      return &spec;
    }
  }
  return nullptr;
}

std::uint32_t messageId(const Message& message) {
  struct Visitor {
    std::uint32_t operator()(const Attitude&) const { return kMsgIdAttitude; }
    std::uint32_t operator()(const AttitudeQuaternion&) const { return kMsgIdAttitudeQuaternion; }
    std::uint32_t operator()(const GlobalPositionInt&) const { return kMsgIdGlobalPositionInt; }
    std::uint32_t operator()(const GimbalDeviceAttitudeStatus&) const {
      return kMsgIdGimbalDeviceAttitudeStatus;
    }
  };
  return std::visit(Visitor{}, message);
}

std::optional<Message> decode(const MavlinkFrame& frame) {
  switch (frame.messageId) {
    case kMsgIdAttitude:
      return Message{decodeAttitude(frame.payload)};
    case kMsgIdAttitudeQuaternion:
      return Message{decodeAttitudeQuaternion(frame.payload)};
    case kMsgIdGlobalPositionInt:
      return Message{decodeGlobalPositionInt(frame.payload)};
    case kMsgIdGimbalDeviceAttitudeStatus:
      return Message{decodeGimbal(frame.payload, frame.payloadLength)};
    default:
      return std::nullopt;
  }
}

std::size_t encode(const Message& message, const FrameHeader& header, std::span<std::uint8_t> out) {
  Payload payload{};
  std::size_t length =
      std::visit([&payload](const auto& m) { return encodePayload(m, payload); }, message);
  // MAVLink 2 truncates trailing zero bytes of the payload, keeping at least one byte.
  while (length > 1 && payload[length - 1] == 0) {
    --length;
  }
  const std::size_t total = kHeaderBytes + length + kChecksumBytes;
  if (out.size() < total) {
    return 0;
  }
  const std::uint32_t id = messageId(message);
  const MessageSpec* spec = findMessageSpec(id);
  if (spec == nullptr) {
    return 0;  // unreachable: every Message alternative has a spec
  }
  out[0] = kStxV2;
  out[1] = static_cast<std::uint8_t>(length);
  out[2] = 0;  // incompat flags: unsigned
  out[3] = 0;  // compat flags
  out[4] = header.sequence;
  out[5] = header.systemId;
  out[6] = header.componentId;
  out[7] = static_cast<std::uint8_t>(id & 0xFF);
  out[8] = static_cast<std::uint8_t>((id >> 8) & 0xFF);
  out[9] = static_cast<std::uint8_t>((id >> 16) & 0xFF);
  std::memcpy(out.data() + kHeaderBytes, payload.data(), length);
  std::uint16_t crc = crcCalculate(out.subspan(1, kHeaderBytes - 1 + length));
  crc = crcAccumulate(spec->crcExtra, crc);
  out[kHeaderBytes + length] = static_cast<std::uint8_t>(crc & 0xFF);
  out[kHeaderBytes + length + 1] = static_cast<std::uint8_t>(crc >> 8);
  return total;
}

}  // namespace vp::mavlink
