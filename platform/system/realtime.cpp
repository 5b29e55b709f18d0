#include "platform/system/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

namespace vp::platform {

bool lockAllMemory(std::string* why) {
  if (::mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    if (why)
      *why = std::string("mlockall(MCL_CURRENT | MCL_FUTURE): ") + std::strerror(errno);
    return false;
  }
  return true;
}

bool setCurrentThreadRealtime(int priority, std::string* why) {
  if (priority == 0) {
    return true;
  }
  if (priority < 1 || priority > 99) {
    if (why)
      *why = "SCHED_FIFO priority " + std::to_string(priority) + " outside 1..99";
    return false;
  }
  sched_param param{};
  param.sched_priority = priority;
  const int rc = ::pthread_setschedparam(::pthread_self(), SCHED_FIFO, &param);
  if (rc != 0) {
    if (why)
      *why = "SCHED_FIFO priority " + std::to_string(priority) + ": " + std::strerror(rc);
    return false;
  }
  return true;
}

bool setCurrentThreadAffinity(std::span<const int> cpus, std::string* why) {
  if (cpus.empty()) {
    return true;
  }
  const long online = ::sysconf(_SC_NPROCESSORS_CONF);
  cpu_set_t set;
  CPU_ZERO(&set);
  for (const int cpu : cpus) {
    if (cpu < 0 || cpu >= online || cpu >= CPU_SETSIZE) {
      if (why)
        *why = "CPU affinity: CPU " + std::to_string(cpu) + " outside 0.." +
               std::to_string(online - 1);
      return false;
    }
    CPU_SET(cpu, &set);
  }
  const int rc = ::pthread_setaffinity_np(::pthread_self(), sizeof(set), &set);
  if (rc != 0) {
    if (why)
      *why = std::string("CPU affinity: ") + std::strerror(rc);
    return false;
  }
  return true;
}

void setCurrentThreadName(const char* name) {
  char truncated[16] = {};
  std::strncpy(truncated, name, sizeof(truncated) - 1);
  ::pthread_setname_np(::pthread_self(), truncated);
}

}  // namespace vp::platform
