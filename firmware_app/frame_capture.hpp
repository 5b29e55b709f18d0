// firmware_app/frame_capture: the capture side of the loop: the frame source, the frame pool,
// the frame channel between the two threads and the capture thread that fills it.
//
// Contract: openFrameSource() builds the configured source (a replay of source.sequence_dir
// or the V4L2 camera on the given device) and fails naming the key or the file. open() takes
// that source over (unique_ptr: FrameCapture owns it, its pool and its channel from then on)
// and allocates the pool (poolSize frames of the source's size) and the channel of `depth`
// (in [1, 8]); it fails naming the key. start() runs the capture thread: a free pool frame ->
// source.next() -> the channel (drop-oldest when the processing thread falls behind, counted;
// with everyFrame it waits for room instead), until the source ends, maxFrames were taken or
// a stop is requested (requestStop() or a stop signal). With a recorder (CaptureSettings), every
// frame taken from the source is offered to it first (a copy into one of its buffers, or a
// count), so that a recording holds the frames the channel later drops too. The processing thread
// takes frames with take(), reads them with frame() and capture_ns() (capture time on the loop
// clock), gives them back with release(), and sleeps on waitFor(wakeCount(), timeout) between
// frames (woken by each frame, bad frame and source retry, or by the timeout); heartbeat() moves
// while the capture thread lives, so the processing thread can feed the watchdog while no frame
// comes (a silent camera) and stop feeding it when capture hangs; done()
// says the capture thread has ended. stop() ends and joins the capture thread and returns
// every waiting frame to the pool, counted as dropped (the destructor only ends and joins it).
// Bad frames and device events are counted (addCounters()), logged once where they happen, and
// capture goes on. The clock given to open() is borrowed and must outlive the FrameCapture.
//
// Stopping: FrameCapture is the loop's StopCondition (requestStop() or a stop signal); the app
// hands it to the clock, so every wait of the capture thread (paced replay, backoff, camera
// reopen) ends within platform::kStopPoll_ns of a stop, and the capture thread then ends and
// wakes the processing thread.
//
// Accounting: after stop(), the counts account for every frame taken from the source:
// framesIn == framesProcessed + framesDropped + badFrames + pipelineErrors, where framesIn
// counts every frame the source gave (good or bad), framesDropped the frames evicted from the
// channel and those still waiting in it at stop, and the processing side counts the rest.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "config/config.hpp"
#include "core/frame_pool.hpp"
#include "loop_inputs.hpp"
#include "loop_stats.hpp"
#include "platform/clock/monotonic_clock.hpp"
#include "platform/v4l2/v4l2_camera.hpp"

namespace vp::app {

class FrameQueue;  // the FrameChannel of the configured depth (frame_capture.cpp)
class Recorder;    // recorder.hpp

// The source of source.kind: a ReplayFrameSource or a CameraFrameSource on device (used
// only for a camera); nullptr
// (and *why) when it cannot be opened.
std::unique_ptr<FrameSource> openFrameSource(const config::SourceConfig& config,
                                             platform::Clock& clock,
                                             platform::v4l2::V4l2Device* device, std::string* why);

struct CaptureSettings {
  std::int64_t maxFrames = 0;    // frames taken from the source; 0 = unlimited
  bool everyFrame = false;       // the source waits for the loop instead of dropping
  std::vector<int> cpus;         // affinity of the capture thread; empty = any
  Recorder* recorder = nullptr;  // offered every frame taken from the source; null = none
};

class FrameCapture final : public platform::StopCondition {
 public:
  FrameCapture();
  ~FrameCapture();
  FrameCapture(const FrameCapture&) = delete;
  FrameCapture& operator=(const FrameCapture&) = delete;

  bool open(std::unique_ptr<FrameSource> source, platform::Clock& clock, int poolSize, int depth,
            std::string* why);
  void start(const CaptureSettings& settings);
  void requestStop() { stop_.store(true, std::memory_order_relaxed); }
  bool stopRequested() const override;
  void stop();

  // Processing thread.
  std::optional<FrameIndex> take();
  bool done() const { return done_.load(std::memory_order_acquire); }
  std::uint32_t wakeCount() const;
  // Until the capture thread wakes it (a frame, a bad frame, a retry, the end) or timeout_ns.
  void waitFor(std::uint32_t seen, std::int64_t timeout_ns) const;
  // Moves while the capture thread is alive: at every step of its loop and while it waits on
  // the clock (it polls the stop condition); stands still when it hangs, e.g. in a driver call.
  std::uint64_t heartbeat() const { return heartbeat_.load(std::memory_order_relaxed); }
  const Frame& frame(FrameIndex index) const { return pool_.frame(index); }
  std::int64_t capture_ns(FrameIndex index) const { return captureNs_[index]; }
  void release(FrameIndex index) { pool_.release(index); }

  const FrameSource& source() const { return *source_; }
  const FramePool& pool() const { return pool_; }
  // The capture thread's counts and the channel's drops into c (framesIn, badFrames,
  // sourceTimeouts, deviceLosses, deviceReopens, framesDropped: evicted + left at stop).
  void addCounters(LoopCounters& c) const;

 private:
  void captureLoop();

  platform::Clock* clock_ = nullptr;
  CaptureSettings settings_{};
  std::unique_ptr<FrameSource> source_;
  FramePool pool_;
  std::unique_ptr<FrameQueue> queue_;
  std::size_t depth_ = 0;
  std::array<std::int64_t, FramePool::kMaxFrames> captureNs_{};  // loop clock, per pool frame
  CaptureCounters counters_;
  std::atomic<std::uint64_t> leftAtStop_{0};  // frames still in the channel at stop()
  std::atomic<bool> stop_{false};
  std::atomic<std::thread::id> captureThread_{};
  mutable std::atomic<std::uint64_t> heartbeat_{0};
  std::atomic<bool> done_{false};
  std::thread thread_;
};

}  // namespace vp::app
