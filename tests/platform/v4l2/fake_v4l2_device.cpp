#include "fake_v4l2_device.hpp"

#include <linux/videodev2.h>
#include <poll.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace vp::test {
namespace {

constexpr std::uint32_t kOffsetStride = 0x100000;  // mmap offset of buffer i: i * stride

void copyName(__u8* target, std::size_t size, const std::string& text) {
  std::memset(target, 0, size);
  std::memcpy(target, text.data(), std::min(size - 1, text.size()));
}

const char* ioctlName(unsigned long request) {
  switch (request) {
    case VIDIOC_QUERYCAP:
      return "QUERYCAP";
    case VIDIOC_S_FMT:
      return "S_FMT";
    case VIDIOC_G_FMT:
      return "G_FMT";
    case VIDIOC_REQBUFS:
      return "REQBUFS";
    case VIDIOC_QUERYBUF:
      return "QUERYBUF";
    case VIDIOC_QBUF:
      return "QBUF";
    case VIDIOC_DQBUF:
      return "DQBUF";
    case VIDIOC_STREAMON:
      return "STREAMON";
    case VIDIOC_STREAMOFF:
      return "STREAMOFF";
    default:
      return "OTHER";
  }
}

}  // namespace

void FakeV4l2Device::addNode(const FakeNodeSpec& spec) {
  specs_[spec.path] = spec;
  replug(spec.path);
}

FakeV4l2Device::Node* FakeV4l2Device::live(const std::string& path) const {
  for (const auto& node : nodes_) {
    if (!node->gone && node->spec.path == path) {
      return node.get();
    }
  }
  return nullptr;
}

void FakeV4l2Device::pushFrame(const std::string& path, FakeFrame frame) {
  if (Node* node = live(path)) {
    node->pending.push_back(std::move(frame));
  }
}

void FakeV4l2Device::unplug(const std::string& path) {
  if (Node* node = live(path)) {
    node->gone = true;
  }
}

void FakeV4l2Device::replug(const std::string& path) {
  if (live(path) != nullptr) {
    return;
  }
  auto node = std::make_unique<Node>();
  node->spec = specs_.at(path);
  setFormat(*node, node->spec.formats.empty() ? V4L2_PIX_FMT_YUYV : node->spec.formats.front());
  nodes_.push_back(std::move(node));
}

void FakeV4l2Device::setFormat(Node& node, std::uint32_t fourcc) {
  const auto w = static_cast<std::uint32_t>(node.spec.width_px);
  const auto h = static_cast<std::uint32_t>(node.spec.height_px);
  node.pixelFormat = fourcc;
  if (fourcc == V4L2_PIX_FMT_YUYV) {
    node.bytesPerLine = 2 * w + node.spec.linePaddingBytes;
    node.sizeImage = node.bytesPerLine * h;
  } else if (fourcc == V4L2_PIX_FMT_NV12) {
    node.bytesPerLine = w + node.spec.linePaddingBytes;
    node.sizeImage = node.bytesPerLine * h * 3 / 2;
  } else {  // compressed: no lines, an upper bound on the size
    node.bytesPerLine = 0;
    node.sizeImage = w * h * 3;
  }
}

int FakeV4l2Device::mappedBuffers() const {
  int mapped = 0;
  for (const auto& node : nodes_) {
    for (const Buffer& buffer : node->buffers) {
      mapped += buffer.mappings;
    }
  }
  return mapped;
}

unsigned FakeV4l2Device::allocatedBuffers(const std::string& path) const {
  unsigned count = 0;
  for (const auto& node : nodes_) {
    if (node->spec.path == path) {
      count += static_cast<unsigned>(node->buffers.size());
    }
  }
  return count;
}

unsigned FakeV4l2Device::queuedBuffers(const std::string& path) const {
  const Node* node = live(path);
  return node == nullptr ? 0 : static_cast<unsigned>(node->queue.size());
}

bool FakeV4l2Device::streaming(const std::string& path) const {
  const Node* node = live(path);
  return node != nullptr && node->streaming;
}

int FakeV4l2Device::open(const char* path) {
  Node* node = live(path);
  if (node == nullptr) {
    return -ENOENT;
  }
  fds_[nextFd_] = node;
  return nextFd_++;
}

int FakeV4l2Device::close(int fd) {
  const auto it = fds_.find(fd);
  if (it == fds_.end()) {
    violation("close of unknown fd " + std::to_string(fd));
    return -EBADF;
  }
  Node* node = it->second;
  fds_.erase(it);
  // The last close releases the queue, as vb2 does; mappings keep their memory alive.
  const bool stillOpen = std::any_of(fds_.begin(), fds_.end(),
                                     [node](const auto& entry) { return entry.second == node; });
  if (!stillOpen) {
    node->streaming = false;
    node->queue.clear();
    node->done.clear();
    const bool mapped = std::any_of(node->buffers.begin(), node->buffers.end(),
                                    [](const Buffer& b) { return b.mappings > 0; });
    if (!mapped) {
      node->buffers.clear();
    }
  }
  return 0;
}

