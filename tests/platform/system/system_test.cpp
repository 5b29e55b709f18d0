// Tests of platform/system against the real OS: a datagram socket standing in for systemd,
// real signals, real affinity calls.
#include <gtest/gtest.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <array>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "alloc_counter.hpp"
#include "platform/system/realtime.hpp"
#include "platform/system/stop_signals.hpp"
#include "platform/system/systemd_notify.hpp"

namespace {

// A bound AF_UNIX datagram socket in a temporary directory: what systemd listens on.
class FakeServiceManager {
 public:
  FakeServiceManager() {
    path_ = (std::filesystem::temp_directory_path() / ("vp_notify_" + std::to_string(::getpid())))
                .string();
    ::unlink(path_.c_str());
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM, 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::snprintf(address.sun_path, sizeof(address.sun_path), "%s", path_.c_str());
    bound_ = ::bind(fd_, reinterpret_cast<sockaddr*>(&address), sizeof(address)) == 0;
  }
  ~FakeServiceManager() {
    ::close(fd_);
    ::unlink(path_.c_str());
  }
  std::string receive() {
    std::array<char, 512> buffer{};
    const ssize_t n = ::recv(fd_, buffer.data(), buffer.size(), MSG_DONTWAIT);
    return n > 0 ? std::string(buffer.data(), static_cast<std::size_t>(n)) : std::string();
  }
  const std::string& path() const { return path_; }
  bool bound() const { return bound_; }

 private:
  std::string path_;
  int fd_ = -1;
  bool bound_ = false;
};

TEST(SystemdNotifier, DisabledWithoutNotifySocket) {
  ::unsetenv("NOTIFY_SOCKET");
  vp::platform::SystemdNotifier notifier;
  std::string why;
  ASSERT_TRUE(notifier.open(&why)) << why;
  EXPECT_FALSE(notifier.enabled());
  EXPECT_TRUE(notifier.ready());
  EXPECT_EQ(notifier.watchdogInterval_ns(), 0);
}

TEST(SystemdNotifier, SendsTheProtocolMessagesAndHalvesTheWatchdogInterval) {
  FakeServiceManager manager;
  ASSERT_TRUE(manager.bound());
  ::setenv("NOTIFY_SOCKET", manager.path().c_str(), 1);
  ::setenv("WATCHDOG_USEC", "4000000", 1);
  ::setenv("WATCHDOG_PID", std::to_string(::getpid()).c_str(), 1);
  vp::platform::SystemdNotifier notifier;
  std::string why;
  ASSERT_TRUE(notifier.open(&why)) << why;
  ASSERT_TRUE(notifier.enabled());
  EXPECT_EQ(notifier.watchdogInterval_ns(), 2'000'000'000);

  {
    vp::test::AllocationCounter allocations;
    EXPECT_TRUE(notifier.ready());
    EXPECT_TRUE(notifier.watchdog());
    EXPECT_TRUE(notifier.status("12.0 fps, 0 dropped"));
    EXPECT_TRUE(notifier.stopping());
    EXPECT_EQ(allocations.count(), 0U);
  }
  EXPECT_EQ(manager.receive(), "READY=1");
  EXPECT_EQ(manager.receive(), "WATCHDOG=1");
  EXPECT_EQ(manager.receive(), "STATUS=12.0 fps, 0 dropped");
  EXPECT_EQ(manager.receive(), "STOPPING=1");

  // A watchdog meant for another process is not ours to feed.
  ::setenv("WATCHDOG_PID", "1", 1);
  ASSERT_TRUE(notifier.open(&why));
  EXPECT_EQ(notifier.watchdogInterval_ns(), 0);
  ::unsetenv("NOTIFY_SOCKET");
  ::unsetenv("WATCHDOG_USEC");
  ::unsetenv("WATCHDOG_PID");
}

TEST(SystemdNotifier, RejectsAnUnusableAddress) {
  ::setenv("NOTIFY_SOCKET", "relative/path", 1);
  vp::platform::SystemdNotifier notifier;
  std::string why;
  EXPECT_FALSE(notifier.open(&why));
  EXPECT_NE(why.find("NOTIFY_SOCKET"), std::string::npos) << why;
  ::unsetenv("NOTIFY_SOCKET");
}

TEST(StopSignals, SigtermAndSigintBecomeAStopRequest) {
  vp::platform::StopSignals signals;
  std::string why;
  ASSERT_TRUE(signals.install(&why)) << why;
  EXPECT_FALSE(vp::platform::StopSignals::stopRequested());
  ASSERT_EQ(std::raise(SIGTERM), 0);  // would kill the test without the handler
  EXPECT_TRUE(vp::platform::StopSignals::stopRequested());
  EXPECT_EQ(vp::platform::StopSignals::lastSignal(), SIGTERM);
}

TEST(Realtime, AffinityIsAppliedAndBadCpusAreNamed) {
  const std::array<int, 1> cpu0{0};
  std::string why;
  ASSERT_TRUE(vp::platform::setCurrentThreadAffinity(cpu0, &why)) << why;
  cpu_set_t set;
  ASSERT_EQ(::sched_getaffinity(0, sizeof(set), &set), 0);
  EXPECT_TRUE(CPU_ISSET(0, &set));
  EXPECT_EQ(CPU_COUNT(&set), 1);

  const std::array<int, 1> bad{4096};
  EXPECT_FALSE(vp::platform::setCurrentThreadAffinity(bad, &why));
  EXPECT_NE(why.find("CPU 4096"), std::string::npos) << why;
  EXPECT_FALSE(vp::platform::setCurrentThreadRealtime(120, &why));
  EXPECT_NE(why.find("outside 1..99"), std::string::npos) << why;
  EXPECT_TRUE(vp::platform::setCurrentThreadRealtime(0, &why));  // 0 = leave as is
}

TEST(Realtime, LockAllMemorySucceedsOrNamesTheCall) {
  std::string why;
  if (!vp::platform::lockAllMemory(&why)) {
    EXPECT_NE(why.find("mlockall"), std::string::npos) << why;  // e.g. no CAP_IPC_LOCK
  } else {
    ::munlockall();
  }
}

}  // namespace
