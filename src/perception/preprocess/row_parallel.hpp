// preprocess/row_parallel: splits image rows over a small fixed thread pool (pthreadpool).
//
// Contract: init(threads) creates the pool once (threads = 1: no pool, the caller's thread
// does all the work). run(rows, body) calls body(rowBegin, rowEnd, slot) for `slots()`
// contiguous, disjoint blocks covering [0, rows) and returns when all are done; slot in
// [0, slots()) identifies the block so bodies can use per-slot scratch. No heap allocation
// per call. Not re-entrant: one run() at a time per pool.
#pragma once

#include <cstddef>
#include <string>

#include <pthreadpool.h>

namespace vp::preprocess {

class RowParallel {
 public:
  RowParallel() = default;
  ~RowParallel();
  RowParallel(const RowParallel&) = delete;
  RowParallel& operator=(const RowParallel&) = delete;

  bool init(int threads, std::string* why = nullptr);
  int slots() const { return threads_; }

  template <class Body>
  void run(int rows, Body& body) {
    if (threads_ <= 1 || pool_ == nullptr || rows < 2 * threads_) {
      body(0, rows, 0);
      return;
    }
    Context<Body> context{&body, rows, threads_};
    // Workers sleep after the job instead of spinning: the engines' own pools need the cores.
    pthreadpool_parallelize_1d(pool_, &Context<Body>::task, &context,
                               static_cast<std::size_t>(threads_), PTHREADPOOL_FLAG_YIELD_WORKERS);
  }

 private:
  template <class Body>
  struct Context {
    Body* body;
    int rows;
    int blocks;
    static void task(void* raw, std::size_t index) {
      auto* self = static_cast<Context*>(raw);
      const int block = static_cast<int>(index);
      const int begin = static_cast<int>(static_cast<long long>(self->rows) * block / self->blocks);
      const int end =
          static_cast<int>(static_cast<long long>(self->rows) * (block + 1) / self->blocks);
      (*self->body)(begin, end, block);
    }
  };

  pthreadpool_t pool_ = nullptr;
  int threads_ = 1;
};

}  // namespace vp::preprocess
