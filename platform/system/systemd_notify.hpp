// platform/system/systemd_notify: the service manager's readiness and watchdog protocol.
//
// Contract: open() reads $NOTIFY_SOCKET (a filesystem path or, with a leading '@', an abstract
// AF_UNIX address) and $WATCHDOG_USEC / $WATCHDOG_PID as systemd sets them for Type=notify
// services, and opens one datagram socket. Without $NOTIFY_SOCKET (run by hand, in tests, in a
// container) the notifier is disabled: open() succeeds and every call is a no-op returning
// true, so the loop needs no special case. ready(), watchdog(), stopping() and status() send
// one datagram each ("READY=1", "WATCHDOG=1", "STOPPING=1", "STATUS=..."), never allocate and
// never block (MSG_DONTWAIT); a failed send returns false and the caller logs it. The protocol
// is systemd's sd_notify(3); this is our own implementation of it so the app needs no
// libsystemd. Not thread-safe: one thread (the loop) notifies.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace vp::platform {

class SystemdNotifier {
 public:
  SystemdNotifier() = default;
  ~SystemdNotifier();
  SystemdNotifier(const SystemdNotifier&) = delete;
  SystemdNotifier& operator=(const SystemdNotifier&) = delete;

  // Reads the environment; fails only when $NOTIFY_SOCKET is set but unusable.
  bool open(std::string* why);
  void close();

  bool enabled() const { return fd_ >= 0; }
  // Interval at which watchdog() must be called (half of WatchdogSec, as systemd advises);
  // 0 when the service has no watchdog or $WATCHDOG_PID names another process.
  std::int64_t watchdogInterval_ns() const { return watchdogIntervalNs_; }

  bool ready() { return send("READY=1"); }
  bool watchdog() { return send("WATCHDOG=1"); }
  bool stopping() { return send("STOPPING=1"); }
  bool status(std::string_view text);  // "STATUS=<text>", text truncated to 200 bytes

 private:
  bool send(std::string_view message);

  int fd_ = -1;
  std::int64_t watchdogIntervalNs_ = 0;
  // sockaddr_un kept as raw bytes so this header needs no system headers.
  alignas(8) unsigned char address_[112] = {};
  unsigned addressLength_ = 0;
};

}  // namespace vp::platform
