// firmware_app/loop_log: the loop's log lines and its wall clock.
//
// Contract: logLine() writes one "vp_firmware_app: ..." line on stderr, formatted on the stack
// (at most 767 bytes, cut when longer): any unit of the loop may log from the real-time path
// without allocating. realtimeNow_ns() is CLOCK_REALTIME in nanoseconds (DDS times are UTC).
#pragma once

#include <cstdint>

namespace vp::app {

void logLine(const char* format, ...) __attribute__((format(printf, 1, 2)));

std::int64_t realtimeNow_ns();

}  // namespace vp::app
