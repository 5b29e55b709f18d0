// platform/clock: a wait ends at its deadline, a signal that interrupts it (EINTR) does not
// shorten it, and the clock's stop condition ends it early, however far the deadline lies.
#include <pthread.h>
#include <signal.h>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "platform/clock/monotonic_clock.hpp"

namespace vp::platform {
namespace {

struct Flag final : StopCondition {
  std::atomic<bool> stop{false};
  bool stopRequested() const override { return stop.load(); }
};

constexpr std::int64_t kMs_ns = 1'000'000;

TEST(MonotonicClock, SleepsUntilTheDeadline) {
  MonotonicClock clock;
  const std::int64_t start = clock.now_ns();
  EXPECT_TRUE(clock.sleepUntil_ns(start + 30 * kMs_ns));
  EXPECT_GE(clock.now_ns(), start + 30 * kMs_ns);
  EXPECT_TRUE(clock.sleepUntil_ns(start - kNsPerSecond));  // passed: at once
}

TEST(MonotonicClock, AStopEndsAWaitOfAnHourWithinThePollPeriod) {
  MonotonicClock clock;
  Flag flag;
  clock.setStopCondition(&flag);
  const std::int64_t start = clock.now_ns();
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    flag.stop = true;
  });
  const bool reached = clock.sleepUntil_ns(start + 3600 * kNsPerSecond);
  const std::int64_t waited_ns = clock.now_ns() - start;
  stopper.join();
  EXPECT_FALSE(reached);
  EXPECT_GE(waited_ns, 50 * kMs_ns);
  EXPECT_LT(waited_ns, 50 * kMs_ns + kStopPoll_ns + 500 * kMs_ns);  // + scheduling slack
  // Stopped: later waits return at once, and without the condition the clock sleeps again.
  EXPECT_FALSE(clock.sleepUntil_ns(clock.now_ns() + 3600 * kNsPerSecond));
  clock.setStopCondition(nullptr);
  EXPECT_TRUE(clock.sleepUntil_ns(clock.now_ns() + kMs_ns));
}

void onSignal(int) {}

TEST(MonotonicClock, ASignalDoesNotShortenTheWait) {
  struct sigaction action {};
  action.sa_handler = &onSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // no SA_RESTART: clock_nanosleep returns EINTR
  struct sigaction previous {};
  ASSERT_EQ(sigaction(SIGUSR1, &action, &previous), 0);
  MonotonicClock clock;
  Flag flag;  // never set
  clock.setStopCondition(&flag);
  const std::int64_t start = clock.now_ns();
  const pthread_t sleeper = pthread_self();
  std::thread signaller([&] {
    for (int i = 0; i < 5; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      pthread_kill(sleeper, SIGUSR1);
    }
  });
  EXPECT_TRUE(clock.sleepUntil_ns(start + 150 * kMs_ns));
  EXPECT_GE(clock.now_ns(), start + 150 * kMs_ns);
  signaller.join();
  sigaction(SIGUSR1, &previous, nullptr);
}

TEST(ManualClock, JumpsToTheDeadlineUnlessStopped) {
  ManualClock clock(1000);
  EXPECT_TRUE(clock.sleepUntil_ns(5000));
  EXPECT_EQ(clock.now_ns(), 5000);
  Flag flag;
  flag.stop = true;
  clock.setStopCondition(&flag);
  EXPECT_FALSE(clock.sleepUntil_ns(9000));
  EXPECT_EQ(clock.now_ns(), 5000);  // time did not move
}

}  // namespace
}  // namespace vp::platform
