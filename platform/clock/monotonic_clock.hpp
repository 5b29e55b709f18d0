// platform/clock/monotonic_clock: the loop's one clock (CLOCK_MONOTONIC, ns) behind a small
// interface, so that sources that wait (replay pacing, device reopen backoff) can be tested
// without sleeping.
//
// Contract: nowNs() never goes backwards; sleepUntilNs() returns at or after the deadline
// (at once when it has passed). Neither allocates nor throws. Header-only.
#pragma once

#include <cerrno>
#include <cstdint>
#include <ctime>

namespace vp::platform {

class Clock {
 public:
  virtual ~Clock() = default;
  virtual std::int64_t nowNs() const = 0;
  virtual void sleepUntilNs(std::int64_t deadlineNs) = 0;
};

constexpr std::int64_t kNsPerSecond = 1'000'000'000;

inline std::int64_t monotonicNowNs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kNsPerSecond + ts.tv_nsec;
}

class MonotonicClock final : public Clock {
 public:
  std::int64_t nowNs() const override { return monotonicNowNs(); }
  void sleepUntilNs(std::int64_t deadlineNs) override {
    timespec ts{};
    ts.tv_sec = static_cast<time_t>(deadlineNs / kNsPerSecond);
    ts.tv_nsec = static_cast<long>(deadlineNs % kNsPerSecond);
    // An absolute deadline: a signal only restarts the same wait, it never shortens it.
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
  }
};

// A clock that only moves when told to (tests, simulation faster than real time).
class ManualClock final : public Clock {
 public:
  explicit ManualClock(std::int64_t startNs = 0) : nowNs_(startNs) {}
  std::int64_t nowNs() const override { return nowNs_; }
  void sleepUntilNs(std::int64_t deadlineNs) override {
    ++sleeps_;
    if (deadlineNs > nowNs_) {
      nowNs_ = deadlineNs;
    }
  }
  void advanceNs(std::int64_t deltaNs) { nowNs_ += deltaNs; }
  int sleeps() const { return sleeps_; }

 private:
  std::int64_t nowNs_;
  int sleeps_ = 0;
};

}  // namespace vp::platform
