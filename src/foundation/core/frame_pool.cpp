#include "core/frame_pool.hpp"

#include <bit>

namespace vp {

const char* toString(FrameStatus status) {
  switch (status) {
    case FrameStatus::Ok:
      return "ok";
    case FrameStatus::Damaged:
      return "damaged";
  }
  return "unknown";
}

bool FramePool::init(std::size_t count, int width_px, int height_px, std::string* why) {
  auto fail = [why](std::string message) {
    if (why != nullptr) {
      *why = "FramePool::init: " + std::move(message);
    }
    return false;
  };
  if (count == 0 || count > kMaxFrames) {
    return fail("frame count " + std::to_string(count) + " outside 1.." +
                std::to_string(kMaxFrames));
  }
  if (width_px <= 0 || height_px <= 0) {
    return fail("frame size " + std::to_string(width_px) + "x" + std::to_string(height_px) +
                " must be positive");
  }
  frames_.clear();
  frames_.resize(count);
  for (Frame& frame : frames_) {
    frame.image.create(height_px, width_px, CV_8UC3);
    frame.image.setTo(cv::Scalar::all(0));  // touch every page now, not in the first capture
  }
  widthPx_ = width_px;
  heightPx_ = height_px;
  const std::uint64_t mask = count == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << count) - 1;
  freeMask_.store(mask, std::memory_order_release);
  return true;
}

std::size_t FramePool::available() const {
  return static_cast<std::size_t>(std::popcount(freeMask_.load(std::memory_order_acquire)));
}

std::optional<FrameIndex> FramePool::acquire() {
  std::uint64_t mask = freeMask_.load(std::memory_order_acquire);
  while (mask != 0) {
    const int bit = std::countr_zero(mask);
    const std::uint64_t taken = mask & ~(std::uint64_t{1} << bit);
    if (freeMask_.compare_exchange_weak(mask, taken, std::memory_order_acq_rel,
                                        std::memory_order_acquire)) {
      return static_cast<FrameIndex>(bit);
    }
  }
  return std::nullopt;
}

bool FramePool::release(FrameIndex index) {
  if (index >= frames_.size()) {
    return false;
  }
  const std::uint64_t bit = std::uint64_t{1} << index;
  const std::uint64_t before = freeMask_.fetch_or(bit, std::memory_order_acq_rel);
  return (before & bit) == 0;
}

}  // namespace vp
