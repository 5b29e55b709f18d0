// core/spsc_queue: a bounded, lock-free queue of small values between one producer thread and
// one consumer thread (the camera thread hands frame indices to the pipeline thread).
//
// Contract: SpscQueue<T, N> holds at most N values of a trivially copyable T whose
// std::atomic<T> is lock-free (an index, a small id). Nothing allocates, nothing blocks,
// nothing throws. Only the producer calls tryPush()/pushDropOldest(); only the consumer calls
// tryPop(); size() and empty() may be called from either side and are a snapshot.
//
// Why "drop oldest" is safe here: both indices are 64-bit counters that only grow (no ABA in
// any realistic run). The producer alone advances `tail_`; `head_` is advanced by a
// compare-and-swap, by the consumer when it pops and by the producer when it evicts the
// oldest value of a full queue. Whoever wins the CAS on head h owns the value of slot h; the
// loser retries. The producer writes slot t only after it has seen head > t - N, and a
// consumer's read of that slot happened before its (failed or successful) CAS on the head the
// producer saw, so a value is never overwritten while someone may still take it. Slots are
// std::atomic<T> (relaxed) so that the speculative read of a slot the producer is about to
// reuse is not a data race; its value is then discarded because the CAS fails.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <type_traits>

namespace vp {

template <class T, std::size_t N>
class SpscQueue {
  static_assert(N >= 1, "SpscQueue needs at least one slot");
  static_assert(std::is_trivially_copyable_v<T>, "SpscQueue holds small trivially copyable values");
  static_assert(std::atomic<T>::is_always_lock_free, "SpscQueue needs a lock-free std::atomic<T>");

 public:
  static constexpr std::size_t capacity() { return N; }

  // Producer: appends `value`; false (and nothing changes) when the queue is full.
  bool tryPush(T value) {
    const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
    if (tail - head_.load(std::memory_order_acquire) >= N) {
      return false;
    }
    slots_[tail % N].store(value, std::memory_order_relaxed);
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  // Producer: appends `value` always. When the queue is full, the oldest value is taken out
  // first and returned, so that the caller can recycle it (a frame buffer back to its pool).
  std::optional<T> pushDropOldest(T value) {
    std::optional<T> evicted;
    const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
    for (;;) {
      std::uint64_t head = head_.load(std::memory_order_acquire);
      if (tail - head < N) {
        break;
      }
      const T oldest = slots_[head % N].load(std::memory_order_relaxed);
      if (head_.compare_exchange_strong(head, head + 1, std::memory_order_acq_rel,
                                        std::memory_order_acquire)) {
        evicted = oldest;
        break;
      }
      // The consumer popped it first: there is room now (checked again by the loop).
    }
    slots_[tail % N].store(value, std::memory_order_relaxed);
    tail_.store(tail + 1, std::memory_order_release);
    return evicted;
  }

  // Consumer: the oldest value, or nothing when the queue is empty.
  std::optional<T> tryPop() {
    std::uint64_t head = head_.load(std::memory_order_acquire);
    for (;;) {
      if (head == tail_.load(std::memory_order_acquire)) {
        return std::nullopt;
      }
      const T value = slots_[head % N].load(std::memory_order_relaxed);
      // On failure `head` is reloaded: the producer evicted the value we read.
      if (head_.compare_exchange_weak(head, head + 1, std::memory_order_acq_rel,
                                      std::memory_order_acquire)) {
        return value;
      }
    }
  }

  std::size_t size() const {
    const std::uint64_t head = head_.load(std::memory_order_acquire);
    const std::uint64_t tail = tail_.load(std::memory_order_acquire);
    return tail > head ? static_cast<std::size_t>(tail - head) : 0;
  }
  bool empty() const { return size() == 0; }

 private:
  // Separate cache lines: the two threads each write one index.
  alignas(64) std::atomic<std::uint64_t> head_{0};
  alignas(64) std::atomic<std::uint64_t> tail_{0};
  alignas(64) std::array<std::atomic<T>, N> slots_{};
};

}  // namespace vp
