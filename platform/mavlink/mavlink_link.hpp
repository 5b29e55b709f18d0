// platform/mavlink/mavlink_link: moves the bytes waiting on a UDP socket or a serial port into
// a MAVLink parser (src/input/mavlink), calling back for every valid frame.
//
// Contract: each call reads until nothing more waits (non-blocking), through a caller-owned
// scratch buffer, so it never allocates. UDP keeps datagram boundaries: the parser is told
// where each datagram ends (a frame cut by the end of a datagram counts as truncated), and a
// datagram longer than the scratch buffer is counted in *oversize. Returns the number of reads
// that delivered bytes, or -errno of a failing read (the link is then the caller's to reopen).
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <span>

#include "mavlink/mavlink_parser.hpp"
#include "platform/mavlink/serial_port.hpp"
#include "platform/mavlink/udp_socket.hpp"

namespace vp::platform::mavlink {

// 2 KiB holds any datagram a MAVLink router sends (it packs frames up to the path MTU).
constexpr std::size_t kLinkScratchBytes = 2048;

template <class OnFrame>
long drainUdp(UdpSocket& socket, vp::mavlink::MavlinkParser& parser,
              std::span<std::uint8_t> scratch, OnFrame&& onFrame,
              std::uint64_t* oversize = nullptr) {
  long reads = 0;
  for (;;) {
    bool truncated = false;
    const ssize_t n = socket.receive(scratch, &truncated);
    if (n < 0) {
      return n;
    }
    if (n == 0) {
      return reads;
    }
    ++reads;
    if (truncated && oversize != nullptr) {
      ++*oversize;
    }
    parser.parse(scratch.first(static_cast<std::size_t>(n)), onFrame);
    parser.endOfDatagram();
  }
}

template <class OnFrame>
long drainSerial(SerialPort& port, vp::mavlink::MavlinkParser& parser,
                 std::span<std::uint8_t> scratch, OnFrame&& onFrame) {
  long reads = 0;
  for (;;) {
    const ssize_t n = port.read(scratch);
    if (n < 0) {
      return n;
    }
    if (n == 0) {
      return reads;
    }
    ++reads;
    parser.parse(scratch.first(static_cast<std::size_t>(n)), onFrame);
  }
}

}  // namespace vp::platform::mavlink
