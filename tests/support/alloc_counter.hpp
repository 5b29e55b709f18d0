// tests/support/alloc_counter: counts heap allocations made by the whole process, for the
// "no allocation in the real-time path" tests.
//
// Contract: while an AllocationCounter is counting (from construction or start() to stop()
// or destruction), every allocation on any thread is counted: the glibc malloc family
// (malloc, calloc, realloc, posix_memalign, aligned_alloc, memalign, valloc, pvalloc) is
// interposed by definitions in this library that forward to glibc's __libc_* entry points,
// so operator new, XNNPACK and pthreadpool workers are all seen. Frees are not counted.
// Under AddressSanitizer (which owns malloc itself) only the replaceable operator new/new[]
// family is counted: countsMalloc() says which mode is active. One counter at a time.
#pragma once

#include <cstddef>

namespace vp::test {

class AllocationCounter {
 public:
  AllocationCounter();  // resets and starts counting
  ~AllocationCounter();
  AllocationCounter(const AllocationCounter&) = delete;
  AllocationCounter& operator=(const AllocationCounter&) = delete;

  void start();  // resets the count and starts counting (every thread)
  // Resets and counts only the allocations made by one thread (its pthread_t as an integer):
  // e.g. the processing thread of a loop whose capture thread is allowed to allocate.
  void startOnThread(unsigned long pthreadId);
  // The same for two threads (e.g. the pipelined loop's detector and processing threads).
  void startOnThreads(unsigned long pthreadId, unsigned long otherPthreadId);
  void stop();
  std::size_t count() const;  // allocations seen while counting

  // True when the malloc family is interposed; false under ASan (operator new only).
  static bool countsMalloc();
};

}  // namespace vp::test
