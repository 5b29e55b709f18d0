// platform/v4l2/v4l2_device: the system calls a V4L2 capture device is driven with, behind an
// interface, so the camera's protocol (formats, buffers, queue/dequeue, errors, hot-unplug) is
// tested against an emulated device.
//
// Contract: every call returns >= 0 on success or -errno (no global errno), never throws.
// SystemV4l2Device forwards to the kernel (open O_RDWR|O_NONBLOCK, ioctl retried on EINTR,
// mmap MAP_SHARED, poll); listVideoNodes() lists /dev/video* (it allocates: start-up and
// reopen only). No camera logic lives here.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace vp::platform::v4l2 {

class V4l2Device {
 public:
  virtual ~V4l2Device() = default;

  virtual int open(const char* path) = 0;  // a descriptor or -errno
  virtual int close(int fd) = 0;
  virtual int ioctl(int fd, unsigned long request, void* argument) = 0;
  // Maps `length` bytes at the buffer offset QUERYBUF gave; nullptr and *error = errno on failure.
  virtual void* mmap(int fd, std::size_t length, std::int64_t offset, int* error) = 0;
  virtual int munmap(void* address, std::size_t length) = 0;
  // Waits for the descriptor to be readable: > 0 with *revents set, 0 on timeout, or -errno.
  virtual int poll(int fd, int timeout_ms, short* revents) = 0;
  // The video device nodes present now (sorted paths), for finding a camera by bus.
  virtual std::vector<std::string> listVideoNodes() = 0;
};

class SystemV4l2Device final : public V4l2Device {
 public:
  int open(const char* path) override;
  int close(int fd) override;
  int ioctl(int fd, unsigned long request, void* argument) override;
  void* mmap(int fd, std::size_t length, std::int64_t offset, int* error) override;
  int munmap(void* address, std::size_t length) override;
  int poll(int fd, int timeout_ms, short* revents) override;
  std::vector<std::string> listVideoNodes() override;
};

}  // namespace vp::platform::v4l2
