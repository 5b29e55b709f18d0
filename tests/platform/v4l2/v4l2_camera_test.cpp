// V4l2Camera against the emulated driver: negotiation, the buffer protocol, timestamps,
// conversion, clean stop, hot-unplug recovery, and no allocation while streaming.
#include <gtest/gtest.h>

#include <linux/videodev2.h>

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "alloc_counter.hpp"
#include "core/frame_pool.hpp"
#include "fake_v4l2_device.hpp"
#include "platform/clock/monotonic_clock.hpp"
#include "platform/v4l2/v4l2_camera.hpp"

namespace vp::platform::v4l2 {
namespace {

using test::FakeFrame;
using test::FakeNodeSpec;
using test::FakeV4l2Device;

constexpr int kWidth = 64;
constexpr int kHeight = 48;
constexpr std::int64_t kStart_ns = 5'000'000'000;

FakeNodeSpec node(std::vector<std::uint32_t> formats, std::string path = "/dev/video0") {
  FakeNodeSpec spec;
  spec.path = std::move(path);
  spec.formats = std::move(formats);
  spec.width_px = kWidth;
  spec.height_px = kHeight;
  return spec;
}

V4l2CameraConfig config(std::string path = "/dev/video0") {
  V4l2CameraConfig c;
  c.devicePath = std::move(path);
  c.width_px = kWidth;
  c.height_px = kHeight;
  return c;
}

// A YUYV image with `stride` bytes per line (random content, seeded).
std::vector<std::uint8_t> yuyvBytes(int seed, std::size_t stride = kWidth * 2) {
  cv::Mat bytes(kHeight, static_cast<int>(stride), CV_8UC1);
  cv::RNG rng(static_cast<std::uint64_t>(seed));
  rng.fill(bytes, cv::RNG::UNIFORM, 0, 256);
  return std::vector<std::uint8_t>(bytes.datastart, bytes.dataend);
}

cv::Mat expectedFromYuyv(const std::vector<std::uint8_t>& bytes, std::size_t stride) {
  cv::Mat padded(kHeight, static_cast<int>(stride), CV_8UC1,
                 const_cast<std::uint8_t*>(bytes.data()));
  cv::Mat bgr;
  cv::cvtColor(padded.colRange(0, kWidth * 2).clone().reshape(2), bgr, cv::COLOR_YUV2BGR_YUYV);
  return bgr;
}

double maxDifference(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  double worst = 0.0;
  cv::minMaxLoc(diff.reshape(1), nullptr, &worst);
  return worst;
}

class V4l2CameraTest : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(pool.init(2, kWidth, kHeight)); }
  Frame& frame() { return pool.frame(0); }

  ManualClock clock{kStart_ns};
  FakeV4l2Device device{&clock};
  FramePool pool;
};

TEST_F(V4l2CameraTest, OpenNegotiatesMapsAndQueuesEveryBuffer) {
  device.addNode(node({V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_MJPEG}));
  V4l2Camera camera(device, clock);
  std::string why;
  ASSERT_TRUE(camera.open(config(), &why)) << why;
  EXPECT_EQ(camera.format().format, PixelFormat::Yuyv);
  EXPECT_EQ(camera.format().width_px, kWidth);
  EXPECT_EQ(camera.format().height_px, kHeight);
  EXPECT_EQ(camera.format().bytesPerLine, kWidth * 2u);
  EXPECT_EQ(camera.format().bufferCount, 4u);
  EXPECT_EQ(camera.format().driver, "fakecam");
  EXPECT_EQ(device.queuedBuffers("/dev/video0"), 4u);
  EXPECT_EQ(device.mappedBuffers(), 4);
  EXPECT_TRUE(device.streaming("/dev/video0"));
  const std::vector<std::string> expected{"QUERYCAP", "S_FMT",    "G_FMT",    "REQBUFS", "QUERYBUF",
                                          "QUERYBUF", "QUERYBUF", "QUERYBUF", "QBUF",    "QBUF",
                                          "QBUF",     "QBUF",     "STREAMON"};
  EXPECT_EQ(device.calls(), expected);
  EXPECT_TRUE(device.violations().empty()) << device.violations().front();
}

