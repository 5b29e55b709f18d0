#include "platform/v4l2/v4l2_camera.hpp"

#include <linux/videodev2.h>
#include <poll.h>

#include <algorithm>
#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstring>

#include <opencv2/imgcodecs.hpp>

#include "platform/v4l2/yuv_to_bgr.hpp"

namespace vp::platform::v4l2 {
namespace {

constexpr std::int64_t kNsPer_ms = 1'000'000;
constexpr std::int64_t kNsPer_us = 1'000;

std::string errorText(int error) {
  return std::strerror(error);
}

std::string fourccText(std::uint32_t code) {
  std::string text(4, ' ');
  for (int i = 0; i < 4; ++i) {
    text[static_cast<std::size_t>(i)] = static_cast<char>((code >> (8 * i)) & 0xFF);
  }
  return text;
}

std::string cString(const __u8* bytes, std::size_t size) {
  const auto* chars = reinterpret_cast<const char*>(bytes);
  return std::string(chars, strnlen(chars, size));
}

// Capabilities of the opened node (device_caps when the driver reports per-node caps).
std::uint32_t nodeCaps(const v4l2_capability& caps) {
  return (caps.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? caps.device_caps : caps.capabilities;
}

bool failWith(std::string* why, std::string message) {
  if (why != nullptr) {
    *why = std::move(message);
  }
  return false;
}

}  // namespace

std::uint32_t fourcc(PixelFormat format) {
  switch (format) {
    case PixelFormat::Yuyv:
      return V4L2_PIX_FMT_YUYV;
    case PixelFormat::Nv12:
      return V4L2_PIX_FMT_NV12;
    case PixelFormat::Mjpeg:
      return V4L2_PIX_FMT_MJPEG;
  }
  return 0;
}

const char* toString(PixelFormat format) {
  switch (format) {
    case PixelFormat::Yuyv:
      return "YUYV";
    case PixelFormat::Nv12:
      return "NV12";
    case PixelFormat::Mjpeg:
      return "MJPEG";
  }
  return "?";
}

const char* toString(CaptureStatus status) {
  switch (status) {
    case CaptureStatus::Frame:
      return "frame";
    case CaptureStatus::Timeout:
      return "timeout";
    case CaptureStatus::DeviceLost:
      return "device lost";
    case CaptureStatus::Reopened:
      return "reopened";
    case CaptureStatus::Error:
      return "error";
  }
  return "?";
}

void V4l2Camera::setError(const char* format, ...) {
  va_list args;
  va_start(args, format);
  std::vsnprintf(lastError_.data(), lastError_.size(), format, args);
  va_end(args);
}

bool V4l2Camera::open(const V4l2CameraConfig& config, std::string* why) {
  close();
  const std::string who =
      config.devicePath.empty() ? "v4l2 bus '" + config.busInfo + "'" : "v4l2 " + config.devicePath;
  if (config.devicePath.empty() && config.busInfo.empty()) {
    return failWith(why, "v4l2: neither a device path nor a bus_info to find the camera by");
  }
  if (config.width_px <= 0 || config.height_px <= 0) {
    return failWith(why, who + ": frame size " + std::to_string(config.width_px) + "x" +
                             std::to_string(config.height_px) + " must be positive");
  }
  if (config.bufferCount < 2 || config.bufferCount > kMaxBuffers) {
    return failWith(why, who + ": buffer count " + std::to_string(config.bufferCount) +
                             " outside 2.." + std::to_string(kMaxBuffers));
  }
  if (config.preferredFormats.empty()) {
    return failWith(why, who + ": no preferred pixel format");
  }
  if (config.dequeueTimeout_ms < 0 || config.reopenInitialBackoff_ms <= 0 ||
      config.reopenMaxBackoff_ms < config.reopenInitialBackoff_ms) {
    return failWith(why, who + ": timeouts must be >= 0 and 0 < initial backoff <= max backoff");
  }
  config_ = config;
  counters_ = CameraCounters{};
  frameIdBase_ = 0;
  nextFrameId_ = 0;
  lost_ = false;
  return openAndStream(why);
}

bool V4l2Camera::findDevice(std::string* path, std::string* why) {
  if (!config_.devicePath.empty()) {
    *path = config_.devicePath;
    return true;
  }
  std::string seen;
  for (const std::string& node : device_.listVideoNodes()) {
    const int fd = device_.open(node.c_str());
    if (fd < 0) {
      seen += " " + node + " (" + errorText(-fd) + ")";
      continue;
    }
    v4l2_capability caps{};
    const int rc = device_.ioctl(fd, VIDIOC_QUERYCAP, &caps);
    device_.close(fd);
    if (rc < 0) {
      seen += " " + node + " (QUERYCAP: " + errorText(-rc) + ")";
      continue;
    }
    const std::string bus = cString(caps.bus_info, sizeof(caps.bus_info));
    const bool capture = (nodeCaps(caps) & V4L2_CAP_VIDEO_CAPTURE) != 0;
    seen += " " + node + " '" + bus + "'" + (capture ? "" : " (no capture)");
    // A UVC camera has a metadata node with the same bus_info: only a capture node matches.
    if (bus == config_.busInfo && capture) {
      *path = node;
      return true;
    }
  }
  return failWith(why, "v4l2: no capture device with bus_info '" + config_.busInfo +
                           "'; seen:" + (seen.empty() ? std::string(" none") : seen));
}

bool V4l2Camera::openAndStream(std::string* why) {
  std::string path;
  if (!findDevice(&path, why)) {
    return false;
  }
  const int fd = device_.open(path.c_str());
  if (fd < 0) {
    return failWith(why, "v4l2 " + path + ": open: " + errorText(-fd));
  }
  fd_ = fd;
  v4l2_capability caps{};
  int rc = device_.ioctl(fd_, VIDIOC_QUERYCAP, &caps);
  if (rc < 0) {
    release();
    return failWith(
        why, "v4l2 " + path + ": VIDIOC_QUERYCAP: " + errorText(-rc) + " (not a V4L2 device?)");
  }
  const std::uint32_t nodeCapabilities = nodeCaps(caps);
  if ((nodeCapabilities & V4L2_CAP_VIDEO_CAPTURE) == 0 ||
      (nodeCapabilities & V4L2_CAP_STREAMING) == 0) {
    release();
    return failWith(why,
                    "v4l2 " + path + ": not a single-planar capture device with streaming I/O");
  }
  format_ = NegotiatedFormat{};
  format_.path = path;
  format_.driver = cString(caps.driver, sizeof(caps.driver));
  format_.card = cString(caps.card, sizeof(caps.card));
  format_.busInfo = cString(caps.bus_info, sizeof(caps.bus_info));
  if (!negotiate(path, why) || !mapAndQueueBuffers(path, why)) {
    release();
    return false;
  }
  frameIdBase_ = nextFrameId_;
  return true;
}

bool V4l2Camera::negotiate(const std::string& path, std::string* why) {
  std::string tried;
  for (const PixelFormat wanted : config_.preferredFormats) {
    v4l2_format format{};
    format.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    format.fmt.pix.width = static_cast<__u32>(config_.width_px);
    format.fmt.pix.height = static_cast<__u32>(config_.height_px);
    format.fmt.pix.pixelformat = fourcc(wanted);
    format.fmt.pix.field = V4L2_FIELD_NONE;
    int rc = device_.ioctl(fd_, VIDIOC_S_FMT, &format);
    if (rc == -EBUSY) {
      return failWith(why,
                      "v4l2 " + path + ": VIDIOC_S_FMT: device busy (used by another program?)");
    }
    if (rc < 0) {
      tried += std::string(" ") + toString(wanted) + ": S_FMT " + errorText(-rc) + ";";
      continue;
    }
    // Read back what the driver really set: S_FMT adjusts instead of failing.
    v4l2_format actual{};
    actual.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    rc = device_.ioctl(fd_, VIDIOC_G_FMT, &actual);
    if (rc < 0) {
      return failWith(why, "v4l2 " + path + ": VIDIOC_G_FMT: " + errorText(-rc));
    }
    const v4l2_pix_format& pix = actual.fmt.pix;
    // (S_FMT wrote the driver's choice back into `format`: compare with the configuration.)
    if (pix.pixelformat != fourcc(wanted) || static_cast<int>(pix.width) != config_.width_px ||
        static_cast<int>(pix.height) != config_.height_px) {
      tried += std::string(" ") + toString(wanted) + ": driver set " + fourccText(pix.pixelformat) +
               " " + std::to_string(pix.width) + "x" + std::to_string(pix.height) + ";";
      continue;
    }
    const std::uint32_t minLine =
        wanted == PixelFormat::Yuyv ? pix.width * 2 : (wanted == PixelFormat::Nv12 ? pix.width : 0);
    format_.format = wanted;
    format_.width_px = static_cast<int>(pix.width);
    format_.height_px = static_cast<int>(pix.height);
    format_.bytesPerLine = std::max(pix.bytesperline, minLine);
    format_.sizeImage = pix.sizeimage;
    return true;
  }
  return failWith(why, "v4l2 " + path + ": no preferred format at " +
                           std::to_string(config_.width_px) + "x" +
                           std::to_string(config_.height_px) + ":" + tried);
}

bool V4l2Camera::mapAndQueueBuffers(const std::string& path, std::string* why) {
  v4l2_requestbuffers request{};
  request.count = config_.bufferCount;
  request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  request.memory = V4L2_MEMORY_MMAP;
  int rc = device_.ioctl(fd_, VIDIOC_REQBUFS, &request);
  if (rc < 0) {
    return failWith(why, "v4l2 " + path + ": VIDIOC_REQBUFS: " + errorText(-rc));
  }
  if (request.count < 2 || request.count > kMaxBuffers) {
    bufferCount_ = request.count;  // so that release() frees them
    return failWith(why, "v4l2 " + path + ": driver granted " + std::to_string(request.count) +
                             " buffers, need 2.." + std::to_string(kMaxBuffers));
  }
  bufferCount_ = request.count;
  format_.bufferCount = request.count;
  for (unsigned i = 0; i < bufferCount_; ++i) {
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    buffer.index = i;
    rc = device_.ioctl(fd_, VIDIOC_QUERYBUF, &buffer);
    if (rc < 0) {
      return failWith(
          why, "v4l2 " + path + ": VIDIOC_QUERYBUF " + std::to_string(i) + ": " + errorText(-rc));
    }
    int error = 0;
    void* start = device_.mmap(fd_, buffer.length, buffer.m.offset, &error);
    if (start == nullptr) {
      return failWith(
          why, "v4l2 " + path + ": mmap buffer " + std::to_string(i) + ": " + errorText(error));
    }
    buffers_[i] = MappedBuffer{start, buffer.length};
  }
  for (unsigned i = 0; i < bufferCount_; ++i) {
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    buffer.index = i;
    rc = device_.ioctl(fd_, VIDIOC_QBUF, &buffer);
    if (rc < 0) {
      return failWith(
          why, "v4l2 " + path + ": VIDIOC_QBUF " + std::to_string(i) + ": " + errorText(-rc));
    }
  }
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  rc = device_.ioctl(fd_, VIDIOC_STREAMON, &type);
  if (rc < 0) {
    return failWith(why, "v4l2 " + path + ": VIDIOC_STREAMON: " + errorText(-rc));
  }
  return true;
}

void V4l2Camera::release() {
  if (fd_ < 0) {
    return;
  }
  // STREAMOFF takes every buffer back from the driver (queued or done), then they are unmapped
  // and freed; errors are ignored because this also runs when the device has vanished.
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  device_.ioctl(fd_, VIDIOC_STREAMOFF, &type);
  for (unsigned i = 0; i < bufferCount_ && i < kMaxBuffers; ++i) {
    if (buffers_[i].start != nullptr) {
      device_.munmap(buffers_[i].start, buffers_[i].length);
      buffers_[i] = MappedBuffer{};
    }
  }
  if (bufferCount_ > 0) {
    v4l2_requestbuffers request{};
    request.count = 0;
    request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    request.memory = V4L2_MEMORY_MMAP;
    device_.ioctl(fd_, VIDIOC_REQBUFS, &request);
  }
  bufferCount_ = 0;
  device_.close(fd_);
  fd_ = -1;
}

void V4l2Camera::close() {
  release();
  lost_ = false;
}

CaptureStatus V4l2Camera::loseDevice(int error, const char* where) {
  setError("v4l2 %s: %s: %s (device lost, reopening)", format_.path.c_str(), where,
           std::strerror(error));
  release();
  lost_ = true;
  ++counters_.deviceLosses;
  backoffNs_ = config_.reopenInitialBackoff_ms * kNsPer_ms;
  nextReopenNs_ = clock_.now_ns() + backoffNs_;
  return CaptureStatus::DeviceLost;
}

CaptureStatus V4l2Camera::tryReopen() {
  std::int64_t now = clock_.now_ns();
  if (now < nextReopenNs_) {
    clock_.sleepUntil_ns(std::min(nextReopenNs_, now + config_.dequeueTimeout_ms * kNsPer_ms));
    now = clock_.now_ns();
    if (now < nextReopenNs_) {
      return CaptureStatus::DeviceLost;
    }
  }
  ++counters_.reopenAttempts;
  std::string why;  // the reopen path may allocate (device scan, messages); steady state never
  if (openAndStream(&why)) {
    lost_ = false;
    ++counters_.reopens;
    return CaptureStatus::Reopened;
  }
  setError("%s", why.c_str());
  backoffNs_ = std::min(2 * backoffNs_, config_.reopenMaxBackoff_ms * kNsPer_ms);
  nextReopenNs_ = now + backoffNs_;
  return CaptureStatus::DeviceLost;
}

CaptureStatus V4l2Camera::capture(Frame& out) {
  if (lost_) {
    return tryReopen();
  }
  if (fd_ < 0) {
    setError("v4l2: capture() on a camera that is not open");
    return CaptureStatus::Error;
  }
  short revents = 0;
  int rc = device_.poll(fd_, config_.dequeueTimeout_ms, &revents);
  if (rc < 0) {
    return loseDevice(-rc, "poll");
  }
  if (rc == 0) {
    ++counters_.timeouts;
    return CaptureStatus::Timeout;
  }
  const bool pollError = (revents & (POLLERR | POLLHUP | POLLNVAL)) != 0;
  v4l2_buffer buffer{};
  buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buffer.memory = V4L2_MEMORY_MMAP;
  rc = device_.ioctl(fd_, VIDIOC_DQBUF, &buffer);
  if (rc < 0) {
    if (rc == -EAGAIN && !pollError) {
      ++counters_.timeouts;
      return CaptureStatus::Timeout;
    }
    return loseDevice(rc == -EAGAIN ? EIO : -rc,
                      pollError ? "poll error, VIDIOC_DQBUF" : "VIDIOC_DQBUF");
  }
  if (buffer.index >= bufferCount_) {
    setError("v4l2 %s: VIDIOC_DQBUF returned buffer %u of %u", format_.path.c_str(), buffer.index,
             bufferCount_);
    ++counters_.frameErrors;
    return CaptureStatus::Error;
  }

  const bool converted = convert(buffers_[buffer.index], buffer.bytesused, out);
  if (converted) {
    if ((buffer.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC) {
      out.timestamp_ns = static_cast<std::int64_t>(buffer.timestamp.tv_sec) * kNsPerSecond +
                         static_cast<std::int64_t>(buffer.timestamp.tv_usec) * kNsPer_us;
    } else {
      out.timestamp_ns = clock_.now_ns();
      ++counters_.stampedAtDequeue;
    }
    out.frameId = frameIdBase_ + buffer.sequence;
    nextFrameId_ = out.frameId + 1;
    out.status = (buffer.flags & V4L2_BUF_FLAG_ERROR) != 0 ? FrameStatus::Damaged : FrameStatus::Ok;
    if (out.status == FrameStatus::Damaged) {
      ++counters_.damagedFrames;
    }
    ++counters_.frames;
  } else {
    ++counters_.frameErrors;
  }
  // The buffer goes back to the driver whatever happened to its content.
  rc = device_.ioctl(fd_, VIDIOC_QBUF, &buffer);
  if (rc < 0) {
    const CaptureStatus lost = loseDevice(-rc, "VIDIOC_QBUF");
    if (!converted) {
      return lost;
    }
  }
  return converted ? CaptureStatus::Frame : CaptureStatus::Error;
}

bool V4l2Camera::convert(const MappedBuffer& buffer, std::uint32_t bytesUsed, Frame& out) {
  const int width = format_.width_px;
  const int height = format_.height_px;
  if (out.image.type() != CV_8UC3 || out.image.cols != width || out.image.rows != height) {
    setError("v4l2 %s: output frame is %dx%d type %d, camera gives %dx%d BGR8",
             format_.path.c_str(), out.image.cols, out.image.rows, out.image.type(), width, height);
    return false;
  }
  const auto* bytes = static_cast<const std::uint8_t*>(buffer.start);
  const std::size_t used = std::min<std::size_t>(bytesUsed, buffer.length);
  const std::size_t line = format_.bytesPerLine;
  switch (format_.format) {
    case PixelFormat::Yuyv: {
      const std::size_t need = line * static_cast<std::size_t>(height);
      if (used < need) {
        setError("v4l2 %s: short YUYV buffer: %zu bytes, need %zu", format_.path.c_str(), used,
                 need);
        return false;
      }
      return yuyvToBgr(bytes, line, width, height, out.image);
    }
    case PixelFormat::Nv12: {
      const std::size_t need = line * static_cast<std::size_t>(height) * 3 / 2;
      if (used < need) {
        setError("v4l2 %s: short NV12 buffer: %zu bytes, need %zu", format_.path.c_str(), used,
                 need);
        return false;
      }
      return nv12ToBgr(bytes, line, bytes + line * static_cast<std::size_t>(height), line, width,
                       height, out.image);
    }
    case PixelFormat::Mjpeg: {
      // cv::imdecode allocates; decode into a scratch image so a wrong-size JPEG can never
      // reallocate the pool's frame.
      const cv::Mat encoded(1, static_cast<int>(used), CV_8UC1, const_cast<std::uint8_t*>(bytes));
      mjpegScratch_.release();  // a failed decode leaves the previous image otherwise
      cv::imdecode(encoded, cv::IMREAD_COLOR, &mjpegScratch_);
      if (mjpegScratch_.empty() || mjpegScratch_.cols != width || mjpegScratch_.rows != height ||
          mjpegScratch_.type() != CV_8UC3) {
        setError("v4l2 %s: MJPEG frame of %zu bytes does not decode to %dx%d BGR8",
                 format_.path.c_str(), used, width, height);
        return false;
      }
      mjpegScratch_.copyTo(out.image);
      return true;
    }
  }
  return false;
}

}  // namespace vp::platform::v4l2
