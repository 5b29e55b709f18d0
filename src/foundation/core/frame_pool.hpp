// core/frame_pool: the fixed set of camera-size image buffers the frame sources fill and the
// pipeline reads, and the channel that hands them from the capture thread to the pipeline.
//
// Contract: FramePool::init() allocates N BGR8 frames once (start-up; it is the only call
// that allocates and the only one that can fail). acquire() hands out the index of a free
// frame (or nothing when all are in use), release() gives it back; both are lock-free, never
// allocate and may be called from any thread. A frame's image is never reallocated: writers
// fill it in place (cv::Mat headers over it share the buffer, they do not copy it). The frame
// carries its capture timestamp (ns, the source's monotonic clock), frame id and the status
// the source reported.
//
// FrameChannel<kDepth> is the app's capture -> pipeline hand-over: the producer publishes
// filled frames; when kDepth frames are already waiting, the oldest waiting frame goes back
// to the pool and is counted as dropped (the pipeline always gets the freshest frames, the
// camera never waits). One producer thread and one consumer thread (see SpscQueue).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "core/spsc_queue.hpp"

namespace vp {

using FrameIndex = std::uint32_t;

// What the source knows about the image it delivered.
enum class FrameStatus : std::uint8_t {
  Ok,
  Damaged,  // the driver flagged the capture (V4L2_BUF_FLAG_ERROR): pixels may be garbage
};
const char* toString(FrameStatus status);

struct Frame {
  cv::Mat image;                  // CV_8UC3 BGR, width_px x height_px, allocated by init()
  std::int64_t timestamp_ns = 0;  // capture time, monotonic clock of the source
  std::int64_t frameId = 0;       // increasing per source (gaps = frames the source lost)
  FrameStatus status = FrameStatus::Ok;
};

class FramePool {
 public:
  static constexpr std::size_t kMaxFrames = 64;  // one bit each in the free mask
  static constexpr int kDefaultWidth_px = 2592;  // seed 000's camera
  static constexpr int kDefaultHeight_px = 2048;

  FramePool() = default;
  FramePool(const FramePool&) = delete;
  FramePool& operator=(const FramePool&) = delete;

  // Allocates `count` frames (1..kMaxFrames) of width_px x height_px BGR8, all free.
  bool init(std::size_t count, int width_px = kDefaultWidth_px, int height_px = kDefaultHeight_px,
            std::string* why = nullptr);

  std::size_t capacity() const { return frames_.size(); }
  std::size_t available() const;  // free frames now (a snapshot)
  int width_px() const { return widthPx_; }
  int height_px() const { return heightPx_; }

  // A free frame's index, now owned by the caller; nothing when every frame is in use.
  std::optional<FrameIndex> acquire();
  // Returns an acquired frame. False (and nothing changes) for an index that is out of range
  // or already free: a double release is a bug of the caller, reported rather than hidden.
  bool release(FrameIndex index);

  Frame& frame(FrameIndex index) { return frames_[index]; }
  const Frame& frame(FrameIndex index) const { return frames_[index]; }

 private:
  std::vector<Frame> frames_;
  std::atomic<std::uint64_t> freeMask_{0};  // bit i set = frame i is free
  int widthPx_ = 0;
  int heightPx_ = 0;
};

template <std::size_t kDepth>
class FrameChannel {
 public:
  explicit FrameChannel(FramePool& pool) : pool_(pool) {}

  // Producer: queues a filled frame (owned by the caller until now). When the channel is
  // full, the oldest waiting frame is returned to the pool and counted as dropped.
  void publish(FrameIndex index) {
    if (const std::optional<FrameIndex> evicted = queue_.pushDropOldest(index)) {
      pool_.release(*evicted);
      dropped_.fetch_add(1, std::memory_order_relaxed);
    }
  }

  // Consumer: the oldest waiting frame, now owned by the caller (release it to the pool).
  std::optional<FrameIndex> take() { return queue_.tryPop(); }

  // Returns every waiting frame to the pool (at stop, once the producer has stopped).
  std::size_t drain() {
    std::size_t drained = 0;
    while (const std::optional<FrameIndex> index = queue_.tryPop()) {
      pool_.release(*index);
      ++drained;
    }
    return drained;
  }

  std::uint64_t droppedFrames() const { return dropped_.load(std::memory_order_relaxed); }
  std::size_t waiting() const { return queue_.size(); }

 private:
  FramePool& pool_;
  SpscQueue<FrameIndex, kDepth> queue_;
  std::atomic<std::uint64_t> dropped_{0};
};

}  // namespace vp
