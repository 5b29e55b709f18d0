// platform/clock/monotonic_clock: the loop's one clock (CLOCK_MONOTONIC, ns) behind a small
// interface, so that sources that wait (replay pacing, device reopen backoff, capture backoff)
// can be tested without sleeping and can all be cut short by the loop's stop request.
//
// Contract: now_ns() never goes backwards. sleepUntil_ns() returns true at or after the
// deadline (at once when it has passed), or false, early, when the clock's stop condition
// (setStopCondition()) reports a stop: at once when the stop was requested before the call,
// otherwise within kStopPoll_ns of the request, however far the deadline lies (a paced replay
// whose next frame is hours ahead still stops promptly). A signal that interrupts the wait
// (EINTR) only makes it look at the stop condition again. Neither allocates nor throws.
// Header-only.
#pragma once

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdint>
#include <ctime>

namespace vp::platform {

// What cuts a wait short: the loop's stop request. Polled while a wait lasts, from the thread
// that waits, so it must be cheap, thread-safe and allocation-free.
class StopCondition {
 public:
  virtual bool stopRequested() const = 0;

 protected:
  ~StopCondition() = default;
};

constexpr std::int64_t kNsPerSecond = 1'000'000'000;
// The longest a wait goes without looking at the stop condition: the delay of a stop.
constexpr std::int64_t kStopPoll_ns = 20'000'000;

class Clock {
 public:
  virtual ~Clock() = default;
  virtual std::int64_t now_ns() const = 0;
  // True when deadline_ns was reached, false when a stop cut the wait short (see the contract).
  virtual bool sleepUntil_ns(std::int64_t deadline_ns) = 0;

  // The condition every wait on this clock polls (nullptr: none). Set it before the threads
  // that wait start and clear it before the condition goes away (the app does both).
  void setStopCondition(const StopCondition* stop) { stop_.store(stop, std::memory_order_release); }

 protected:
  bool stopRequested() const {
    const StopCondition* stop = stop_.load(std::memory_order_acquire);
    return stop != nullptr && stop->stopRequested();
  }

 private:
  std::atomic<const StopCondition*> stop_{nullptr};
};

inline std::int64_t monotonicNow_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kNsPerSecond + ts.tv_nsec;
}

class MonotonicClock final : public Clock {
 public:
  std::int64_t now_ns() const override { return monotonicNow_ns(); }
  bool sleepUntil_ns(std::int64_t deadline_ns) override {
    // Slices of at most kStopPoll_ns to an absolute deadline: a signal (EINTR) or the end of a
    // slice only leads back to the stop check, and the deadline never moves.
    for (;;) {
      if (stopRequested()) {
        return false;
      }
      const std::int64_t now = monotonicNow_ns();
      if (now >= deadline_ns) {
        return true;
      }
      const std::int64_t until = now + std::min(deadline_ns - now, kStopPoll_ns);
      timespec ts{};
      ts.tv_sec = static_cast<time_t>(until / kNsPerSecond);
      ts.tv_nsec = static_cast<long>(until % kNsPerSecond);
      clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
    }
  }
};

// A clock that only moves when told to (tests, simulation faster than real time). A wait jumps
// to its deadline, unless the stop condition already reports a stop.
class ManualClock final : public Clock {
 public:
  explicit ManualClock(std::int64_t start_ns = 0) : nowNs_(start_ns) {}
  std::int64_t now_ns() const override { return nowNs_; }
  bool sleepUntil_ns(std::int64_t deadline_ns) override {
    ++sleeps_;
    if (stopRequested()) {
      return false;
    }
    if (deadline_ns > nowNs_) {
      nowNs_ = deadline_ns;
    }
    return true;
  }
  void advance_ns(std::int64_t delta_ns) { nowNs_ += delta_ns; }
  int sleeps() const { return sleeps_; }

 private:
  std::int64_t nowNs_;
  int sleeps_ = 0;
};

}  // namespace vp::platform
