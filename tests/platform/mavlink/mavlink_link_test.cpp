// MAVLink links on real descriptors: a UDP socket pair on loopback and a serial port on a
// pseudo-terminal, fed with encoded messages and deliberate corruptions.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <unistd.h>

#include <array>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "mavlink/mavlink_parser.hpp"
#include "mavlink/messages.hpp"
#include "platform/mavlink/mavlink_link.hpp"
#include "platform/mavlink/serial_port.hpp"
#include "platform/mavlink/udp_socket.hpp"

namespace vp::platform::mavlink {
namespace {

namespace mv = vp::mavlink;
using Bytes = std::vector<std::uint8_t>;

Bytes frameOf(std::uint32_t timeBoot_ms, std::uint8_t sequence) {
  mv::AttitudeQuaternion m;
  m.timeBoot_ms = timeBoot_ms;
  m.q = {0.9f, 0.1f, 0.2f, 0.37416574f};
  std::array<std::uint8_t, mv::kMaxFrameBytes> buffer{};
  const std::size_t n = mv::encode(mv::Message{m}, {sequence, 1, 1}, buffer);
  return Bytes(buffer.begin(), buffer.begin() + static_cast<long>(n));
}

TEST(UdpSocket, LoopbackDatagramsWithCorruptionsAreCounted) {
  UdpSocket receiver;
  std::string why;
  ASSERT_TRUE(receiver.open("127.0.0.1", 0, &why)) << why;
  ASSERT_NE(receiver.localPort(), 0);
  UdpSocket sender;
  ASSERT_TRUE(sender.open("127.0.0.1", 0, &why)) << why;
  ASSERT_TRUE(sender.connect("127.0.0.1", receiver.localPort(), &why)) << why;

  std::array<std::uint8_t, kLinkScratchBytes> scratch{};
  mv::MavlinkParser parser;
  std::vector<std::uint32_t> times;
  auto onFrame = [&times](const mv::MavlinkFrame& frame) {
    times.push_back(std::get<mv::AttitudeQuaternion>(*mv::decode(frame)).timeBoot_ms);
  };
  EXPECT_EQ(drainUdp(receiver, parser, scratch, onFrame), 0);  // nothing yet, no blocking

  // 10 good datagrams, 3 good frames packed in one datagram, 2 bad CRCs, 2 truncated
  // datagrams, 1 datagram of noise.
  std::vector<Bytes> datagrams;
  std::uint32_t t = 0;
  for (int i = 0; i < 10; ++i) {
    ++t;
    datagrams.push_back(frameOf(t, static_cast<std::uint8_t>(t)));
  }
  Bytes packed;
  for (int i = 0; i < 3; ++i) {
    ++t;
    const Bytes f = frameOf(t, static_cast<std::uint8_t>(t));
    packed.insert(packed.end(), f.begin(), f.end());
  }
  datagrams.push_back(packed);
  for (int i = 0; i < 2; ++i) {
    Bytes bad = frameOf(900 + static_cast<std::uint32_t>(i), 0);
    bad[bad.size() - 1] ^= 0xFF;  // checksum byte
    datagrams.push_back(bad);
  }
  for (int i = 0; i < 2; ++i) {
    Bytes cut = frameOf(950 + static_cast<std::uint32_t>(i), 0);
    cut.resize(cut.size() - 5);
    datagrams.push_back(cut);
  }
  datagrams.push_back(Bytes{1, 2, 3, 4, 5, 6, 7, 8});
  for (const Bytes& d : datagrams) {
    ASSERT_EQ(sender.send(d), static_cast<ssize_t>(d.size()));
  }

  long reads = 0;
  for (int attempt = 0; attempt < 50 && reads < static_cast<long>(datagrams.size()); ++attempt) {
    if (receiver.waitReadable(100)) {
      const long n = drainUdp(receiver, parser, scratch, onFrame);
      ASSERT_GE(n, 0);
      reads += n;
    }
  }
  EXPECT_EQ(reads, static_cast<long>(datagrams.size()));
  std::vector<std::uint32_t> expected;
  for (std::uint32_t i = 1; i <= 13; ++i) {
    expected.push_back(i);
  }
  EXPECT_EQ(times, expected);
  EXPECT_EQ(parser.counters().frames, 13u);
  EXPECT_EQ(parser.counters().badCrc, 2u);
  EXPECT_EQ(parser.counters().truncated, 2u);
  // The noise datagram, and the bytes after the STX of each bad frame (scanned again).
  EXPECT_EQ(parser.counters().skippedBytes, 8u + 2 * (datagrams[11].size() - 1));
}

TEST(UdpSocket, SteadyStateReceiveAllocatesNothing) {
  UdpSocket receiver;
  UdpSocket sender;
  std::string why;
  ASSERT_TRUE(receiver.open("127.0.0.1", 0, &why)) << why;
  ASSERT_TRUE(sender.open("127.0.0.1", 0, &why)) << why;
  ASSERT_TRUE(sender.connect("127.0.0.1", receiver.localPort(), &why)) << why;
  const Bytes frame = frameOf(5, 5);
  std::array<std::uint8_t, kLinkScratchBytes> scratch{};
  mv::MavlinkParser parser;
  std::size_t frames = 0;
  test::AllocationCounter counter;
  for (int i = 0; i < 200; ++i) {
    ASSERT_EQ(sender.send(frame), static_cast<ssize_t>(frame.size()));
    ASSERT_TRUE(receiver.waitReadable(1000));
    drainUdp(receiver, parser, scratch, [&frames](const mv::MavlinkFrame&) { ++frames; });
  }
  counter.stop();
  EXPECT_EQ(counter.count(), 0u);
  EXPECT_EQ(frames, 200u);
}

TEST(UdpSocket, BindErrorsNameTheAddress) {
  UdpSocket first;
  std::string why;
  ASSERT_TRUE(first.open("127.0.0.1", 0, &why)) << why;
  UdpSocket second;
  EXPECT_FALSE(second.open("127.0.0.1", first.localPort(), &why));
  EXPECT_NE(why.find("127.0.0.1:" + std::to_string(first.localPort())), std::string::npos) << why;
  EXPECT_NE(why.find("in use"), std::string::npos) << why;
  EXPECT_FALSE(second.open("no.such.host.invalid", 14550, &why));
  EXPECT_NE(why.find("no.such.host.invalid"), std::string::npos) << why;
  EXPECT_FALSE(second.isOpen());
}

// A pseudo-terminal stands in for the autopilot's UART: the test writes on the master side,
// SerialPort reads the slave side with real termios settings.
class PtyPair {
 public:
  PtyPair() {
    master_ = posix_openpt(O_RDWR | O_NOCTTY);
    if (master_ >= 0 && grantpt(master_) == 0 && unlockpt(master_) == 0) {
      slavePath_ = ptsname(master_);
    }
  }
  ~PtyPair() {
    if (master_ >= 0) {
      ::close(master_);
    }
  }
  bool ok() const { return !slavePath_.empty(); }
  const std::string& slavePath() const { return slavePath_; }
  void write(const Bytes& bytes) {
    ASSERT_EQ(::write(master_, bytes.data(), bytes.size()), static_cast<ssize_t>(bytes.size()));
  }

