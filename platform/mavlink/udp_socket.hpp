// platform/mavlink/udp_socket: RAII owner of one IPv4 UDP socket, the usual MAVLink link of a
// companion computer (the autopilot or mavlink-router sends to a local port).
//
// Contract: the constructor does nothing; open() binds host:port (port 0: any free port) and
// can fail with a message naming the address and the system error. The socket is
// non-blocking: receive() returns at once with one datagram, 0 when none waits, or -errno.
// receive(), send() and waitReadable() never allocate; open()/connect() may (address lookup,
// start-up only). Move-only; the destructor closes the descriptor. No MAVLink logic here.
#pragma once

#include <sys/types.h>

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace vp::platform::mavlink {

class UdpSocket {
 public:
  UdpSocket() = default;
  ~UdpSocket() { close(); }
  UdpSocket(UdpSocket&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }
  UdpSocket& operator=(UdpSocket&& other) noexcept;
  UdpSocket(const UdpSocket&) = delete;
  UdpSocket& operator=(const UdpSocket&) = delete;

  // Binds to host (numeric IPv4 or a name; "0.0.0.0" = every interface) and port.
  bool open(const std::string& host, std::uint16_t port, std::string* why);
  // Sets the peer of send() (and filters receive() to it, as connected UDP sockets do).
  bool connect(const std::string& host, std::uint16_t port, std::string* why);
  void close();

  bool isOpen() const { return fd_ >= 0; }
  int fd() const { return fd_; }
  std::uint16_t localPort() const;  // the bound port (useful after binding port 0)

  // One datagram into `buffer`: its length, 0 when none waits, -errno on error. A datagram
  // longer than the buffer is cut; *truncated then says so.
  ssize_t receive(std::span<std::uint8_t> buffer, bool* truncated = nullptr);
  // Sends one datagram to the connected peer: bytes sent or -errno.
  ssize_t send(std::span<const std::uint8_t> bytes);
  // Waits up to timeout_ms for a datagram: true when one waits.
  bool waitReadable(int timeout_ms) const;

 private:
  int fd_ = -1;
};

}  // namespace vp::platform::mavlink
