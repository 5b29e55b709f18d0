// MAVLink 2 parser, message codecs and pose assembly (pure; no sockets here).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "alloc_counter.hpp"
#include "geodesy/attitude.hpp"
#include "mavlink/mavlink_parser.hpp"
#include "mavlink/messages.hpp"
#include "mavlink/pose_assembler.hpp"

namespace vp::mavlink {
namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes encodeToBytes(const Message& message, FrameHeader header = {}) {
  std::array<std::uint8_t, kMaxFrameBytes> buffer{};
  const std::size_t length = encode(message, header, buffer);
  EXPECT_GT(length, 0u);
  return Bytes(buffer.begin(), buffer.begin() + static_cast<long>(length));
}

// Recomputes the checksum after a test edited a frame's header (e.g. its flags).
void reseal(Bytes& frame, std::uint8_t crcExtra) {
  const std::size_t payloadLength = frame[1];
  std::uint16_t crc = crcCalculate(
      std::span<const std::uint8_t>(frame.data() + 1, kHeaderBytes - 1 + payloadLength));
  crc = crcAccumulate(crcExtra, crc);
  frame[kHeaderBytes + payloadLength] = static_cast<std::uint8_t>(crc & 0xFF);
  frame[kHeaderBytes + payloadLength + 1] = static_cast<std::uint8_t>(crc >> 8);
}

struct Collected {
  std::vector<MavlinkFrame> frames;
};

void parseAll(MavlinkParser& parser, const Bytes& bytes, Collected& out) {
  parser.parse(bytes, [&out](const MavlinkFrame& frame) { out.frames.push_back(frame); });
}

AttitudeQuaternion sampleAttitudeQuaternion() {
  AttitudeQuaternion m;
  m.timeBoot_ms = 123456;
  const Eigen::Quaterniond q(geodesy::rotationFromEuler({3.0, -4.0, 75.0}));
  m.q = {static_cast<float>(q.w()), static_cast<float>(q.x()), static_cast<float>(q.y()),
         static_cast<float>(q.z())};
  m.rollSpeed_radps = 0.01f;
  m.pitchSpeed_radps = -0.02f;
  m.yawSpeed_radps = 0.03f;
  return m;
}

GlobalPositionInt samplePosition() {
  GlobalPositionInt m;
  m.timeBoot_ms = 123400;
  m.latitude_degE7 = 430731000;
  m.longitude_degE7 = -894012000;
  m.altitudeMsl_mm = 292500;
  m.relativeAltitude_mm = 32500;
  m.vx_cmps = 120;
  m.vy_cmps = -40;
  m.vz_cmps = 0;
  m.heading_cdeg = 0;  // trailing zeros: this frame gets truncated on the wire
  return m;
}

TEST(MavlinkCrc, MatchesTheMcrf4xxCheckValue) {
  const char* text = "123456789";
  const std::span<const std::uint8_t> bytes(reinterpret_cast<const std::uint8_t*>(text), 9);
  EXPECT_EQ(crcCalculate(bytes), 0x6F91);  // CRC-16/MCRF4XX catalogue check value
}

// A GLOBAL_POSITION_INT frame laid out by hand from common.xml (offsets and CRC_EXTRA 104),
// independent of the encoder: the parser and decoder must read it.
TEST(MavlinkParser, ReadsAHandBuiltGlobalPositionIntFrame) {
  Bytes payload(28, 0);
  auto put32 = [&payload](std::size_t at, std::uint32_t v) {
    for (int i = 0; i < 4; ++i)
      payload[at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(v >> (8 * i));
  };
  put32(0, 5000);                                   // time_boot_ms
  put32(4, static_cast<std::uint32_t>(473977420));  // lat
  put32(8, static_cast<std::uint32_t>(85455940));   // lon
  put32(12, static_cast<std::uint32_t>(488000));    // alt (mm, MSL)
  put32(16, static_cast<std::uint32_t>(-1000));     // relative_alt
  payload[20] = 0x10;                               // vx = 16 cm/s
  payload[26] = 0x28;                               // hdg = 0x2328 = 9000 cdeg
  payload[27] = 0x23;
  Bytes frame{0xFD, 28, 0, 0, 7, 1, 1, 33, 0, 0};
  frame.insert(frame.end(), payload.begin(), payload.end());
  frame.resize(frame.size() + 2);
  reseal(frame, 104);

  MavlinkParser parser;
  Collected got;
  parseAll(parser, frame, got);
  ASSERT_EQ(got.frames.size(), 1u);
  EXPECT_EQ(got.frames[0].sequence, 7);
  EXPECT_EQ(got.frames[0].messageId, 33u);
  const auto message = decode(got.frames[0]);
  ASSERT_TRUE(message.has_value());
  const auto& position = std::get<GlobalPositionInt>(*message);
  EXPECT_EQ(position.timeBoot_ms, 5000u);
  EXPECT_EQ(position.latitude_degE7, 473977420);
  EXPECT_EQ(position.longitude_degE7, 85455940);
  EXPECT_EQ(position.altitudeMsl_mm, 488000);
  EXPECT_EQ(position.relativeAltitude_mm, -1000);
  EXPECT_EQ(position.vx_cmps, 16);
  EXPECT_EQ(position.heading_cdeg, 9000);
}

TEST(MavlinkCodec, EveryMessageRoundTrips) {
  GimbalDeviceAttitudeStatus gimbal;
  gimbal.timeBoot_ms = 999;
  gimbal.q = {0.7071068f, 0.0f, -0.7071068f, 0.0f};
  gimbal.flags = kGimbalFlagYawInVehicleFrame;
  gimbal.failureFlags = 0x20;
  gimbal.targetSystem = 1;
  gimbal.deltaYaw_rad = 1.25f;
  gimbal.gimbalDeviceId = 1;
  gimbal.hasExtensions = true;
  Attitude attitude{42, 0.1f, -0.2f, 2.5f, 0.0f, 0.0f, 0.3f};
  const std::array<Message, 4> messages{Message{attitude}, Message{sampleAttitudeQuaternion()},
                                        Message{samplePosition()}, Message{gimbal}};
  MavlinkParser parser;
  for (const Message& message : messages) {
    Collected got;
    parseAll(parser, encodeToBytes(message, {9, 2, 154}), got);
    ASSERT_EQ(got.frames.size(), 1u) << messageId(message);
    EXPECT_EQ(got.frames[0].systemId, 2);
    EXPECT_EQ(got.frames[0].componentId, 154);
    const auto decoded = decode(got.frames[0]);
    ASSERT_TRUE(decoded.has_value());
    ASSERT_EQ(decoded->index(), message.index());
    // Re-encoding the decoded message gives the same bytes: every field survived.
    EXPECT_EQ(encodeToBytes(*decoded, {9, 2, 154}), encodeToBytes(message, {9, 2, 154}));
  }
  EXPECT_EQ(parser.counters().frames, 4u);
  EXPECT_EQ(parser.counters().badCrc, 0u);
}

TEST(MavlinkCodec, TrailingZerosAreTruncatedAndReadBackAsZero) {
  GlobalPositionInt position = samplePosition();  // vz and heading are zero: 4 bytes cut
  const Bytes frame = encodeToBytes(Message{position});
  EXPECT_EQ(frame[1], 24);
  EXPECT_EQ(frame.size(), kHeaderBytes + 24 + kChecksumBytes);
  MavlinkParser parser;
  Collected got;
  parseAll(parser, frame, got);
  ASSERT_EQ(got.frames.size(), 1u);
  EXPECT_EQ(got.frames[0].payloadLength, 24);
  const auto decoded = std::get<GlobalPositionInt>(*decode(got.frames[0]));
  EXPECT_EQ(decoded.vy_cmps, -40);
  EXPECT_EQ(decoded.vz_cmps, 0);
  EXPECT_EQ(decoded.heading_cdeg, 0);

  // An all-zero payload keeps one byte.
  const Bytes zero = encodeToBytes(Message{Attitude{}});
  EXPECT_EQ(zero[1], 1);
  // A gimbal status without extensions is 40 bytes at most and decodes as such.
  GimbalDeviceAttitudeStatus gimbal;
  gimbal.targetComponent = 1;  // last base byte non-zero
  const Bytes base = encodeToBytes(Message{gimbal});
  EXPECT_EQ(base[1], 40);
  Collected gotGimbal;
  parseAll(parser, base, gotGimbal);
  ASSERT_EQ(gotGimbal.frames.size(), 1u);
  EXPECT_FALSE(std::get<GimbalDeviceAttitudeStatus>(*decode(gotGimbal.frames[0])).hasExtensions);
}

TEST(MavlinkCodec, EncodeRefusesATooSmallBuffer) {
  std::array<std::uint8_t, 20> small{};
  EXPECT_EQ(encode(Message{sampleAttitudeQuaternion()}, {}, small), 0u);
}

TEST(MavlinkParser, CountsEveryKindOfDamageAndKeepsTheGoodFrames) {
  const Bytes good = encodeToBytes(Message{sampleAttitudeQuaternion()});
  Bytes stream;
  stream.reserve(1024);  // (GCC 12 at -O3 reports a false -Warray-bounds on the first insert)
  // 1. line noise before the first frame
  const Bytes noise{0x00, 0x11, 0x55, 0xFE, 0x22};
  stream.insert(stream.end(), noise.begin(), noise.end());
  stream.insert(stream.end(), good.begin(), good.end());
  // 2. a corrupted payload byte -> bad CRC
  Bytes corrupt = good;
  corrupt[kHeaderBytes + 3] ^= 0x40;
  stream.insert(stream.end(), corrupt.begin(), corrupt.end());
  // 3. a message this library has no CRC_EXTRA for (HEARTBEAT, id 0): skipped by length
  Bytes heartbeat{0xFD, 9, 0, 0, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0, 2, 3, 81, 4, 3, 0xAB, 0xCD};
  stream.insert(stream.end(), heartbeat.begin(), heartbeat.end());
  // 4. a signed frame: flag set, CRC over the flagged header, 13 signature bytes after it
  Bytes signedFrame = good;
  signedFrame[2] = kIncompatFlagSigned;
  reseal(signedFrame, 246);
  signedFrame.insert(signedFrame.end(), kSignatureBytes, 0x5A);
  stream.insert(stream.end(), signedFrame.begin(), signedFrame.end());
  // 5. an incompat flag MAVLink does not define: must be dropped
  Bytes unknownFlag = good;
  unknownFlag[2] = 0x02;
  reseal(unknownFlag, 246);
  stream.insert(stream.end(), unknownFlag.begin(), unknownFlag.end());
  // 6. a frame cut short, immediately followed by a good frame (a serial glitch)
  stream.insert(stream.end(), good.begin(), good.begin() + 20);
  stream.insert(stream.end(), good.begin(), good.end());

  MavlinkParser parser;
  Collected got;
  parseAll(parser, stream, got);
  const ParserCounters& c = parser.counters();
  EXPECT_EQ(got.frames.size(), 3u);  // first, signed, and the one after the cut frame
  EXPECT_EQ(c.frames, 3u);
  EXPECT_EQ(c.badCrc, 2u);  // the corrupted frame and the cut one
  EXPECT_EQ(c.unknownMessage, 1u);
  EXPECT_EQ(c.unsupportedFlags, 1u);
  EXPECT_TRUE(got.frames[1].isSigned);
  for (const MavlinkFrame& frame : got.frames) {
    const auto attitude = std::get<AttitudeQuaternion>(*decode(frame));
    EXPECT_EQ(attitude.timeBoot_ms, 123456u);
  }
  EXPECT_GE(c.skippedBytes, noise.size());
}

TEST(MavlinkParser, ADatagramEndingInsideAFrameCountsAsTruncated) {
  const Bytes good = encodeToBytes(Message{samplePosition()});
  MavlinkParser parser;
  Collected got;
  parseAll(parser, Bytes(good.begin(), good.begin() + 15), got);
  parser.endOfDatagram();
  parseAll(parser, good, got);
  parser.endOfDatagram();
  EXPECT_EQ(parser.counters().truncated, 1u);
  EXPECT_EQ(parser.counters().frames, 1u);
  EXPECT_EQ(got.frames.size(), 1u);
}

TEST(MavlinkParser, RandomCorruptionNeverLosesAnUntouchedFrame) {
  // 500 frames with random damage (bit flips, cuts, inserted noise) in one stream; every
  // frame whose bytes were not touched is delivered, and nothing false gets through.
  std::mt19937 rng(7);
  MavlinkParser parser;
  Bytes stream;
  std::size_t untouched = 0;
  std::vector<std::uint32_t> expectedTimes;
  for (std::uint32_t i = 0; i < 500; ++i) {
    AttitudeQuaternion m = sampleAttitudeQuaternion();
    m.timeBoot_ms = 1000 + i;
    Bytes frame = encodeToBytes(Message{m}, {static_cast<std::uint8_t>(i), 1, 1});
    switch (rng() % 4) {
      case 0:  // flip one bit
        frame[1 + rng() % (frame.size() - 1)] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
        break;
      case 1:  // cut anywhere, even inside the header
        frame.resize(1 + rng() % (frame.size() - 1));
        break;
      case 2:  // noise before it, STX bytes included
        for (int k = 0; k < 7; ++k) {
          stream.push_back(k == 3 ? kStxV2 : static_cast<std::uint8_t>(rng()));
        }
        [[fallthrough]];
      default:
        ++untouched;
        expectedTimes.push_back(m.timeBoot_ms);
    }
    stream.insert(stream.end(), frame.begin(), frame.end());
  }
  std::vector<std::uint32_t> times;
  parser.parse(stream, [&times](const MavlinkFrame& frame) {
    times.push_back(std::get<AttitudeQuaternion>(*decode(frame)).timeBoot_ms);
  });
  // Every untouched frame arrives, in order; a damaged one never does (CRC).
  EXPECT_EQ(times, expectedTimes);
  EXPECT_EQ(parser.counters().frames, untouched);
  EXPECT_GT(parser.counters().badCrc, 0u);
}

TEST(MavlinkParser, ParsingAndAssemblingAllocateNothing) {
  Bytes stream;
  for (std::uint32_t i = 0; i < 50; ++i) {
    AttitudeQuaternion attitude = sampleAttitudeQuaternion();
    attitude.timeBoot_ms = 2000 + 20 * i;
    GlobalPositionInt position = samplePosition();
    position.timeBoot_ms = 2000 + 20 * i;
    for (const Message& m : {Message{attitude}, Message{position}}) {
      const Bytes frame = encodeToBytes(m);
      stream.insert(stream.end(), frame.begin(), frame.end());
    }
    stream.push_back(0x33);  // noise
  }
  MavlinkParser parser;
  MavlinkPoseAssembler assembler;
  std::size_t samples = 0;
  std::int64_t receive_ns = 1'000'000'000;
  test::AllocationCounter counter;
  parser.parse(stream, [&](const MavlinkFrame& frame) {
    if (const auto message = decode(frame)) {
      receive_ns += 10'000'000;
      samples += assembler.add(*message, frame.systemId, receive_ns) ? 1 : 0;
    }
  });
  counter.stop();
  EXPECT_EQ(counter.count(), 0u);
  EXPECT_EQ(parser.counters().frames, 100u);
  EXPECT_EQ(samples, 49u);  // every attitude after the first position
}

// ---- pose assembly ----

constexpr std::int64_t kMs = 1'000'000;

TEST(MavlinkPoseAssembler, BuildsPoseSamplesInTheProjectsConventions) {
  PoseAssemblerConfig config;
  config.geoidSeparation_m = -33.5;  // h = H_msl + N
  MavlinkPoseAssembler assembler(config);
  const AttitudeQuaternion attitude = sampleAttitudeQuaternion();
  EXPECT_FALSE(assembler.add(Message{attitude}, 1, 5 * kMs));  // no position yet
  EXPECT_EQ(assembler.counters().noPositionYet, 1u);
  EXPECT_FALSE(assembler.add(Message{samplePosition()}, 1, 6 * kMs));
  ASSERT_TRUE(assembler.add(Message{attitude}, 1, 7 * kMs));
  const PoseSample& s = assembler.sample();
  EXPECT_NEAR(s.position.latitude_deg, 43.0731, 1e-9);
  EXPECT_NEAR(s.position.longitude_deg, -89.4012, 1e-9);
  EXPECT_NEAR(s.position.height_m, 292.5 - 33.5, 1e-9);
  const geodesy::EulerAnglesDeg euler = geodesy::eulerFromRotation(s.bodyToNed.toRotationMatrix());
  EXPECT_NEAR(euler.roll_deg, 3.0, 1e-4);
  EXPECT_NEAR(euler.pitch_deg, -4.0, 1e-4);
  EXPECT_NEAR(euler.yaw_deg, 75.0, 1e-4);
  EXPECT_FALSE(s.hasGimbal);
}

TEST(MavlinkPoseAssembler, AttitudeEulerIsUsedOnlyWithoutQuaternions) {
  MavlinkPoseAssembler assembler;
  assembler.add(Message{samplePosition()}, 1, 1 * kMs);
  const float deg = static_cast<float>(std::numbers::pi / 180.0);
  const Attitude euler{100, 10 * deg, 20 * deg, -30 * deg, 0, 0, 0};
  ASSERT_TRUE(assembler.add(Message{euler}, 1, 2 * kMs));
  const Eigen::Matrix3d expected = geodesy::rotationFromEuler({10, 20, -30});
  EXPECT_TRUE(assembler.sample().bodyToNed.toRotationMatrix().isApprox(expected, 1e-6));
  EXPECT_TRUE(assembler.add(Message{sampleAttitudeQuaternion()}, 1, 3 * kMs));
  EXPECT_FALSE(assembler.add(Message{euler}, 1, 4 * kMs));  // quaternions are streaming
}

TEST(MavlinkPoseAssembler, RejectsBadValuesAndOtherSystems) {
  PoseAssemblerConfig config;
  config.systemId = 1;
  MavlinkPoseAssembler assembler(config);
  EXPECT_FALSE(assembler.add(Message{samplePosition()}, 2, kMs));
  EXPECT_EQ(assembler.counters().otherSystem, 1u);
  GlobalPositionInt badPosition = samplePosition();
  badPosition.latitude_degE7 = 950000000;  // 95 deg
  EXPECT_FALSE(assembler.add(Message{badPosition}, 1, kMs));
  AttitudeQuaternion nanAttitude = sampleAttitudeQuaternion();
  nanAttitude.q[2] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(assembler.add(Message{nanAttitude}, 1, kMs));
  AttitudeQuaternion longQuaternion = sampleAttitudeQuaternion();
  longQuaternion.q = {1, 1, 0, 0};
  EXPECT_FALSE(assembler.add(Message{longQuaternion}, 1, kMs));
  GimbalDeviceAttitudeStatus contradictory;
  contradictory.flags = kGimbalFlagYawInEarthFrame | kGimbalFlagYawInVehicleFrame;
  EXPECT_FALSE(assembler.add(Message{contradictory}, 1, kMs));
  EXPECT_EQ(assembler.counters().rejected, 4u);
  EXPECT_EQ(assembler.counters().samples, 0u);
}

GimbalDeviceAttitudeStatus gimbalAt(const geodesy::EulerAnglesDeg& angles, std::uint16_t flags) {
  GimbalDeviceAttitudeStatus m;
  m.timeBoot_ms = 50;
  const Eigen::Quaterniond q(geodesy::rotationFromEuler(angles));
  m.q = {static_cast<float>(q.w()), static_cast<float>(q.x()), static_cast<float>(q.y()),
         static_cast<float>(q.z())};
  m.flags = flags;
  return m;
}

TEST(MavlinkPoseAssembler, GimbalYawIsTurnedToNorth) {
  MavlinkPoseAssembler assembler;
  assembler.add(Message{samplePosition()}, 1, kMs);
  assembler.add(Message{sampleAttitudeQuaternion()}, 1, 2 * kMs);  // drone yaw 75 deg

  // Earth frame (new flag, and the legacy YAW_LOCK): the angles as sent.
  for (const std::uint16_t flags : {kGimbalFlagYawInEarthFrame, kGimbalFlagYawLock}) {
    assembler.add(Message{gimbalAt({0.0, -60.0, 10.0}, flags)}, 1, 3 * kMs);
    const PoseSample& s = assembler.sample();
    ASSERT_TRUE(s.hasGimbal);
    EXPECT_EQ(s.gimbal.reference, geodesy::GimbalReference::Earth);
    EXPECT_NEAR(s.gimbal.angles.pitch_deg, -60.0, 1e-4);
    EXPECT_NEAR(s.gimbal.angles.yaw_deg, 10.0, 1e-4);
  }
  // Vehicle frame without delta_yaw: yaw relative to the drone's heading (75 deg).
  assembler.add(Message{gimbalAt({0.0, -60.0, 10.0}, kGimbalFlagYawInVehicleFrame)}, 1, 4 * kMs);
  EXPECT_NEAR(assembler.sample().gimbal.angles.yaw_deg, 85.0, 1e-4);
  EXPECT_NEAR(assembler.sample().gimbal.angles.pitch_deg, -60.0, 1e-4);
  // With delta_yaw sent (extensions), it wins over the drone's yaw.
  GimbalDeviceAttitudeStatus withDelta = gimbalAt({0.0, -60.0, 10.0}, kGimbalFlagYawInVehicleFrame);
  withDelta.hasExtensions = true;
  withDelta.deltaYaw_rad = static_cast<float>(-20.0 * std::numbers::pi / 180.0);
  assembler.add(Message{withDelta}, 1, 5 * kMs);
  EXPECT_NEAR(assembler.sample().gimbal.angles.yaw_deg, -10.0, 1e-4);
  // Neither flag (legacy, no YAW_LOCK): vehicle frame, the drone's yaw.
  assembler.add(Message{gimbalAt({0.0, -90.0 + 1e-3, 0.0}, 0)}, 1, 6 * kMs);
  const Eigen::Vector3d axis =
      geodesy::rotationFromEuler(assembler.sample().gimbal.angles) * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(axis.z(), 1.0, 1e-6);  // still looks straight down
}

TEST(BootClockMapper, EstimatesTheOffsetFromTheLeastDelayedMessages) {
  // Messages at 50 Hz with 2..25 ms of transport delay; the estimate is the true offset plus
  // the smallest delay in the window, to the millisecond of time_boot_ms.
  std::mt19937 rng(3);
  std::uniform_int_distribution<std::int64_t> delay_us(2000, 25000);
  const std::int64_t trueOffset_ns = 7'654'321'000'000;
  BootClockMapper mapper;
  std::int64_t worstError_ns = 0;
  for (std::uint32_t boot_ms = 10000; boot_ms < 20000; boot_ms += 20) {
    const std::int64_t send_ns = static_cast<std::int64_t>(boot_ms) * kMs + trueOffset_ns;
    mapper.observe(boot_ms, send_ns + delay_us(rng) * 1000);
    if (boot_ms > 12000) {
      worstError_ns = std::max(worstError_ns, std::abs(mapper.offset_ns() - trueOffset_ns));
    }
  }
  EXPECT_LE(worstError_ns, 5 * kMs);  // min of 64 uniform delays in 2..25 ms
  EXPECT_GE(mapper.offset_ns(), trueOffset_ns + 2 * kMs);
  std::printf("boot clock offset error: worst %.3f ms after warm-up\n", worstError_ns / 1e6);

  // The sender reboots: its boot time restarts, so does the estimate.
  mapper.observe(100, 30'000 * kMs + trueOffset_ns);
  EXPECT_EQ(mapper.restarts(), 1u);
  EXPECT_EQ(mapper.toLocal_ns(100), 30'000 * kMs + trueOffset_ns);
}

TEST(BootClockMapper, FollowsClockDrift) {
  // 100 ppm drift between the autopilot's and the companion's crystals over 100 s.
  BootClockMapper mapper;
  for (std::uint32_t boot_ms = 0; boot_ms <= 100000; boot_ms += 20) {
    const double local_ns = boot_ms * 1e6 * (1.0 + 100e-6) + 1e9;
    mapper.observe(boot_ms, static_cast<std::int64_t>(local_ns) + 3 * kMs);
  }
  const double expected_ns = 100000 * 1e6 * (1.0 + 100e-6) + 1e9 + 3e6;
  EXPECT_NEAR(static_cast<double>(mapper.toLocal_ns(100000)), expected_ns, 0.2e6);
}

TEST(MavlinkPoseAssembler, SampleTimesAreOnTheLocalClock) {
  PoseAssemblerConfig config;
  config.linkLatency_ns = 2 * kMs;
  MavlinkPoseAssembler assembler(config);
  const std::int64_t offset_ns = 500'000 * kMs;
  GlobalPositionInt position = samplePosition();
  position.timeBoot_ms = 1000;
  assembler.add(Message{position}, 1, 1000 * kMs + offset_ns + 2 * kMs);
  AttitudeQuaternion attitude = sampleAttitudeQuaternion();
  attitude.timeBoot_ms = 1010;
  ASSERT_TRUE(assembler.add(Message{attitude}, 1, 1010 * kMs + offset_ns + 9 * kMs));
  EXPECT_EQ(assembler.sample().timestamp_ns, 1010 * kMs + offset_ns);
  EXPECT_EQ(assembler.sample().positionTimestamp_ns, 1000 * kMs + offset_ns);
}

}  // namespace
}  // namespace vp::mavlink
