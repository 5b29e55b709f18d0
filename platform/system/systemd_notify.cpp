#include "platform/system/systemd_notify.hpp"

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstddef>
#include <cstdlib>
#include <cstring>

namespace vp::platform {

static_assert(sizeof(sockaddr_un) <= 112, "address_ buffer too small for sockaddr_un");

SystemdNotifier::~SystemdNotifier() {
  close();
}

void SystemdNotifier::close() {
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
  }
}

namespace {

std::int64_t parseInt(const char* text) {
  if (text == nullptr) {
    return -1;
  }
  std::int64_t value = -1;
  const char* end = text + std::strlen(text);
  const auto [ptr, ec] = std::from_chars(text, end, value);
  return (ec == std::errc() && ptr == end) ? value : -1;
}

}  // namespace

bool SystemdNotifier::open(std::string* why) {
  close();
  const char* socketPath = std::getenv("NOTIFY_SOCKET");
  if (socketPath == nullptr || socketPath[0] == '\0') {
    return true;  // not started by systemd: disabled
  }
  const std::size_t length = std::strlen(socketPath);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  if (length >= sizeof(address.sun_path)) {
    if (why)
      *why = std::string("NOTIFY_SOCKET: path too long: ") + socketPath;
    return false;
  }
  if (socketPath[0] != '/' && socketPath[0] != '@') {
    if (why)
      *why = std::string("NOTIFY_SOCKET: neither a path nor an abstract address: ") + socketPath;
    return false;
  }
  std::memcpy(address.sun_path, socketPath, length);
  if (socketPath[0] == '@') {
    address.sun_path[0] = '\0';  // abstract namespace
  }
  const int fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    if (why)
      *why = std::string("NOTIFY_SOCKET: socket(): ") + std::strerror(errno);
    return false;
  }
  fd_ = fd;
  std::memcpy(address_, &address, sizeof(address));
  addressLength_ = static_cast<unsigned>(offsetof(sockaddr_un, sun_path) + length);

  watchdogIntervalNs_ = 0;
  const std::int64_t usec = parseInt(std::getenv("WATCHDOG_USEC"));
  const std::int64_t pid = parseInt(std::getenv("WATCHDOG_PID"));
  if (usec > 0 && (pid < 0 || pid == static_cast<std::int64_t>(::getpid()))) {
    watchdogIntervalNs_ = usec * 1000 / 2;
  }
  return true;
}

bool SystemdNotifier::status(std::string_view text) {
  char buffer[8 + 200];
  constexpr std::string_view kPrefix = "STATUS=";
  const std::size_t n = text.size() < 200 ? text.size() : 200;
  std::memcpy(buffer, kPrefix.data(), kPrefix.size());
  std::memcpy(buffer + kPrefix.size(), text.data(), n);
  return send(std::string_view(buffer, kPrefix.size() + n));
}

bool SystemdNotifier::send(std::string_view message) {
  if (fd_ < 0) {
    return true;
  }
  const ssize_t sent = ::sendto(fd_, message.data(), message.size(), MSG_DONTWAIT | MSG_NOSIGNAL,
                                reinterpret_cast<const sockaddr*>(address_), addressLength_);
  return sent == static_cast<ssize_t>(message.size());
}

}  // namespace vp::platform
