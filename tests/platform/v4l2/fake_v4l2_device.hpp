// tests/platform/v4l2/fake_v4l2_device: an emulated V4L2 capture driver behind the V4l2Device
// interface.
//
// It follows the kernel's protocol closely enough to catch misuse: S_FMT substitutes an
// unsupported pixel format and clamps the size (as drivers do), REQBUFS clamps the count and
// refuses to free mapped buffers, QBUF refuses a buffer already queued, DQBUF hands buffers
// back in the order they were queued, STREAMOFF returns every buffer to user space, and a
// device that is unplugged answers ENODEV/POLLERR until it is plugged in again (a fresh
// device: no buffers, not streaming). Frames are supplied by the test (raw bytes in the
// negotiated layout); poll() never sleeps, it advances an optional ManualClock instead.
// Every protocol violation is recorded in violations().
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "platform/clock/monotonic_clock.hpp"
#include "platform/v4l2/v4l2_device.hpp"

namespace vp::test {

struct FakeNodeSpec {
  std::string path = "/dev/video0";
  std::string busInfo = "usb-0000:00:14.0-1";
  bool capture = true;                 // false: a metadata node (UVC cameras have one)
  std::vector<std::uint32_t> formats;  // supported fourccs; the first is the driver's default
  int width_px = 64;                   // the one size it supports
  int height_px = 48;
  std::uint32_t linePaddingBytes = 0;  // bytesperline = minimum + this
  bool monotonicTimestamps = true;
  unsigned minBuffers = 2;
  unsigned maxBuffers = 8;
};

struct FakeFrame {
  std::vector<std::uint8_t> bytes;
  std::int64_t timestamp_ns = 0;
  bool error = false;  // V4L2_BUF_FLAG_ERROR
};

class FakeV4l2Device final : public platform::v4l2::V4l2Device {
 public:
  // The logs are reserved up front so that the emulation allocates nothing while streaming
  // (tests count the camera's allocations around it).
  explicit FakeV4l2Device(platform::ManualClock* clock = nullptr) : clock_(clock) {
    calls_.reserve(4096);
    dequeued_.reserve(4096);
  }

  void addNode(const FakeNodeSpec& spec);
  void pushFrame(const std::string& path, FakeFrame frame);
  void unplug(const std::string& path);
  void replug(const std::string& path);

  // Inspection.
  int openDescriptors() const { return static_cast<int>(fds_.size()); }
  int mappedBuffers() const;
  unsigned allocatedBuffers(const std::string& path) const;
  unsigned queuedBuffers(const std::string& path) const;
  bool streaming(const std::string& path) const;
  const std::vector<std::string>& calls() const { return calls_; }  // ioctl names in order
  const std::vector<unsigned>& dequeuedIndices() const { return dequeued_; }
  const std::vector<std::string>& violations() const { return violations_; }
  void clearCalls() { calls_.clear(); }

  // V4l2Device
  int open(const char* path) override;
  int close(int fd) override;
  int ioctl(int fd, unsigned long request, void* argument) override;
  void* mmap(int fd, std::size_t length, std::int64_t offset, int* error) override;
  int munmap(void* address, std::size_t length) override;
  int poll(int fd, int timeout_ms, short* revents) override;
  std::vector<std::string> listVideoNodes() override;

 private:
  enum class BufferState { User, Queued, Done };
  struct Buffer {
    std::vector<std::uint8_t> memory;
    BufferState state = BufferState::User;
    int mappings = 0;
    std::uint32_t bytesUsed = 0;
    std::int64_t timestamp_ns = 0;
    std::uint32_t sequence = 0;
    bool error = false;
  };
  struct Node {
    FakeNodeSpec spec;
    bool gone = false;  // unplugged: this instance never comes back
    bool streaming = false;
    std::uint32_t pixelFormat = 0;
    std::uint32_t bytesPerLine = 0;
    std::uint32_t sizeImage = 0;
    std::vector<Buffer> buffers;
    std::deque<unsigned> queue;  // queued, in QBUF order
    std::deque<unsigned> done;   // filled, in capture order
    std::deque<FakeFrame> pending;
    std::uint32_t sequence = 0;
  };

  Node* live(const std::string& path) const;
  void setFormat(Node& node, std::uint32_t fourcc);
  bool captureOne(Node& node);  // moves one pending frame into the oldest queued buffer
  void violation(const std::string& what) { violations_.push_back(what); }

  platform::ManualClock* clock_;
  std::vector<std::unique_ptr<Node>> nodes_;  // every instance ever plugged in
  std::map<std::string, FakeNodeSpec> specs_;
  std::map<int, Node*> fds_;
  int nextFd_ = 100;
  std::vector<std::string> calls_;
  std::vector<unsigned> dequeued_;
  std::vector<std::string> violations_;
};

}  // namespace vp::test
