#include "alloc_counter.hpp"

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <new>

#include <pthread.h>

namespace {

std::atomic<bool> gCounting{false};
std::atomic<std::size_t> gCount{0};
std::atomic<unsigned long> gThread{0};       // pthread_t of the only thread counted; 0 = all
std::atomic<unsigned long> gOtherThread{0};  // a second thread counted with it; 0 = none

inline void noteAllocation() {
  if (gCounting.load(std::memory_order_relaxed)) {
    const unsigned long only = gThread.load(std::memory_order_relaxed);
    const unsigned long self = static_cast<unsigned long>(pthread_self());
    if (only == 0 || only == self || gOtherThread.load(std::memory_order_relaxed) == self)
      gCount.fetch_add(1, std::memory_order_relaxed);
  }
}

}  // namespace

namespace vp::test {

AllocationCounter::AllocationCounter() {
  start();
}
AllocationCounter::~AllocationCounter() {
  stop();
}

void AllocationCounter::start() {
  gThread.store(0);
  gOtherThread.store(0);
  gCount.store(0);
  gCounting.store(true);
}
void AllocationCounter::startOnThread(unsigned long pthreadId) {
  startOnThreads(pthreadId, 0);
}
void AllocationCounter::startOnThreads(unsigned long pthreadId, unsigned long otherPthreadId) {
  gThread.store(pthreadId);
  gOtherThread.store(otherPthreadId);
  gCount.store(0);
  gCounting.store(true);
}
void AllocationCounter::stop() {
  gCounting.store(false);
}
std::size_t AllocationCounter::count() const {
  return gCount.load();
}

}  // namespace vp::test

#if defined(__SANITIZE_ADDRESS__)

// ASan intercepts malloc itself: count the replaceable operator new family instead.
bool vp::test::AllocationCounter::countsMalloc() {
  return false;
}

namespace {
void* countedNew(std::size_t size) {
  noteAllocation();
  if (void* p = std::malloc(size == 0 ? 1 : size))
    return p;
  throw std::bad_alloc();
}
void* countedAlignedNew(std::size_t size, std::align_val_t align) {
  noteAllocation();
  const auto a = static_cast<std::size_t>(align);
  const std::size_t rounded = ((size == 0 ? 1 : size) + a - 1) / a * a;
  if (void* p = std::aligned_alloc(a, rounded))
    return p;
  throw std::bad_alloc();
}
}  // namespace

void* operator new(std::size_t size) {
  return countedNew(size);
}
void* operator new[](std::size_t size) {
  return countedNew(size);
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  noteAllocation();
  return std::malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  noteAllocation();
  return std::malloc(size == 0 ? 1 : size);
}
void* operator new(std::size_t size, std::align_val_t align) {
  return countedAlignedNew(size, align);
}
void* operator new[](std::size_t size, std::align_val_t align) {
  return countedAlignedNew(size, align);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete(void* p, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}

#else

// glibc's internal entry points: the real allocator behind the public names.
extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* ptr, std::size_t size);
void __libc_free(void* ptr);
void* __libc_memalign(std::size_t alignment, std::size_t size);
}

bool vp::test::AllocationCounter::countsMalloc() {
  return true;
}

extern "C" {

void* malloc(std::size_t size) noexcept {
  noteAllocation();
  return __libc_malloc(size);
}

void* calloc(std::size_t count, std::size_t size) noexcept {
  noteAllocation();
  return __libc_calloc(count, size);
}

void* realloc(void* ptr, std::size_t size) noexcept {
  noteAllocation();
  return __libc_realloc(ptr, size);
}

void free(void* ptr) noexcept {
  __libc_free(ptr);
}

void* memalign(std::size_t alignment, std::size_t size) noexcept {
  noteAllocation();
  return __libc_memalign(alignment, size);
}

void* aligned_alloc(std::size_t alignment, std::size_t size) noexcept {
  noteAllocation();
  return __libc_memalign(alignment, size);
}

int posix_memalign(void** out, std::size_t alignment, std::size_t size) noexcept {
  if (alignment < sizeof(void*) || (alignment & (alignment - 1)) != 0)
    return EINVAL;
  noteAllocation();
  void* p = __libc_memalign(alignment, size);
  if (p == nullptr && size != 0)
    return ENOMEM;
  *out = p;
  return 0;
}

void* valloc(std::size_t size) noexcept {
  noteAllocation();
  return __libc_memalign(4096, size);
}

void* pvalloc(std::size_t size) noexcept {
  noteAllocation();
  return __libc_memalign(4096, (size + 4095) / 4096 * 4096);
}

}  // extern "C"

#endif