 private:
  int master_ = -1;
  std::string slavePath_;
};

TEST(SerialPort, StreamWithACutFrameKeepsTheFollowingFrame) {
  PtyPair pty;
  ASSERT_TRUE(pty.ok());
  SerialPort port;
  std::string why;
  ASSERT_TRUE(port.open(pty.slavePath(), 57600, &why)) << why;

  Bytes stream;
  for (std::uint32_t t = 1; t <= 5; ++t) {
    const Bytes f = frameOf(t, static_cast<std::uint8_t>(t));
    stream.insert(stream.end(), f.begin(), f.end());
  }
  const Bytes cut = frameOf(77, 0);
  stream.insert(stream.end(), cut.begin(), cut.begin() + 30);  // a glitch mid-frame
  for (std::uint32_t t = 6; t <= 8; ++t) {
    const Bytes f = frameOf(t, static_cast<std::uint8_t>(t));
    stream.insert(stream.end(), f.begin(), f.end());
  }
  pty.write(stream);

  std::array<std::uint8_t, 64> scratch{};  // small on purpose: frames span reads
  mv::MavlinkParser parser;
  std::vector<std::uint32_t> times;
  for (int attempt = 0; attempt < 50 && times.size() < 8; ++attempt) {
    if (port.waitReadable(100)) {
      ASSERT_GE(drainSerial(port, parser, scratch,
                            [&times](const mv::MavlinkFrame& frame) {
                              times.push_back(
                                  std::get<mv::AttitudeQuaternion>(*mv::decode(frame)).timeBoot_ms);
                            }),
                0);
    }
  }
  EXPECT_EQ(times, (std::vector<std::uint32_t>{1, 2, 3, 4, 5, 6, 7, 8}));
  EXPECT_EQ(parser.counters().badCrc, 1u);
}

TEST(SerialPort, OpenErrorsNameTheDeviceAndTheCause) {
  SerialPort port;
  std::string why;
  EXPECT_FALSE(port.open("/dev/does-not-exist-ttyACM9", 57600, &why));
  EXPECT_NE(why.find("/dev/does-not-exist-ttyACM9"), std::string::npos) << why;
  EXPECT_FALSE(port.open("/dev/null", 57600, &why));
  EXPECT_NE(why.find("not a serial device"), std::string::npos) << why;
  EXPECT_FALSE(port.open("/dev/null", 12345, &why));
  EXPECT_NE(why.find("unsupported baud rate 12345"), std::string::npos) << why;
  EXPECT_FALSE(port.isOpen());
}

}  // namespace
}  // namespace vp::platform::mavlink
