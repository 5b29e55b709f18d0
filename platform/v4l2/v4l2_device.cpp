#include "platform/v4l2/v4l2_device.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <system_error>

namespace vp::platform::v4l2 {

int SystemV4l2Device::open(const char* path) {
  const int fd = ::open(path, O_RDWR | O_NONBLOCK | O_CLOEXEC);
  return fd < 0 ? -errno : fd;
}

int SystemV4l2Device::close(int fd) {
  return ::close(fd) != 0 ? -errno : 0;
}

int SystemV4l2Device::ioctl(int fd, unsigned long request, void* argument) {
  int rc = 0;
  do {
    rc = ::ioctl(fd, request, argument);
  } while (rc < 0 && errno == EINTR);
  return rc < 0 ? -errno : rc;
}

void* SystemV4l2Device::mmap(int fd, std::size_t length, std::int64_t offset, int* error) {
  void* address =
      ::mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_SHARED, fd, static_cast<off_t>(offset));
  if (address == MAP_FAILED) {
    *error = errno;
    return nullptr;
  }
  return address;
}

int SystemV4l2Device::munmap(void* address, std::size_t length) {
  return ::munmap(address, length) != 0 ? -errno : 0;
}

int SystemV4l2Device::poll(int fd, int timeout_ms, short* revents) {
  pollfd descriptor{fd, POLLIN, 0};
  const int rc = ::poll(&descriptor, 1, timeout_ms);
  if (rc < 0) {
    return errno == EINTR ? 0 : -errno;
  }
  *revents = descriptor.revents;
  return rc;
}

std::vector<std::string> SystemV4l2Device::listVideoNodes() {
  std::vector<std::string> nodes;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator("/dev", error)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("video", 0) == 0) {
      nodes.push_back(entry.path().string());
    }
  }
  std::sort(nodes.begin(), nodes.end());
  return nodes;
}

}  // namespace vp::platform::v4l2
