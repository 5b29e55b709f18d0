// platform/v4l2/v4l2_camera: one V4L2 capture device streaming into the app's frame pool.
//
// Contract: the constructor borrows a V4l2Device (the kernel, or an emulation in tests) and a
// Clock, and does nothing else. open() finds the device (by path, or by the bus_info its
// VIDIOC_QUERYCAP reports, scanning /dev/video*), checks it can capture and stream, negotiates
// the first of the preferred pixel formats the driver accepts at the requested size (S_FMT,
// then the format is read back: drivers substitute silently), requests and maps a fixed set of
// buffers, queues them all and starts streaming; it fails with a message naming the device,
// the step and the error. capture() waits up to the dequeue timeout (poll) for the next
// buffer, converts it into the caller's pool frame (BGR8 of the negotiated size; never
// reallocated), stamps it and queues the buffer again. close() (and the destructor) stops
// streaming, unmaps every buffer, frees them and closes the device.
//
// Real time: capture() allocates nothing for YUYV and NV12 (tests count it) and reports every
// failure as a CaptureStatus, never an exception. MJPEG decoding goes through cv::imdecode,
// which allocates per frame (libjpeg state and a scratch image): use it only when the camera
// offers nothing else at the wanted size.
//
// Timestamps: the buffer's own timestamp when the driver says it is CLOCK_MONOTONIC (the
// loop's clock); otherwise the time of the dequeue on the given clock, counted in
// counters().stampedAtDequeue. Frame ids follow the driver's sequence counter (gaps = frames
// the driver dropped) and keep increasing across reopens.
//
// Hot-unplug: ENODEV/EIO from the device or POLLERR from poll() means the device is gone.
// Everything is released at once (counted in deviceLosses) and later capture() calls try to
// reopen it with an exponential backoff (reopenAttempts, reopens); on success they return
// Reopened and streaming goes on. A reopened device must give the same frame size.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "core/frame_pool.hpp"
#include "platform/clock/monotonic_clock.hpp"
#include "platform/v4l2/v4l2_device.hpp"

namespace vp::platform::v4l2 {

enum class PixelFormat : std::uint8_t { Yuyv, Nv12, Mjpeg };
std::uint32_t fourcc(PixelFormat format);  // V4L2_PIX_FMT_*
const char* toString(PixelFormat format);

struct V4l2CameraConfig {
  std::string devicePath;  // "/dev/video0"; when empty, busInfo picks the device
  std::string busInfo;     // VIDIOC_QUERYCAP bus_info, e.g. "usb-0000:00:14.0-2"
  int width_px = FramePool::kDefaultWidth_px;
  int height_px = FramePool::kDefaultHeight_px;
  // Tried in order; the first the driver keeps (read back) at the requested size wins.
  std::vector<PixelFormat> preferredFormats{PixelFormat::Yuyv, PixelFormat::Nv12,
                                            PixelFormat::Mjpeg};
  unsigned bufferCount = 4;           // mmap buffers requested; the driver may grant 2..kMaxBuffers
  int dequeueTimeout_ms = 1000;       // longest capture() waits for a frame
  int reopenInitialBackoff_ms = 100;  // first wait after a loss, doubled per failed attempt
  int reopenMaxBackoff_ms = 5000;
};

struct NegotiatedFormat {
  PixelFormat format = PixelFormat::Yuyv;
  int width_px = 0;
  int height_px = 0;
  std::uint32_t bytesPerLine = 0;
  std::uint32_t sizeImage = 0;
  unsigned bufferCount = 0;  // granted by the driver
  std::string path;          // the node that was opened
  std::string driver, card, busInfo;
};

enum class CaptureStatus : std::uint8_t {
  Frame,       // the frame was filled
  Timeout,     // no frame within the dequeue timeout
  DeviceLost,  // the device is gone; later calls retry opening it (with backoff)
  Reopened,    // the device came back and streams again; no frame in this call
  Error,       // this frame failed (see lastError()); the stream goes on
};
const char* toString(CaptureStatus status);

struct CameraCounters {
  std::uint64_t frames = 0;
  std::uint64_t timeouts = 0;
  std::uint64_t damagedFrames = 0;     // V4L2_BUF_FLAG_ERROR, delivered as FrameStatus::Damaged
  std::uint64_t frameErrors = 0;       // short buffer, failed decode, wrong output frame
  std::uint64_t stampedAtDequeue = 0;  // driver timestamps not monotonic
  std::uint64_t deviceLosses = 0;
  std::uint64_t reopenAttempts = 0;
  std::uint64_t reopens = 0;
};

class V4l2Camera {
 public:
  static constexpr unsigned kMaxBuffers = 16;

  V4l2Camera(V4l2Device& device, Clock& clock) : device_(device), clock_(clock) {}
  ~V4l2Camera() { close(); }
  V4l2Camera(const V4l2Camera&) = delete;
  V4l2Camera& operator=(const V4l2Camera&) = delete;

  bool open(const V4l2CameraConfig& config, std::string* why);
  // The next frame into `out` (its image must be CV_8UC3 of format().width_px x height_px).
  CaptureStatus capture(Frame& out);
  void close();

  bool isStreaming() const { return fd_ >= 0; }
  const NegotiatedFormat& format() const { return format_; }
  const CameraCounters& counters() const { return counters_; }
  const char* lastError() const { return lastError_.data(); }

 private:
  struct MappedBuffer {
    void* start = nullptr;
    std::size_t length = 0;
  };

  bool openAndStream(std::string* why);
  bool findDevice(std::string* path, std::string* why);
  bool negotiate(const std::string& path, std::string* why);
  bool mapAndQueueBuffers(const std::string& path, std::string* why);
  void release();  // stop, unmap, free, close; ignores errors (the device may be gone)
  CaptureStatus loseDevice(int error, const char* where);
  CaptureStatus tryReopen();
  bool convert(const MappedBuffer& buffer, std::uint32_t bytesUsed, Frame& out);
  void setError(const char* format, ...) __attribute__((format(printf, 2, 3)));

  V4l2Device& device_;
  Clock& clock_;
  V4l2CameraConfig config_;
  NegotiatedFormat format_;
  int fd_ = -1;
  bool lost_ = false;
  std::array<MappedBuffer, kMaxBuffers> buffers_{};
  unsigned bufferCount_ = 0;
  std::int64_t frameIdBase_ = 0;  // added to the driver's sequence (it restarts at 0)
  std::int64_t nextFrameId_ = 0;  // first id the next stream may use
  std::int64_t nextReopenNs_ = 0;
  std::int64_t backoffNs_ = 0;
  cv::Mat mjpegScratch_;  // decoder output before the size check (MJPEG only)
  CameraCounters counters_{};
  std::array<char, 256> lastError_{};
};

}  // namespace vp::platform::v4l2