TEST_F(V4l2CameraTest, FormatFallsBackWhenTheDriverSubstitutes) {
  // The driver knows NV12 and MJPEG; asked for YUYV it silently sets its default (MJPEG).
  device.addNode(node({V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_NV12}));
  V4l2Camera camera(device, clock);
  std::string why;
  ASSERT_TRUE(camera.open(config(), &why)) << why;
  EXPECT_EQ(camera.format().format, PixelFormat::Nv12);
  EXPECT_EQ(camera.format().bytesPerLine, static_cast<std::uint32_t>(kWidth));
}

TEST_F(V4l2CameraTest, NoAcceptableFormatOrSizeIsAClearError) {
  device.addNode(node({V4L2_PIX_FMT_MJPEG}));
  V4l2Camera camera(device, clock);
  V4l2CameraConfig c = config();
  c.preferredFormats = {PixelFormat::Yuyv, PixelFormat::Nv12};
  std::string why;
  EXPECT_FALSE(camera.open(c, &why));
  EXPECT_NE(why.find("/dev/video0"), std::string::npos) << why;
  EXPECT_NE(why.find("YUYV: driver set MJPG 64x48"), std::string::npos) << why;
  EXPECT_NE(why.find("NV12: driver set MJPG 64x48"), std::string::npos) << why;

  c.preferredFormats = {PixelFormat::Mjpeg};
  c.width_px = 1920;
  c.height_px = 1080;
  EXPECT_FALSE(camera.open(c, &why));
  EXPECT_NE(why.find("no preferred format at 1920x1080"), std::string::npos) << why;
  EXPECT_NE(why.find("64x48"), std::string::npos) << why;
  // Nothing stays open after a failed open.
  EXPECT_EQ(device.openDescriptors(), 0);
  EXPECT_EQ(device.mappedBuffers(), 0);
  EXPECT_EQ(device.allocatedBuffers("/dev/video0"), 0u);
}

TEST_F(V4l2CameraTest, BadConfigurationAndMissingDeviceAreNamed) {
  V4l2Camera camera(device, clock);
  std::string why;
  V4l2CameraConfig c = config("/dev/video7");
  EXPECT_FALSE(camera.open(c, &why));
  EXPECT_NE(why.find("/dev/video7: open:"), std::string::npos) << why;
  c.bufferCount = 1;
  EXPECT_FALSE(camera.open(c, &why));
  EXPECT_NE(why.find("buffer count 1"), std::string::npos) << why;
  device.addNode(node({V4L2_PIX_FMT_YUYV}));
  FakeNodeSpec metadata = node({V4L2_PIX_FMT_YUYV}, "/dev/video1");
  metadata.capture = false;
  device.addNode(metadata);
  EXPECT_FALSE(camera.open(config("/dev/video1"), &why));
  EXPECT_NE(why.find("not a single-planar capture device"), std::string::npos) << why;
}

TEST_F(V4l2CameraTest, OpensByBusInfoSkippingTheMetadataNode) {
  FakeNodeSpec other = node({V4L2_PIX_FMT_YUYV}, "/dev/video0");
  other.busInfo = "usb-0000:00:14.0-1";
  FakeNodeSpec metadata = node({V4L2_PIX_FMT_YUYV}, "/dev/video2");
  metadata.busInfo = "usb-0000:00:14.0-3";
  metadata.capture = false;
  FakeNodeSpec wanted = node({V4L2_PIX_FMT_YUYV}, "/dev/video3");
  wanted.busInfo = "usb-0000:00:14.0-3";
  device.addNode(other);
  device.addNode(metadata);
  device.addNode(wanted);
  V4l2Camera camera(device, clock);
  V4l2CameraConfig c = config("");
  c.busInfo = "usb-0000:00:14.0-3";
  std::string why;
  ASSERT_TRUE(camera.open(c, &why)) << why;
  EXPECT_EQ(camera.format().path, "/dev/video3");
  EXPECT_EQ(device.openDescriptors(), 1);  // the scan closed what it probed
  camera.close();

  c.busInfo = "usb-0000:00:14.0-9";
  EXPECT_FALSE(camera.open(c, &why));
  EXPECT_NE(why.find("no capture device with bus_info 'usb-0000:00:14.0-9'"), std::string::npos)
      << why;
  EXPECT_NE(why.find("/dev/video2 'usb-0000:00:14.0-3' (no capture)"), std::string::npos) << why;
}

