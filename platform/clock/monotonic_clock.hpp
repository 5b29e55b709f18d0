// platform/clock/monotonic_clock: the loop's one clock (CLOCK_MONOTONIC, ns) behind a small
// interface, so that sources that wait (replay pacing, device reopen backoff) can be tested
// without sleeping.
//
// Contract: now_ns() never goes backwards; sleepUntil_ns() returns at or after the deadline
// (at once when it has passed). Neither allocates nor throws. Header-only.
#pragma once

#include <cerrno>
#include <cstdint>
#include <ctime>

namespace vp::platform {

class Clock {
 public:
  virtual ~Clock() = default;
  virtual std::int64_t now_ns() const = 0;
  virtual void sleepUntil_ns(std::int64_t deadline_ns) = 0;
};

constexpr std::int64_t kNsPerSecond = 1'000'000'000;

inline std::int64_t monotonicNow_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kNsPerSecond + ts.tv_nsec;
}

class MonotonicClock final : public Clock {
 public:
  std::int64_t now_ns() const override { return monotonicNow_ns(); }
  void sleepUntil_ns(std::int64_t deadline_ns) override {
    timespec ts{};
    ts.tv_sec = static_cast<time_t>(deadline_ns / kNsPerSecond);
    ts.tv_nsec = static_cast<long>(deadline_ns % kNsPerSecond);
    // An absolute deadline: a signal only restarts the same wait, it never shortens it.
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
  }
};

// A clock that only moves when told to (tests, simulation faster than real time).
class ManualClock final : public Clock {
 public:
  explicit ManualClock(std::int64_t start_ns = 0) : nowNs_(start_ns) {}
  std::int64_t now_ns() const override { return nowNs_; }
  void sleepUntil_ns(std::int64_t deadline_ns) override {
    ++sleeps_;
    if (deadline_ns > nowNs_) {
      nowNs_ = deadline_ns;
    }
  }
  void advance_ns(std::int64_t delta_ns) { nowNs_ += delta_ns; }
  int sleeps() const { return sleeps_; }

 private:
  std::int64_t nowNs_;
  int sleeps_ = 0;
};

}  // namespace vp::platform
