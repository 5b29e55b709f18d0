// core/transient_arena: a block reserved at start-up that serves the short-lived heap blocks a
// library allocates inside one call, so that a real-time loop calling that library allocates
// nothing (oneDNN 2.6 builds an argument map and an execution context on the heap in every
// primitive execution, and its API offers no allocator to hand it).
//
// Contract: a TransientArena reserves `capacity_bytes` in its constructor. While a
// TransientArena::Scope is open on a thread, every form of the replaceable global operator new
// called on that thread (plain, array, aligned, nothrow) takes its block from that arena: a bump
// pointer, aligned to 16 bytes or the requested alignment. operator delete of a block inside any
// live arena only counts it returned, on any thread. When a Scope closes with every block of the
// arena returned, the arena is empty again; a block still out (a library keeping one) stays valid
// and the arena is not rewound until it has been returned. A block that does not fit is taken
// from the heap as usual and counted (overflows()): still correct, but an allocation, which the
// owner reports. Only operator new is redirected: C code calling malloc is not. Scopes do not
// nest on a thread (an inner one is refused: isOpen() false) and one arena is used by one thread
// at a time. At most kMaxArenas arenas live at once; a further one has no block (every request
// overflows). Under AddressSanitizer, which replaces operator new itself, nothing is redirected:
// redirects() is false and every request is the heap's.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

namespace vp::core {

class TransientArena {
 public:
  static constexpr std::size_t kMaxArenas = 16;

  explicit TransientArena(std::size_t capacity_bytes);
  ~TransientArena();
  TransientArena(const TransientArena&) = delete;
  TransientArena& operator=(const TransientArena&) = delete;

  // Opens the arena for the calling thread's operator new until destruction (RAII).
  class Scope {
   public:
    explicit Scope(TransientArena& arena);
    ~Scope();
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;
    bool isOpen() const { return arena_ != nullptr; }

   private:
    TransientArena* arena_ = nullptr;
  };

  std::size_t capacity() const { return capacity_; }
  std::size_t blocksOut() const { return live_.load(std::memory_order_relaxed); }
  std::size_t highWaterBytes() const { return highWater_; }
  std::uint64_t blocksServed() const { return served_; }
  std::uint64_t overflows() const { return overflows_.load(std::memory_order_relaxed); }

  // True when this build redirects operator new (false under AddressSanitizer).
  static bool redirects();

  // Used by the replaced operators (transient_arena.cpp); not for callers.
  void* take(std::size_t bytes, std::size_t alignment);
  static bool giveBack(void* block);
  static TransientArena* current();

 private:
  std::unique_ptr<std::byte[]> block_;
  std::size_t capacity_ = 0;
  std::size_t offset_ = 0;     // next free byte; touched only by the thread with the open scope
  std::size_t highWater_ = 0;  // the largest offset reached
  std::uint64_t served_ = 0;
  std::atomic<std::size_t> live_{0};  // blocks handed out and not returned
  std::atomic<std::uint64_t> overflows_{0};
  int slot_ = -1;  // index in the registry of live arenas; -1 = not registered
};

}  // namespace vp::core