TEST_F(V4l2CameraTest, DequeueRequeueCycleDeliversConvertedStampedFrames) {
  FakeNodeSpec spec = node({V4L2_PIX_FMT_YUYV});
  spec.linePaddingBytes = 16;  // a driver with padded lines
  device.addNode(spec);
  V4l2Camera camera(device, clock);
  std::string why;
  ASSERT_TRUE(camera.open(config(), &why)) << why;
  const std::size_t stride = kWidth * 2 + 16;
  std::vector<std::vector<std::uint8_t>> images;
  for (int i = 0; i < 10; ++i) {
    images.push_back(yuyvBytes(i, stride));
    device.pushFrame("/dev/video0", FakeFrame{images.back(), kStart_ns + i * 100'000'000, false});
  }
  for (int i = 0; i < 10; ++i) {
    ASSERT_EQ(camera.capture(frame()), CaptureStatus::Frame) << camera.lastError();
    EXPECT_EQ(frame().frameId, i);
    EXPECT_EQ(frame().timestamp_ns, kStart_ns + i * 100'000'000);
    EXPECT_EQ(frame().status, FrameStatus::Ok);
    EXPECT_LE(maxDifference(frame().image, expectedFromYuyv(images[i], stride)), 1.0);
    EXPECT_EQ(device.queuedBuffers("/dev/video0"), 4u);  // handed straight back
  }
  EXPECT_EQ(camera.capture(frame()), CaptureStatus::Timeout);
  EXPECT_EQ(device.dequeuedIndices(),
            (std::vector<unsigned>{0, 1, 2, 3, 0, 1, 2, 3, 0, 1}));  // queue order
  EXPECT_EQ(camera.counters().frames, 10u);
  EXPECT_EQ(camera.counters().timeouts, 1u);
  EXPECT_EQ(camera.counters().stampedAtDequeue, 0u);
  EXPECT_TRUE(device.violations().empty()) << device.violations().front();
}

TEST_F(V4l2CameraTest, Nv12FramesMatchCvtColor) {
  device.addNode(node({V4L2_PIX_FMT_NV12}));
  V4l2Camera camera(device, clock);
  std::string why;
  ASSERT_TRUE(camera.open(config(), &why)) << why;
  cv::Mat nv12(kHeight * 3 / 2, kWidth, CV_8UC1);
  cv::RNG rng(9);
  rng.fill(nv12, cv::RNG::UNIFORM, 0, 256);
  device.pushFrame("/dev/video0",
                   FakeFrame{std::vector<std::uint8_t>(nv12.datastart, nv12.dataend), 1, false});
  ASSERT_EQ(camera.capture(frame()), CaptureStatus::Frame) << camera.lastError();
  cv::Mat expected;
  cv::cvtColor(nv12, expected, cv::COLOR_YUV2BGR_NV12);
  EXPECT_LE(maxDifference(frame().image, expected), 1.0);
}

TEST_F(V4l2CameraTest, DriverFlagsAndClocksAreHonoured) {
  FakeNodeSpec spec = node({V4L2_PIX_FMT_YUYV});
  spec.monotonicTimestamps = false;  // e.g. a driver stamping with an unknown clock
  device.addNode(spec);
  V4l2Camera camera(device, clock);
  std::string why;
  ASSERT_TRUE(camera.open(config(), &why)) << why;
  device.pushFrame("/dev/video0", FakeFrame{yuyvBytes(1), 42, true});
  ASSERT_EQ(camera.capture(frame()), CaptureStatus::Frame);
  EXPECT_EQ(frame().status, FrameStatus::Damaged);
  EXPECT_EQ(frame().timestamp_ns, clock.now_ns());  // stamped at dequeue, not 42
  EXPECT_EQ(camera.counters().damagedFrames, 1u);
  EXPECT_EQ(camera.counters().stampedAtDequeue, 1u);
}

TEST_F(V4l2CameraTest, ShortBufferAndWrongOutputAreFrameErrorsAndTheStreamGoesOn) {
  device.addNode(node({V4L2_PIX_FMT_YUYV}));
  V4l2Camera camera(device, clock);
  std::string why;
  ASSERT_TRUE(camera.open(config(), &why)) << why;
  std::vector<std::uint8_t> shortImage = yuyvBytes(1);
  shortImage.resize(shortImage.size() / 2);
  device.pushFrame("/dev/video0", FakeFrame{shortImage, 1, false});
  EXPECT_EQ(camera.capture(frame()), CaptureStatus::Error);
  EXPECT_NE(std::string(camera.lastError()).find("short YUYV buffer"), std::string::npos);
  device.pushFrame("/dev/video0", FakeFrame{yuyvBytes(2), 2, false});
  Frame wrong;
  wrong.image.create(10, 10, CV_8UC3);
  EXPECT_EQ(camera.capture(wrong), CaptureStatus::Error);
  EXPECT_NE(std::string(camera.lastError()).find("output frame is 10x10"), std::string::npos);
  EXPECT_EQ(wrong.image.cols, 10);  // never reallocated
  device.pushFrame("/dev/video0", FakeFrame{yuyvBytes(3), 3, false});
  EXPECT_EQ(camera.capture(frame()), CaptureStatus::Frame);
  EXPECT_EQ(camera.counters().frameErrors, 2u);
  EXPECT_EQ(device.queuedBuffers("/dev/video0"), 4u);  // every buffer went back
}

