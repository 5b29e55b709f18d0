// platform/system/realtime: the process and thread settings of a real-time service.
//
// Contract: each call applies one OS setting to the process or to the calling thread and
// returns false with a message naming the setting and the OS error when it cannot (e.g. no
// CAP_IPC_LOCK for mlockall, no CAP_SYS_NICE or RLIMIT_RTPRIO for SCHED_FIFO, a CPU outside
// the machine). The app calls them once at start-up, from the thread concerned, and decides
// whether a failure is fatal (config) or only logged. No product logic here.
#pragma once

#include <span>
#include <string>

namespace vp::platform {

// mlockall(MCL_CURRENT | MCL_FUTURE): no page faults to disk in the loop.
bool lockAllMemory(std::string* why);

// SCHED_FIFO at `priority` (1..99) for the calling thread; 0 = leave SCHED_OTHER.
bool setCurrentThreadRealtime(int priority, std::string* why);

// Pins the calling thread to the given CPUs (empty = leave as is).
bool setCurrentThreadAffinity(std::span<const int> cpus, std::string* why);

// Names the calling thread (15 characters at most, shown by top -H, ps -L, gdb).
void setCurrentThreadName(const char* name);

}  // namespace vp::platform
