#include "preprocess/row_parallel.hpp"

namespace vp::preprocess {

RowParallel::~RowParallel() {
  if (pool_ != nullptr) {
    pthreadpool_destroy(pool_);
  }
}

bool RowParallel::init(int threads, std::string* why) {
  if (threads < 1) {
    if (why != nullptr) {
      *why = "threads: must be >= 1, got " + std::to_string(threads);
    }
    return false;
  }
  if (pool_ != nullptr) {
    pthreadpool_destroy(pool_);
    pool_ = nullptr;
  }
  threads_ = threads;
  if (threads > 1) {
    pool_ = pthreadpool_create(static_cast<std::size_t>(threads));
    if (pool_ == nullptr) {
      threads_ = 1;
      if (why != nullptr) {
        *why = "threads: cannot create a pool of " + std::to_string(threads) + " threads";
      }
      return false;
    }
  }
  return true;
}

}  // namespace vp::preprocess