TEST_F(V4l2CameraTest, MjpegFramesDecodeAndCorruptOnesAreErrors) {
  device.addNode(node({V4L2_PIX_FMT_MJPEG}));
  V4l2Camera camera(device, clock);
  std::string why;
  ASSERT_TRUE(camera.open(config(), &why)) << why;
  EXPECT_EQ(camera.format().format, PixelFormat::Mjpeg);
  cv::Mat source(kHeight, kWidth, CV_8UC3);
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      source.at<cv::Vec3b>(v, u) = cv::Vec3b(static_cast<uchar>(4 * u), static_cast<uchar>(5 * v),
                                             static_cast<uchar>(2 * (u + v)));
    }
  }
  std::vector<std::uint8_t> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", source, jpeg, {cv::IMWRITE_JPEG_QUALITY, 95}));
  device.pushFrame("/dev/video0", FakeFrame{jpeg, 1, false});
  const uchar* before = frame().image.data;
  ASSERT_EQ(camera.capture(frame()), CaptureStatus::Frame) << camera.lastError();
  EXPECT_EQ(frame().image.data, before);
  EXPECT_LT(cv::norm(frame().image, source, cv::NORM_L1) / source.total() / 3, 3.0);
  device.pushFrame("/dev/video0", FakeFrame{std::vector<std::uint8_t>(100, 0x42), 2, false});
  EXPECT_EQ(camera.capture(frame()), CaptureStatus::Error);
  EXPECT_NE(std::string(camera.lastError()).find("MJPEG"), std::string::npos);
}

TEST_F(V4l2CameraTest, StopReturnsEveryBufferAndClosesTheDevice) {
  device.addNode(node({V4L2_PIX_FMT_YUYV}));
  {
    V4l2Camera camera(device, clock);
    std::string why;
    ASSERT_TRUE(camera.open(config(), &why)) << why;
    for (int i = 0; i < 3; ++i) {
      device.pushFrame("/dev/video0", FakeFrame{yuyvBytes(i), i, false});
      ASSERT_EQ(camera.capture(frame()), CaptureStatus::Frame);
    }
    device.clearCalls();
    camera.close();
    EXPECT_EQ(device.calls(), (std::vector<std::string>{"STREAMOFF", "REQBUFS"}));
    EXPECT_FALSE(camera.isStreaming());
    EXPECT_EQ(device.openDescriptors(), 0);
    EXPECT_EQ(device.mappedBuffers(), 0);
    EXPECT_EQ(device.allocatedBuffers("/dev/video0"), 0u);

    ASSERT_TRUE(camera.open(config(), &why)) << why;  // and again, then the destructor
  }
  EXPECT_EQ(device.openDescriptors(), 0);
  EXPECT_EQ(device.mappedBuffers(), 0);
  EXPECT_EQ(device.allocatedBuffers("/dev/video0"), 0u);
  EXPECT_TRUE(device.violations().empty()) << device.violations().front();
}