bool FakeV4l2Device::captureOne(Node& node) {
  while (!node.pending.empty()) {
    if (node.queue.empty()) {
      // No buffer to capture into: the driver drops the frame but counts it.
      node.pending.pop_front();
      ++node.sequence;
      continue;
    }
    FakeFrame frame = std::move(node.pending.front());
    node.pending.pop_front();
    const unsigned index = node.queue.front();
    node.queue.pop_front();
    Buffer& buffer = node.buffers[index];
    const std::size_t n = std::min(frame.bytes.size(), buffer.memory.size());
    std::memcpy(buffer.memory.data(), frame.bytes.data(), n);
    buffer.bytesUsed = static_cast<std::uint32_t>(n);
    buffer.timestamp_ns = frame.timestamp_ns;
    buffer.error = frame.error;
    buffer.sequence = node.sequence++;
    buffer.state = BufferState::Done;
    node.done.push_back(index);
    return true;
  }
  return false;
}

int FakeV4l2Device::ioctl(int fd, unsigned long request, void* argument) {
  calls_.push_back(ioctlName(request));
  const auto it = fds_.find(fd);
  if (it == fds_.end()) {
    violation(std::string("ioctl ") + ioctlName(request) + " on unknown fd");
    return -EBADF;
  }
  Node& node = *it->second;
  if (node.gone) {
    return -ENODEV;
  }
  switch (request) {
    case VIDIOC_QUERYCAP: {
      auto* caps = static_cast<v4l2_capability*>(argument);
      *caps = v4l2_capability{};
      copyName(caps->driver, sizeof(caps->driver), "fakecam");
      copyName(caps->card, sizeof(caps->card), "Fake Camera");
      copyName(caps->bus_info, sizeof(caps->bus_info), node.spec.busInfo);
      caps->device_caps =
          (node.spec.capture ? V4L2_CAP_VIDEO_CAPTURE : V4L2_CAP_META_CAPTURE) | V4L2_CAP_STREAMING;
      caps->capabilities = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_META_CAPTURE | V4L2_CAP_STREAMING |
                           V4L2_CAP_DEVICE_CAPS;
      return 0;
    }
    case VIDIOC_S_FMT:
    case VIDIOC_G_FMT: {
      auto* format = static_cast<v4l2_format*>(argument);
      if (format->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || !node.spec.capture) {
        return -EINVAL;
      }
      if (request == VIDIOC_S_FMT) {
        if (node.streaming || !node.buffers.empty()) {
          return -EBUSY;
        }
        const std::uint32_t wanted = format->fmt.pix.pixelformat;
        const bool supported = std::find(node.spec.formats.begin(), node.spec.formats.end(),
                                         wanted) != node.spec.formats.end();
        setFormat(node, supported ? wanted : node.spec.formats.front());
      }
      format->fmt.pix = v4l2_pix_format{};
      format->fmt.pix.width = static_cast<__u32>(node.spec.width_px);
      format->fmt.pix.height = static_cast<__u32>(node.spec.height_px);
      format->fmt.pix.pixelformat = node.pixelFormat;
      format->fmt.pix.field = V4L2_FIELD_NONE;
      format->fmt.pix.bytesperline = node.bytesPerLine;
      format->fmt.pix.sizeimage = node.sizeImage;
      return 0;
    }
    case VIDIOC_REQBUFS: {
      auto* request_ = static_cast<v4l2_requestbuffers*>(argument);
      if (request_->memory != V4L2_MEMORY_MMAP || request_->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) {
        return -EINVAL;
      }
      if (node.streaming) {
        violation("REQBUFS while streaming");
        return -EBUSY;
      }
      for (const Buffer& buffer : node.buffers) {
        if (buffer.mappings > 0) {
          violation("REQBUFS with buffers still mapped");
          return -EBUSY;
        }
      }
      node.buffers.clear();
      node.queue.clear();
      node.done.clear();
      if (request_->count == 0) {
        return 0;
      }
      request_->count = std::clamp(request_->count, node.spec.minBuffers, node.spec.maxBuffers);
      node.buffers.resize(request_->count);
      for (Buffer& buffer : node.buffers) {
        buffer.memory.assign(node.sizeImage, 0);
      }
      return 0;
    }
    case VIDIOC_QUERYBUF:
    case VIDIOC_QBUF: {
      auto* buffer = static_cast<v4l2_buffer*>(argument);
      if (buffer->index >= node.buffers.size() || buffer->memory != V4L2_MEMORY_MMAP) {
        violation(std::string(ioctlName(request)) + " of invalid buffer " +
                  std::to_string(buffer->index));
        return -EINVAL;
      }
      Buffer& b = node.buffers[buffer->index];
      if (request == VIDIOC_QUERYBUF) {
        buffer->length = static_cast<__u32>(b.memory.size());
        buffer->m.offset = buffer->index * kOffsetStride;
        return 0;
      }
      if (b.state != BufferState::User) {
        violation("QBUF of buffer " + std::to_string(buffer->index) + " not owned by user");
        return -EINVAL;
      }
      b.state = BufferState::Queued;
      node.queue.push_back(buffer->index);
      return 0;
    }
    case VIDIOC_DQBUF: {
      if (!node.streaming) {
        return -EINVAL;
      }
      if (node.done.empty()) {
        captureOne(node);
      }
      if (node.done.empty()) {
        return -EAGAIN;
      }
      const unsigned index = node.done.front();
      node.done.pop_front();
      Buffer& b = node.buffers[index];
      b.state = BufferState::User;
      auto* buffer = static_cast<v4l2_buffer*>(argument);
      buffer->index = index;
      buffer->bytesused = b.bytesUsed;
      buffer->sequence = b.sequence;
      buffer->flags = (node.spec.monotonicTimestamps ? V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC
                                                     : V4L2_BUF_FLAG_TIMESTAMP_UNKNOWN) |
                      (b.error ? V4L2_BUF_FLAG_ERROR : 0u);
      buffer->timestamp.tv_sec = static_cast<time_t>(b.timestamp_ns / 1'000'000'000);
      buffer->timestamp.tv_usec = static_cast<suseconds_t>((b.timestamp_ns % 1'000'000'000) / 1000);
      dequeued_.push_back(index);
      return 0;
    }
    case VIDIOC_STREAMON:
      if (node.buffers.empty()) {
        violation("STREAMON without buffers");
        return -EINVAL;
      }
      node.streaming = true;
      node.sequence = 0;
      return 0;
    case VIDIOC_STREAMOFF:
      node.streaming = false;
      for (Buffer& b : node.buffers) {
        b.state = BufferState::User;
      }
      node.queue.clear();
      node.done.clear();
      return 0;
    default:
      return -ENOTTY;
  }
}

void* FakeV4l2Device::mmap(int fd, std::size_t length, std::int64_t offset, int* error) {
  const auto it = fds_.find(fd);
  if (it == fds_.end()) {
    *error = EBADF;
    return nullptr;
  }
  Node& node = *it->second;
  if (node.gone) {
    *error = ENODEV;
    return nullptr;
  }
  const auto index = static_cast<std::size_t>(offset / kOffsetStride);
  if (offset % kOffsetStride != 0 || index >= node.buffers.size() ||
      length > node.buffers[index].memory.size()) {
    violation("mmap of an offset/length QUERYBUF did not give");
    *error = EINVAL;
    return nullptr;
  }
  ++node.buffers[index].mappings;
  return node.buffers[index].memory.data();
}

int FakeV4l2Device::munmap(void* address, std::size_t length) {
  for (const auto& node : nodes_) {
    for (Buffer& buffer : node->buffers) {
      if (buffer.memory.data() == address && buffer.mappings > 0) {
        if (length != buffer.memory.size()) {
          violation("munmap with a length other than the mapping's");
        }
        --buffer.mappings;
        return 0;
      }
    }
  }
  violation("munmap of an address that is not mapped");
  return -EINVAL;
}

int FakeV4l2Device::poll(int fd, int timeout_ms, short* revents) {
  const auto it = fds_.find(fd);
  if (it == fds_.end()) {
    *revents = POLLNVAL;
    return 1;
  }
  Node& node = *it->second;
  if (node.gone || !node.streaming) {
    *revents = static_cast<short>(POLLERR | (node.gone ? POLLHUP : 0));
    return 1;
  }
  if (node.done.empty()) {
    captureOne(node);
  }
  if (!node.done.empty()) {
    *revents = POLLIN;
    return 1;
  }
  if (clock_ != nullptr) {
    clock_->advance_ns(static_cast<std::int64_t>(timeout_ms) * 1'000'000);
  }
  *revents = 0;
  return 0;
}

std::vector<std::string> FakeV4l2Device::listVideoNodes() {
  std::vector<std::string> paths;
  for (const auto& node : nodes_) {
    if (!node->gone) {
      paths.push_back(node->spec.path);
    }
  }
  std::sort(paths.begin(), paths.end());
  return paths;
}

}  // namespace vp::test
