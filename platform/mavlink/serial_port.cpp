#include "platform/mavlink/serial_port.hpp"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <utility>

namespace vp::platform::mavlink {
namespace {

struct BaudRate {
  int baud;
  speed_t speed;
};
constexpr std::array<BaudRate, 13> kBaudRates{{{9600, B9600},
                                               {19200, B19200},
                                               {38400, B38400},
                                               {57600, B57600},
                                               {115200, B115200},
                                               {230400, B230400},
                                               {460800, B460800},
                                               {500000, B500000},
                                               {921600, B921600},
                                               {1000000, B1000000},
                                               {1500000, B1500000},
                                               {2000000, B2000000},
                                               {3000000, B3000000}}};

}  // namespace

SerialPort& SerialPort::operator=(SerialPort&& other) noexcept {
  if (this != &other) {
    close();
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

bool SerialPort::open(const std::string& device, int baud, std::string* why) {
  close();
  auto fail = [&](const std::string& what) {
    if (why != nullptr) {
      *why = "serial " + device + ": " + what;
    }
    return false;
  };
  speed_t speed = B0;
  for (const BaudRate& rate : kBaudRates) {
    if (rate.baud == baud) {
      speed = rate.speed;
    }
  }
  if (speed == B0) {
    return fail("unsupported baud rate " + std::to_string(baud));
  }
  const int fd = ::open(device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    return fail(std::strerror(errno));
  }
  termios tty{};
  if (::tcgetattr(fd, &tty) != 0) {
    const int error = errno;
    ::close(fd);
    return fail(std::string("not a serial device: ") + std::strerror(error));
  }
  ::cfmakeraw(&tty);
  tty.c_cflag |= CLOCAL | CREAD;  // no modem control lines, receiver on
  tty.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | CRTSCTS | PARENB);
  tty.c_cc[VMIN] = 0;  // read() returns what is there, never waits
  tty.c_cc[VTIME] = 0;
  if (::cfsetispeed(&tty, speed) != 0 || ::cfsetospeed(&tty, speed) != 0 ||
      ::tcsetattr(fd, TCSANOW, &tty) != 0) {
    const int error = errno;
    ::close(fd);
    return fail("cannot set " + std::to_string(baud) + " baud 8N1 raw: " + std::strerror(error));
  }
  ::tcflush(fd, TCIFLUSH);  // bytes from before we were listening are stale
  fd_ = fd;
  return true;
}

void SerialPort::close() {
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
  }
}

ssize_t SerialPort::read(std::span<std::uint8_t> buffer) {
  const ssize_t n = ::read(fd_, buffer.data(), buffer.size());
  if (n < 0) {
    return (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) ? 0 : -errno;
  }
  return n;
}

ssize_t SerialPort::write(std::span<const std::uint8_t> bytes) {
  const ssize_t n = ::write(fd_, bytes.data(), bytes.size());
  if (n < 0) {
    return (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) ? 0 : -errno;
  }
  return n;
}

bool SerialPort::waitReadable(int timeout_ms) const {
  pollfd descriptor{fd_, POLLIN, 0};
  return ::poll(&descriptor, 1, timeout_ms) > 0 && (descriptor.revents & POLLIN) != 0;
}

}  // namespace vp::platform::mavlink