TEST_F(V4l2CameraTest, UnpluggedDeviceIsReleasedAndReopenedWithBackoff) {
  device.addNode(node({V4L2_PIX_FMT_YUYV}));
  V4l2Camera camera(device, clock);
  V4l2CameraConfig c = config();
  c.reopenInitialBackoff_ms = 100;
  c.reopenMaxBackoff_ms = 400;
  c.dequeueTimeout_ms = 1000;
  std::string why;
  ASSERT_TRUE(camera.open(c, &why)) << why;
  for (int i = 0; i < 5; ++i) {
    device.pushFrame("/dev/video0", FakeFrame{yuyvBytes(i), i, false});
    ASSERT_EQ(camera.capture(frame()), CaptureStatus::Frame);
  }
  EXPECT_EQ(frame().frameId, 4);

  device.unplug("/dev/video0");
  const std::int64_t lostAt = clock.now_ns();
  EXPECT_EQ(camera.capture(frame()), CaptureStatus::DeviceLost);
  EXPECT_NE(std::string(camera.lastError()).find("device lost"), std::string::npos);
  EXPECT_EQ(camera.counters().deviceLosses, 1u);
  const int descriptorsAfterLoss = device.openDescriptors();
  const int mappingsAfterLoss = device.mappedBuffers();
  EXPECT_EQ(descriptorsAfterLoss, 0);  // released at once
  EXPECT_EQ(mappingsAfterLoss, 0);

  // Attempts at +100 ms, then 200, 400, 400 ms apart (doubling, capped).
  std::vector<std::int64_t> attempts_ms;
  for (int call = 0; call < 12 && attempts_ms.size() < 4; ++call) {
    const std::uint64_t before = camera.counters().reopenAttempts;
    EXPECT_EQ(camera.capture(frame()), CaptureStatus::DeviceLost);
    if (camera.counters().reopenAttempts > before) {
      attempts_ms.push_back((clock.now_ns() - lostAt) / 1'000'000);
    }
  }
  ASSERT_EQ(attempts_ms, (std::vector<std::int64_t>{100, 300, 700, 1100}));

  device.replug("/dev/video0");
  CaptureStatus status = CaptureStatus::DeviceLost;
  for (int call = 0; call < 5 && status == CaptureStatus::DeviceLost; ++call) {
    status = camera.capture(frame());
  }
  ASSERT_EQ(status, CaptureStatus::Reopened) << camera.lastError();
  const std::int64_t reopenedAfter_ms = (clock.now_ns() - lostAt) / 1'000'000;
  EXPECT_EQ(camera.counters().reopens, 1u);
  EXPECT_EQ(camera.counters().reopenAttempts, 5u);
  std::printf(
      "unplug: device released at once (%d descriptors, %d mappings left); failed reopen "
      "attempts at %lld, %lld, %lld, %lld ms; reopened at attempt %llu, %lld ms after the loss "
      "(fake clock; backoff %d ms doubling to %d ms)\n",
      descriptorsAfterLoss, mappingsAfterLoss, static_cast<long long>(attempts_ms[0]),
      static_cast<long long>(attempts_ms[1]), static_cast<long long>(attempts_ms[2]),
      static_cast<long long>(attempts_ms[3]),
      static_cast<unsigned long long>(camera.counters().reopenAttempts),
      static_cast<long long>(reopenedAfter_ms), c.reopenInitialBackoff_ms, c.reopenMaxBackoff_ms);
  EXPECT_EQ(device.queuedBuffers("/dev/video0"), 4u);
  device.pushFrame("/dev/video0", FakeFrame{yuyvBytes(9), 9, false});
  ASSERT_EQ(camera.capture(frame()), CaptureStatus::Frame);
  EXPECT_EQ(frame().frameId, 5);  // ids keep increasing across the reopen
  camera.close();
  EXPECT_EQ(device.mappedBuffers(), 0);
  EXPECT_EQ(device.openDescriptors(), 0);
  EXPECT_TRUE(device.violations().empty()) << device.violations().front();
}

TEST_F(V4l2CameraTest, SteadyStateCaptureAllocatesNothing) {
  for (const std::uint32_t fourccCode : {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_NV12}) {
    FakeV4l2Device fake(&clock);
    fake.addNode(node({fourccCode}));
    V4l2Camera camera(fake, clock);
    std::string why;
    ASSERT_TRUE(camera.open(config(), &why)) << why;
    const std::vector<std::uint8_t> bytes(kWidth * kHeight * 2, 100);
    for (int i = 0; i < 20; ++i) {
      fake.pushFrame("/dev/video0", FakeFrame{bytes, i, false});
    }
    ASSERT_EQ(camera.capture(frame()), CaptureStatus::Frame);  // warm-up
    test::AllocationCounter counter;
    for (int i = 1; i < 20; ++i) {
      ASSERT_EQ(camera.capture(frame()), CaptureStatus::Frame);
    }
    counter.stop();
    EXPECT_EQ(counter.count(), 0u) << "fourcc " << fourccCode;
  }
}

}  // namespace
}  // namespace vp::platform::v4l2
