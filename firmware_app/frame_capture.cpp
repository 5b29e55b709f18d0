#include "frame_capture.hpp"

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <utility>

#include "core/spsc_queue.hpp"
#include "csv/csv_io.hpp"
#include "loop_log.hpp"
#include "platform/system/realtime.hpp"
#include "platform/system/stop_signals.hpp"
#include "recorder.hpp"

namespace vp::app {

namespace {

constexpr std::int64_t kNsPer_ms = 1'000'000;
constexpr int kMaxQueueDepth = 8;                       // app.queue_depth's upper bound
constexpr std::int64_t kCaptureBackoff_ns = kNsPer_ms;  // capture waits this long on a retry

void sleep_ns(platform::Clock& clock, std::int64_t ns) {
  clock.sleepUntil_ns(clock.now_ns() + ns);
}

}  // namespace

// The FrameChannel's depth is a template argument; the configured depth picks one instance.
class FrameQueue {
 public:
  virtual ~FrameQueue() = default;
  virtual void publish(FrameIndex index) = 0;
  virtual std::optional<FrameIndex> take() = 0;
  virtual std::size_t drain() = 0;
  virtual std::uint64_t dropped() const = 0;
  virtual std::size_t waiting() const = 0;

  // Wakes the processing thread: bumped after every publish and when capture ends.
  void notify() {
    wake_.fetch_add(1, std::memory_order_release);
    // Taking the mutex after the increment: a waiter between its check and its sleep holds it,
    // so the wake-up cannot fall between the two.
    { const std::lock_guard<std::mutex> lock(mutex_); }
    wakeup_.notify_one();
  }
  std::uint32_t wakeCount() const { return wake_.load(std::memory_order_acquire); }
  // Until the count moves past `seen` or timeout_ns passed (no allocation).
  void waitFor(std::uint32_t seen, std::int64_t timeout_ns) const {
    std::unique_lock<std::mutex> lock(mutex_);
    wakeup_.wait_for(lock, std::chrono::nanoseconds(timeout_ns),
                     [&] { return wake_.load(std::memory_order_acquire) != seen; });
  }

  static std::unique_ptr<FrameQueue> make(int depth, FramePool& pool);

 private:
  std::atomic<std::uint32_t> wake_{0};
  mutable std::mutex mutex_;
  mutable std::condition_variable wakeup_;
};

namespace {

template <std::size_t kDepth>
class FrameQueueOf final : public FrameQueue {
 public:
  explicit FrameQueueOf(FramePool& pool) : channel_(pool) {}
  void publish(FrameIndex index) override { channel_.publish(index); }
  std::optional<FrameIndex> take() override { return channel_.take(); }
  std::size_t drain() override { return channel_.drain(); }
  std::uint64_t dropped() const override { return channel_.droppedFrames(); }
  std::size_t waiting() const override { return channel_.waiting(); }

