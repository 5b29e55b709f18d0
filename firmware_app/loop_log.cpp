#include "loop_log.hpp"

#include <time.h>

#include <algorithm>
#include <cstdarg>
#include <cstddef>
#include <cstdio>

namespace vp::app {

namespace {
constexpr std::int64_t kNsPerSecond = 1'000'000'000;
constexpr int kLogLineBytes = 768;
}  // namespace

void logLine(const char* format, ...) {
  char line[kLogLineBytes];
  int n = std::snprintf(line, sizeof(line), "vp_firmware_app: ");
  va_list args;
  va_start(args, format);
  const int m =
      std::vsnprintf(line + n, sizeof(line) - static_cast<std::size_t>(n) - 1, format, args);
  va_end(args);
  n = std::min<int>(static_cast<int>(sizeof(line)) - 2, n + std::max(m, 0));
  line[n++] = '\n';
  std::fwrite(line, 1, static_cast<std::size_t>(n), stderr);
}

std::int64_t realtimeNow_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kNsPerSecond + ts.tv_nsec;
}

}  // namespace vp::app
