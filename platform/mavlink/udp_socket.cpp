#include "platform/mavlink/udp_socket.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

namespace vp::platform::mavlink {
namespace {

bool fail(std::string* why, const std::string& what, int error) {
  if (why != nullptr) {
    *why = what + ": " + std::strerror(error);
  }
  return false;
}

bool resolve(const std::string& host, std::uint16_t port, sockaddr_in* address, std::string* why) {
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* found = nullptr;
  const int rc = getaddrinfo(host.c_str(), nullptr, &hints, &found);
  if (rc != 0 || found == nullptr) {
    if (why != nullptr) {
      *why =
          "udp " + host + ":" + std::to_string(port) + ": cannot resolve host: " + gai_strerror(rc);
    }
    return false;
  }
  std::memcpy(address, found->ai_addr, sizeof(sockaddr_in));
  address->sin_port = htons(port);
  freeaddrinfo(found);
  return true;
}

}  // namespace

UdpSocket& UdpSocket::operator=(UdpSocket&& other) noexcept {
  if (this != &other) {
    close();
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

bool UdpSocket::open(const std::string& host, std::uint16_t port, std::string* why) {
  close();
  sockaddr_in address{};
  if (!resolve(host, port, &address, why)) {
    return false;
  }
  const std::string where = "udp bind " + host + ":" + std::to_string(port);
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    return fail(why, where + ": socket", errno);
  }
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) != 0) {
    const int error = errno;
    ::close(fd);
    return fail(why, where, error);
  }
  fd_ = fd;
  return true;
}

bool UdpSocket::connect(const std::string& host, std::uint16_t port, std::string* why) {
  if (fd_ < 0) {
    if (why != nullptr) {
      *why = "udp connect " + host + ":" + std::to_string(port) + ": socket is not open";
    }
    return false;
  }
  sockaddr_in address{};
  if (!resolve(host, port, &address, why)) {
    return false;
  }
  if (::connect(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) != 0) {
    return fail(why, "udp connect " + host + ":" + std::to_string(port), errno);
  }
  return true;
}

void UdpSocket::close() {
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
  }
}

std::uint16_t UdpSocket::localPort() const {
  sockaddr_in address{};
  socklen_t length = sizeof(address);
  if (fd_ < 0 || ::getsockname(fd_, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
    return 0;
  }
  return ntohs(address.sin_port);
}

ssize_t UdpSocket::receive(std::span<std::uint8_t> buffer, bool* truncated) {
  // MSG_TRUNC makes recv() return the datagram's real length, so a cut is visible.
  const ssize_t n = ::recv(fd_, buffer.data(), buffer.size(), MSG_TRUNC);
  if (n < 0) {
    return (errno == EAGAIN || errno == EWOULDBLOCK) ? 0 : -errno;
  }
  const bool cut = static_cast<std::size_t>(n) > buffer.size();
  if (truncated != nullptr) {
    *truncated = cut;
  }
  return cut ? static_cast<ssize_t>(buffer.size()) : n;
}

ssize_t UdpSocket::send(std::span<const std::uint8_t> bytes) {
  const ssize_t n = ::send(fd_, bytes.data(), bytes.size(), 0);
  return n < 0 ? -errno : n;
}

bool UdpSocket::waitReadable(int timeout_ms) const {
  pollfd descriptor{fd_, POLLIN, 0};
  return ::poll(&descriptor, 1, timeout_ms) > 0 && (descriptor.revents & POLLIN) != 0;
}

}  // namespace vp::platform::mavlink