 private:
  FrameChannel<kDepth> channel_;
};

template <std::size_t... kDepths>
std::unique_ptr<FrameQueue> makeQueue(int depth, FramePool& pool, std::index_sequence<kDepths...>) {
  std::unique_ptr<FrameQueue> queue;
  ((depth == static_cast<int>(kDepths + 1)
        ? (void)(queue = std::make_unique<FrameQueueOf<kDepths + 1>>(pool))
        : (void)0),
   ...);
  return queue;
}

}  // namespace

std::unique_ptr<FrameQueue> FrameQueue::make(int depth, FramePool& pool) {
  return makeQueue(depth, pool, std::make_index_sequence<kMaxQueueDepth>{});
}

std::unique_ptr<FrameSource> openFrameSource(const config::SourceConfig& source,
                                             platform::Clock& clock,
                                             platform::v4l2::V4l2Device* device, std::string* why) {
  if (source.kind == config::FrameSourceKind::Replay) {
    if (source.sequenceDir.empty()) {
      if (why) {
        *why =
            "source.sequence_dir: no recorded sequence to replay (give --sequence DIR, "
            "or --camera for a V4L2 camera)";
      }
      return nullptr;
    }
    auto replay = std::make_unique<ReplayFrameSource>(clock);
    std::string problem;
    if (!replay->open(source.sequenceDir, source.paced, source.loop, &problem)) {
      if (why) {
        *why = "sequence " + csv::shortened(source.sequenceDir) + ": " + problem;
      }
      return nullptr;
    }
    return replay;
  }
  if (source.kind == config::FrameSourceKind::Video) {
    auto video = std::make_unique<VideoFrameSource>(clock);
    if (!video->open(source, why)) {
      return nullptr;
    }
    return video;
  }
  auto camera = std::make_unique<CameraFrameSource>(*device, clock);
  if (!camera->open(source.v4l2, why)) {
    return nullptr;
  }
  return camera;
}

FrameCapture::FrameCapture() = default;

FrameCapture::~FrameCapture() {
  requestStop();
  if (thread_.joinable()) {
    thread_.join();
  }
}

bool FrameCapture::open(std::unique_ptr<FrameSource> source, platform::Clock& clock, int poolSize,
                        int depth, std::string* why) {
  source_ = std::move(source);
  clock_ = &clock;
  std::string problem;
  if (!pool_.init(static_cast<std::size_t>(poolSize), source_->width_px(), source_->height_px(),
                  &problem)) {
    if (why) {
      *why = "frame pool: " + problem;
    }
    return false;
  }
  queue_ = FrameQueue::make(depth, pool_);
  depth_ = static_cast<std::size_t>(depth);
  if (!queue_) {
    if (why) {
      *why = "app.queue_depth: " + std::to_string(depth) + " is not in [1, 8]";
    }
    return false;
  }
  return true;
}

void FrameCapture::start(const CaptureSettings& settings) {
  settings_ = settings;
  thread_ = std::thread(&FrameCapture::captureLoop, this);
}

bool FrameCapture::stopRequested() const {
  // The capture thread asks at every step of its loop and every few ms of each wait on the
  // clock (replay pacing, backoff, camera reopen): each question is a sign of life.
  if (std::this_thread::get_id() == captureThread_.load(std::memory_order_relaxed)) {
    heartbeat_.fetch_add(1, std::memory_order_relaxed);
  }
  return stop_.load(std::memory_order_relaxed) || platform::StopSignals::stopRequested();
}

void FrameCapture::stop() {
  requestStop();
  if (thread_.joinable()) {
    thread_.join();
  }
  // Every waiting frame back in the pool; frames taken from the source but never processed
  // are drops like the channel's evictions, so the counts still add up.
  if (queue_) {
    leftAtStop_.fetch_add(queue_->drain(), std::memory_order_relaxed);
  }
}

std::optional<FrameIndex> FrameCapture::take() {
  return queue_->take();
}

std::uint32_t FrameCapture::wakeCount() const {
  return queue_->wakeCount();
}

void FrameCapture::waitFor(std::uint32_t seen, std::int64_t timeout_ns) const {
  queue_->waitFor(seen, timeout_ns);
}

void FrameCapture::addCounters(LoopCounters& c) const {
  c.framesIn = counters_.framesIn.load(std::memory_order_relaxed);
  c.badFrames = counters_.badFrames.load(std::memory_order_relaxed);
  c.sourceTimeouts = counters_.timeouts.load(std::memory_order_relaxed);
  c.deviceLosses = counters_.deviceLosses.load(std::memory_order_relaxed);
  c.deviceReopens = counters_.reopens.load(std::memory_order_relaxed);
  c.framesDropped = (queue_ ? queue_->dropped() : 0) + leftAtStop_.load(std::memory_order_relaxed);
}

void FrameCapture::captureLoop() {
  captureThread_.store(std::this_thread::get_id(), std::memory_order_relaxed);
  platform::setCurrentThreadName("vp-capture");
  std::string problem;
  if (!settings_.cpus.empty() && !platform::setCurrentThreadAffinity(settings_.cpus, &problem)) {
    logLine("app.capture_cpus: %s (capture thread runs unpinned)", problem.c_str());
  }
  std::int64_t taken = 0;
  SourceEvents seen{};
  const std::size_t depth = depth_;
  while (!stopRequested()) {
    if (settings_.maxFrames > 0 && taken >= settings_.maxFrames) {
      break;
    }
    if (settings_.everyFrame) {
      // Offline runs: wait for room instead of dropping (the source is not a live camera).
      while (queue_->waiting() >= depth && !stopRequested()) {
        sleep_ns(*clock_, kCaptureBackoff_ns);
      }
    }
    const std::optional<FrameIndex> index = pool_.acquire();
    if (!index) {
      counters_.poolEmpty.fetch_add(1, std::memory_order_relaxed);
      sleep_ns(*clock_, kCaptureBackoff_ns);
      continue;
    }
    Frame& frame = pool_.frame(*index);
    const SourceStatus status = source_->next(frame);
    const SourceEvents events = source_->events();
    if (events.deviceLosses != seen.deviceLosses || events.reopens != seen.reopens) {
      logLine("%s (device losses %llu, reopens %llu)", source_->message(),
              static_cast<unsigned long long>(events.deviceLosses),
              static_cast<unsigned long long>(events.reopens));
    }
    counters_.timeouts.store(events.timeouts, std::memory_order_relaxed);
    counters_.deviceLosses.store(events.deviceLosses, std::memory_order_relaxed);
    counters_.reopens.store(events.reopens, std::memory_order_relaxed);
    seen = events;
    switch (status) {
      case SourceStatus::Frame:
        ++taken;
        captureNs_[*index] =
            source_->capturesOnMonotonicClock() ? frame.timestamp_ns : clock_->now_ns();
        counters_.framesIn.fetch_add(1, std::memory_order_relaxed);
        if (settings_.recorder != nullptr) {
          settings_.recorder->offerFrame(frame);  // before the processing thread may see it
        }
        queue_->publish(*index);
        queue_->notify();
        continue;
      case SourceStatus::BadFrame:
        ++taken;
        pool_.release(*index);
        counters_.framesIn.fetch_add(1, std::memory_order_relaxed);
        counters_.badFrames.fetch_add(1, std::memory_order_relaxed);
        if (settings_.recorder != nullptr) {
          settings_.recorder->offerBadFrame();
        }
        logLine("bad frame skipped: %s", source_->message());
        queue_->notify();  // no frame, but the processing thread's periodic reports go on
        continue;
      case SourceStatus::Retry:
        pool_.release(*index);
        queue_->notify();
        sleep_ns(*clock_, kCaptureBackoff_ns);
        continue;
      case SourceStatus::End:
        pool_.release(*index);
        break;
    }
    break;
  }
  done_.store(true, std::memory_order_release);
  queue_->notify();
}

}  // namespace vp::app
