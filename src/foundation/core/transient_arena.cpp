// core/transient_arena (contract in transient_arena.hpp): the arena, the registry of live arenas
// that operator delete consults, and the replaced global allocation functions.
#include "core/transient_arena.hpp"

#include <cstdlib>
#include <new>

#if defined(__SANITIZE_ADDRESS__)
#define VP_TRANSIENT_ARENA_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define VP_TRANSIENT_ARENA_ASAN 1
#endif
#endif

namespace vp::core {
namespace {

constexpr std::size_t kMinAlignment = 16;

// The live arenas' address ranges, read by every operator delete of the process: a fixed table
// of atomics, so the check is a few loads and never locks or allocates.
std::atomic<std::uintptr_t> gBegin[TransientArena::kMaxArenas];
std::atomic<std::uintptr_t> gEnd[TransientArena::kMaxArenas];
std::atomic<TransientArena*> gArena[TransientArena::kMaxArenas];

// The arena whose scope is open on this thread (a constant-initialised pointer: no TLS
// constructor runs, so operator new may read it at any point of a thread's life).
thread_local TransientArena* tOpen = nullptr;

// The mark of a slot whose arena is gone with a block still out (its range stays claimed).
TransientArena* retired() {
  return reinterpret_cast<TransientArena*>(alignof(TransientArena));
}

std::size_t roundUp(std::size_t value, std::size_t to) {
  return (value + to - 1) / to * to;
}

}  // namespace

TransientArena::TransientArena(std::size_t capacity_bytes) {
  if (capacity_bytes == 0)
    return;
  for (std::size_t i = 0; i < kMaxArenas; ++i) {
    TransientArena* expected = nullptr;
    if (gArena[i].compare_exchange_strong(expected, this)) {
      block_ = std::make_unique<std::byte[]>(capacity_bytes);
      capacity_ = capacity_bytes;
      const auto begin = reinterpret_cast<std::uintptr_t>(block_.get());
      gEnd[i].store(begin + capacity_bytes, std::memory_order_release);
      gBegin[i].store(begin, std::memory_order_release);
      slot_ = static_cast<int>(i);
      return;
    }
  }
  // No free slot: the arena has no block and every request overflows to the heap.
}

TransientArena::~TransientArena() {
  if (slot_ < 0)
    return;
  if (live_.load(std::memory_order_acquire) != 0) {
    // A block is still out (a library object that outlives this arena): its later delete must
    // still find the range and not reach free(), so the block is left allocated and the slot
    // keeps the range, marked retired, for the rest of the process.
    gArena[slot_].store(retired(), std::memory_order_release);
    static_cast<void>(block_.release());
    return;
  }
  gBegin[slot_].store(0, std::memory_order_release);
  gEnd[slot_].store(0, std::memory_order_release);
  gArena[slot_].store(nullptr, std::memory_order_release);
}

TransientArena::Scope::Scope(TransientArena& arena) {
  if (tOpen != nullptr)
    return;  // no nesting
  tOpen = &arena;
  arena_ = &arena;
}

TransientArena::Scope::~Scope() {
  if (arena_ == nullptr)
    return;
  tOpen = nullptr;
  if (arena_->live_.load(std::memory_order_acquire) == 0)
    arena_->offset_ = 0;
}

bool TransientArena::redirects() {
#ifdef VP_TRANSIENT_ARENA_ASAN
  return false;
#else
  return true;
#endif
}

TransientArena* TransientArena::current() {
  return tOpen;
}

void* TransientArena::take(std::size_t bytes, std::size_t alignment) {
  if (block_ == nullptr) {
    overflows_.fetch_add(1, std::memory_order_relaxed);
    return nullptr;
  }
  alignment = alignment < kMinAlignment ? kMinAlignment : alignment;
  const auto begin = reinterpret_cast<std::uintptr_t>(block_.get());
  const std::size_t start = roundUp(begin + offset_, alignment) - begin;
  if (start > capacity_ || bytes > capacity_ - start) {
    overflows_.fetch_add(1, std::memory_order_relaxed);
    return nullptr;
  }
  offset_ = start + bytes;
  if (offset_ > highWater_)
    highWater_ = offset_;
  ++served_;
  live_.fetch_add(1, std::memory_order_relaxed);
  return block_.get() + start;
}

bool TransientArena::giveBack(void* block) {
  const auto a = reinterpret_cast<std::uintptr_t>(block);
  for (std::size_t i = 0; i < kMaxArenas; ++i) {
    const std::uintptr_t begin = gBegin[i].load(std::memory_order_acquire);
    if (begin != 0 && a >= begin && a < gEnd[i].load(std::memory_order_acquire)) {
      TransientArena* arena = gArena[i].load(std::memory_order_acquire);
      if (arena != nullptr && arena != retired())
        arena->live_.fetch_sub(1, std::memory_order_acq_rel);
      return true;
    }
  }
  return false;
}

}  // namespace vp::core

#ifndef VP_TRANSIENT_ARENA_ASAN

// The replaceable global allocation functions (every form): from the open arena when a scope is
// open on this thread and the block fits, else from the heap with the standard's new-handler loop.
namespace {

void* allocate(std::size_t size, std::size_t alignment) {
  if (size == 0)
    size = 1;
  if (vp::core::TransientArena* arena = vp::core::TransientArena::current())
    if (void* p = arena->take(size, alignment))
      return p;
  for (;;) {
    void* p = alignment <= alignof(std::max_align_t)
                  ? std::malloc(size)
                  : std::aligned_alloc(alignment, (size + alignment - 1) / alignment * alignment);
    if (p != nullptr)
      return p;
    const std::new_handler handler = std::get_new_handler();
    if (handler == nullptr)
      throw std::bad_alloc();
    handler();
  }
}

void* allocateNoThrow(std::size_t size, std::size_t alignment) noexcept {
  try {
    return allocate(size, alignment);
  } catch (...) {
    return nullptr;
  }
}

void release(void* p) noexcept {
  if (p == nullptr || vp::core::TransientArena::giveBack(p))
    return;
  std::free(p);
}

}  // namespace

void* operator new(std::size_t size) {
  return allocate(size, alignof(std::max_align_t));
}
void* operator new[](std::size_t size) {
  return allocate(size, alignof(std::max_align_t));
}
void* operator new(std::size_t size, std::align_val_t alignment) {
  return allocate(size, static_cast<std::size_t>(alignment));
}
void* operator new[](std::size_t size, std::align_val_t alignment) {
  return allocate(size, static_cast<std::size_t>(alignment));
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  return allocateNoThrow(size, alignof(std::max_align_t));
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  return allocateNoThrow(size, alignof(std::max_align_t));
}
void* operator new(std::size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
  return allocateNoThrow(size, static_cast<std::size_t>(alignment));
}
void* operator new[](std::size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
  return allocateNoThrow(size, static_cast<std::size_t>(alignment));
}

void operator delete(void* p) noexcept {
  release(p);
}
void operator delete[](void* p) noexcept {
  release(p);
}
void operator delete(void* p, std::size_t) noexcept {
  release(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  release(p);
}
void operator delete(void* p, std::align_val_t) noexcept {
  release(p);
}
void operator delete[](void* p, std::align_val_t) noexcept {
  release(p);
}
void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
  release(p);
}
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept {
  release(p);
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
  release(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
  release(p);
}
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  release(p);
}
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  release(p);
}

#endif
