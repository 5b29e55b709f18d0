// platform/mavlink/serial_port: RAII owner of a serial device (the autopilot's TELEM port on
// a UART or a USB serial adapter), raw 8N1 at a standard baud rate.
//
// Contract: the constructor does nothing; open() opens the device non-blocking, sets raw mode
// (no echo, no line editing, no flow control, 8 data bits, no parity, 1 stop bit) and the baud
// rate, and fails with a message naming the device and the cause (missing device, no
// permission, not a tty, unsupported baud). read()/write() return at once: bytes moved, 0
// when nothing is waiting, or -errno (a USB adapter pulled out gives -EIO/-ENODEV; reopening
// is the caller's decision). They never allocate. Move-only; the destructor closes it.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <span>
#include <string>

namespace vp::platform::mavlink {

class SerialPort {
 public:
  SerialPort() = default;
  ~SerialPort() { close(); }
  SerialPort(SerialPort&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }
  SerialPort& operator=(SerialPort&& other) noexcept;
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  // baud: one of 9600, 19200, 38400, 57600, 115200, 230400, 460800, 500000, 921600,
  // 1000000, 1500000, 2000000, 3000000.
  bool open(const std::string& device, int baud, std::string* why);
  void close();

  bool isOpen() const { return fd_ >= 0; }
  int fd() const { return fd_; }

  ssize_t read(std::span<std::uint8_t> buffer);
  ssize_t write(std::span<const std::uint8_t> bytes);
  // Waits up to timeout_ms for input: true when bytes wait; false on timeout or hang-up.
  bool waitReadable(int timeout_ms) const;

 private:
  int fd_ = -1;
};

}  // namespace vp::platform::mavlink
