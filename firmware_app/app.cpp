#include "app.hpp"

#include <time.h>

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <optional>
#include <utility>

#include "core/spsc_queue.hpp"
#include "geometry/rotated_box.hpp"
#include "io/dtm_file.hpp"
#include "messages/occupancy.hpp"
#include "platform/system/realtime.hpp"
#include "platform/system/stop_signals.hpp"
#include "tracking/from_perception.hpp"

namespace vp::app {

namespace {

constexpr std::int64_t kNsPerSecond = 1'000'000'000;
constexpr std::int64_t kNsPerMs = 1'000'000;
constexpr int kMaxQueueDepth = 8;                     // app.queue_depth's upper bound
constexpr std::int64_t kCaptureBackoffNs = kNsPerMs;  // capture waits this long on a retry
constexpr int kLogLineBytes = 768;

std::int64_t realtimeNowNs() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kNsPerSecond + ts.tv_nsec;
}

// One line on stderr, formatted on the stack: logging from the loop never allocates.
void logLine(const char* format, ...) __attribute__((format(printf, 1, 2)));
void logLine(const char* format, ...) {
  char line[kLogLineBytes];
  int n = std::snprintf(line, sizeof(line), "vp_firmware_app: ");
  va_list args;
  va_start(args, format);
  const int m =
      std::vsnprintf(line + n, sizeof(line) - static_cast<std::size_t>(n) - 1, format, args);
  va_end(args);
  n = std::min<int>(static_cast<int>(sizeof(line)) - 2, n + std::max(m, 0));
  line[n++] = '\n';
  std::fwrite(line, 1, static_cast<std::size_t>(n), stderr);
}

bool isOffDtm(perception::LiftStatus status) {
  return status == perception::LiftStatus::OutsideDtm || status == perception::LiftStatus::NoData ||
         status == perception::LiftStatus::NoIntersection;
}

void sleepNs(platform::Clock& clock, std::int64_t ns) {
  clock.sleepUntilNs(clock.nowNs() + ns);
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
    wake_.notify_one();
  }
  std::uint32_t wakeCount() const { return wake_.load(std::memory_order_acquire); }
  void waitFor(std::uint32_t seen) const { wake_.wait(seen, std::memory_order_acquire); }

  static std::unique_ptr<FrameQueue> make(int depth, FramePool& pool);

 private:
  std::atomic<std::uint32_t> wake_{0};
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

App::App() = default;

App::~App() {
  requestStop();
  if (capture_.joinable()) {
    capture_.join();
  }
}

bool App::init(const config::AppConfig& config, const RunSettings& run, AppSeams seams,
               std::string* why) {
  config_ = config;
  run_ = run;
  seams_ = std::move(seams);
  if (seams_.clock != nullptr) {
    clock_ = seams_.clock;
  } else {
    ownClock_ = std::make_unique<platform::MonotonicClock>();
    clock_ = ownClock_.get();
  }
  monotonicToUtcNs_ = realtimeNowNs() - platform::monotonicNowNs();
  if (!initSource(why) || !initWorld(why) || !initPose(why)) {
    return false;
  }

  // The `tracking:` section is the tracker's own options; the app adds what it owns.
  tracking::TrackerConfig tracker = config_.tracking;
  tracker.maxDetections = detection::kMaxDetectionsPerFrame;
  tracker.asmModel = &asm_;
  std::string problem;
  if (!tracker_.init(tracker, &problem)) {
    if (why) {
      *why = "tracking: " + problem;
    }
    return false;
  }
  worldDetections_.resize(detection::kMaxDetectionsPerFrame);
  states_.resize(static_cast<std::size_t>(tracker.maxTracks));
  published_.resize(static_cast<std::size_t>(tracker.maxTracks));

  if (config_.dds.enabled) {
    dds_ = std::make_unique<DdsWriters>();
    if (!dds_->open(config_.dds, why)) {
      return false;
    }
    if (config_.dds.occupancyRate_hz > 0.0) {
      grid_.resize(config_.dds.grid.rows, config_.dds.grid.cols);
    }
  }

  OutputSpec outputs;
  outputs.trajectoryCsv = config_.app.trajectoryCsv;
  outputs.detectionsCsv = config_.app.detectionsCsv;
  outputs.annotatedVideo = config_.app.annotatedVideo;
  outputs.videoFps = config_.app.annotatedVideoFps;
  outputs.frameSize = cv::Size(pool_.widthPx(), pool_.heightPx());
  outputs.gammaColumns = asm_.componentCount();
  outputs.model = perception_->modelId();
  outputs.source = replay_ != nullptr ? config_.source.sequenceDir : config_.source.v4l2.device;
  if (!outputs_.open(outputs, why)) {
    return false;
  }
  if (!notifier_.open(&problem)) {
    if (why) {
      *why = "systemd notify: " + problem;
    }
    return false;
  }
  return true;
}

bool App::initSource(std::string* why) {
  const config::SourceConfig& source = config_.source;
  if (source.kind == config::FrameSourceKind::Replay) {
    if (source.sequenceDir.empty()) {
      if (why) {
        *why =
            "source.sequence_dir: no recorded sequence to replay (give --sequence DIR, "
            "or --camera for a V4L2 camera)";
      }
      return false;
    }
    auto replay = std::make_unique<ReplayFrameSource>(*clock_);
    std::string problem;
    if (!replay->open(source.sequenceDir, source.paced, source.loop, &problem)) {
      if (why) {
        *why = "sequence " + source.sequenceDir + ": " + problem;
      }
      return false;
    }
    // The rig of a recording is the one it was recorded with (its rig.yaml).
    const sequence::Rig& rig = replay->replay().reader().rig();
    config_.origin = rig.origin;
    config_.camera = {rig.intrinsics, rig.distortion};
    config_.mount = {rig.mount, rig.gimbal};
    config_.terrain = {rig.dtmPath, rig.crs};
    replay_ = replay.get();
    source_ = std::move(replay);
  } else {
    if (seams_.v4l2Device == nullptr) {
      ownDevice_ = std::make_unique<platform::v4l2::SystemV4l2Device>();
    }
    platform::v4l2::V4l2Device& device =
        seams_.v4l2Device != nullptr ? *seams_.v4l2Device : *ownDevice_;
    auto camera = std::make_unique<CameraFrameSource>(device, *clock_);
    if (!camera->open(source.v4l2, why)) {
      return false;
    }
    source_ = std::move(camera);
  }
  int widthPx = 0;
  int heightPx = 0;
  if (replay_ != nullptr) {
    widthPx = replay_->replay().widthPx();
    heightPx = replay_->replay().heightPx();
  } else {
    const auto& format = static_cast<CameraFrameSource&>(*source_).camera().format();
    widthPx = format.widthPx;
    heightPx = format.heightPx;
  }
  const camera::Intrinsics& in = config_.camera.intrinsics;
  if (in.widthPx != widthPx || in.heightPx != heightPx) {
    if (why) {
      *why = "camera.width_px x camera.height_px is " + std::to_string(in.widthPx) + "x" +
             std::to_string(in.heightPx) + " but the source delivers " + std::to_string(widthPx) +
             "x" + std::to_string(heightPx) + " frames (calibrate at the capture size)";
    }
    return false;
  }
  const int depth = config_.app.queueDepth;
  const int poolSize = config_.app.framePoolSize > 0 ? config_.app.framePoolSize : depth + 2;
  std::string problem;
  if (!pool_.init(static_cast<std::size_t>(poolSize), widthPx, heightPx, &problem)) {
    if (why) {
      *why = "frame pool: " + problem;
    }
    return false;
  }
  queue_ = FrameQueue::make(depth, pool_);
  if (!queue_) {
    if (why) {
      *why = "app.queue_depth: " + std::to_string(depth) + " is not in [1, 8]";
    }
    return false;
  }
  return true;
}

bool App::initWorld(std::string* why) {
  std::string problem;
  frame_ = geodesy::LocalFrame(config_.origin);
  terrain::TerrainGrid grid;
  if (!io::loadDtm(config_.terrain.dtmPath, config_.terrain.crs, grid, &problem) ||
      !terrain_.init(std::move(grid), frame_, &problem)) {
    if (why) {
      *why = "terrain.dtm_path " + config_.terrain.dtmPath + ": " + problem;
    }
    return false;
  }
  if (!camera_.init(config_.camera.intrinsics, config_.camera.distortion, &problem)) {
    if (why) {
      *why = "camera: " + problem;
    }
    return false;
  }
  if (!asm_.load(config_.asmPath, &problem)) {
    if (why) {
      *why = "perception.asm " + config_.asmPath + ": " + problem;
    }
    return false;
  }
  if (seams_.perception) {
    perception_ = std::move(seams_.perception);
  } else {
    auto pipeline = std::make_unique<PipelinePerception>();
    if (!pipeline->init(config_.perception, camera_, config_.mount.mount, terrain_, frame_, asm_,
                        &problem)) {
      if (why) {
        *why = "perception: " + problem;
      }
      return false;
    }
    perception_ = std::move(pipeline);
  }
  return true;
}

bool App::initPose(std::string* why) {
  std::string problem;
  if (!poses_.init(config_.pose, &problem)) {
    if (why) {
      *why = "pose: " + problem;
    }
    return false;
  }
  if (seams_.poseInput) {
    poseInput_ = std::move(seams_.poseInput);
    return true;
  }
  const config::TelemetryLinkConfig& link = config_.telemetry;
  switch (link.source) {
    case config::TelemetrySourceKind::Recording: {
      if (replay_ == nullptr) {
        if (why) {
          *why =
              "telemetry.source: recording needs a replayed sequence (source.kind replay); "
              "with a camera use mavlink_udp, mavlink_serial or dds";
        }
        return false;
      }
      auto recording = std::make_unique<RecordingPoseInput>();
      recording->open(replay_->replay(), config_.source.loop, link.replayLookahead_s);
      poseInput_ = std::move(recording);
      return true;
    }
    case config::TelemetrySourceKind::MavlinkUdp:
    case config::TelemetrySourceKind::MavlinkSerial: {
      auto mavlink = std::make_unique<MavlinkPoseInput>(*clock_, config_.mount.gimbal);
      if (!mavlink->open(link, &problem)) {
        if (why) {
          *why = std::string("telemetry (") + config::toString(link.source) + "): " + problem;
        }
        return false;
      }
      poseInput_ = std::move(mavlink);
      return true;
    }
    case config::TelemetrySourceKind::Dds: {
      auto dds = std::make_unique<DdsPoseInput>(*clock_, config_.mount.gimbal, monotonicToUtcNs_);
      if (!dds->open(config_.dds.telemetry, why)) {
        return false;
      }
      poseInput_ = std::move(dds);
      return true;
    }
    case config::TelemetrySourceKind::None:
      poseInput_ = std::make_unique<NoPoseInput>();
      return true;
  }
  return false;
}

bool App::stopRequested() const {
  return stop_.load(std::memory_order_relaxed) || platform::StopSignals::stopRequested();
}

void App::captureLoop() {
  platform::setCurrentThreadName("vp-capture");
  std::string problem;
  if (!config_.app.captureCpus.empty() &&
      !platform::setCurrentThreadAffinity(config_.app.captureCpus, &problem)) {
    logLine("app.capture_cpus: %s (capture thread runs unpinned)", problem.c_str());
  }
  std::int64_t taken = 0;
  SourceEvents seen{};
  const auto depth = static_cast<std::size_t>(config_.app.queueDepth);
  while (!stopRequested()) {
    if (run_.maxFrames > 0 && taken >= run_.maxFrames) {
      break;
    }
    if (run_.everyFrame) {
      // Offline runs: wait for room instead of dropping (the source is not a live camera).
      while (queue_->waiting() >= depth && !stopRequested()) {
        sleepNs(*clock_, kCaptureBackoffNs);
      }
    }
    const std::optional<FrameIndex> index = pool_.acquire();
    if (!index) {
      captureCounters_.poolEmpty.fetch_add(1, std::memory_order_relaxed);
      sleepNs(*clock_, kCaptureBackoffNs);
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
    captureCounters_.timeouts.store(events.timeouts, std::memory_order_relaxed);
    captureCounters_.deviceLosses.store(events.deviceLosses, std::memory_order_relaxed);
    captureCounters_.reopens.store(events.reopens, std::memory_order_relaxed);
    seen = events;
    switch (status) {
      case SourceStatus::Frame:
        ++taken;
        captureNs_[*index] =
            source_->capturesOnMonotonicClock() ? frame.timestampNs : clock_->nowNs();
        captureCounters_.framesIn.fetch_add(1, std::memory_order_relaxed);
        queue_->publish(*index);
        queue_->notify();
        continue;
      case SourceStatus::BadFrame:
        ++taken;
        pool_.release(*index);
        captureCounters_.badFrames.fetch_add(1, std::memory_order_relaxed);
        logLine("bad frame skipped: %s", source_->message());
        continue;
      case SourceStatus::Retry:
        pool_.release(*index);
        sleepNs(*clock_, kCaptureBackoffNs);
        continue;
      case SourceStatus::End:
        pool_.release(*index);
        break;
    }
    break;
  }
  captureDone_.store(true, std::memory_order_release);
  queue_->notify();
}

bool App::run(std::string* why) {
  if (ran_) {
    if (why) {
      *why = "run() was already called";
    }
    return false;
  }
  ran_ = true;
  std::string problem;
  if (config_.app.lockMemory && !platform::lockAllMemory(&problem)) {
    if (why) {
      *why = "app.lock_memory: " + problem;
    }
    return false;
  }
  if (!config_.app.processingCpus.empty() &&
      !platform::setCurrentThreadAffinity(config_.app.processingCpus, &problem)) {
    if (why) {
      *why = "app.processing_cpus: " + problem;
    }
    return false;
  }
  if (config_.app.realtimePriority > 0 &&
      !platform::setCurrentThreadRealtime(config_.app.realtimePriority, &problem)) {
    if (why) {
      *why = "app.realtime_priority: " + problem;
    }
    return false;
  }
  const std::int64_t startNs = clock_->nowNs();
  nextStatsNs_ = startNs + static_cast<std::int64_t>(config_.app.statsPeriod_s * 1e9);
  nextStatusNs_ = startNs;
  nextOccupancyNs_ = startNs;
  nextWatchdogNs_ = startNs;
  logLine(
      "running: %s %s, pose from %s, DDS %s, queue depth %d, %zu frames of %dx%d",
      replay_ != nullptr ? "replay of" : "camera",
      replay_ != nullptr ? config_.source.sequenceDir.c_str() : config_.source.v4l2.device.c_str(),
      poseInput_->name(), dds_ ? "on" : "off", config_.app.queueDepth, pool_.capacity(),
      pool_.widthPx(), pool_.heightPx());
  notifier_.ready();
  capture_ = std::thread(&App::captureLoop, this);

  for (;;) {
    const std::uint32_t seen = queue_->wakeCount();
    if (const std::optional<FrameIndex> index = queue_->take()) {
      processFrame(*index);
      if (stopRequested()) {
        break;
      }
      continue;
    }
    if (captureDone_.load(std::memory_order_acquire)) {
      if (const std::optional<FrameIndex> last = queue_->take()) {
        processFrame(*last);
        continue;
      }
      break;
    }
    if (stopRequested()) {
      break;
    }
    // The capture thread bumps the count after each frame and when it ends, and it checks the
    // stop flag at every frame (paced replay: one frame period; camera: the dequeue timeout).
    queue_->waitFor(seen);
  }
  shutdown();
  runWall_s_ = static_cast<double>(clock_->nowNs() - startNs) / 1e9;
  return true;
}

void App::shutdown() {
  notifier_.stopping();
  stop_.store(true, std::memory_order_relaxed);
  if (capture_.joinable()) {
    capture_.join();
  }
  queue_->drain();  // every waiting frame back in the pool
  if (dds_) {
    // A frame without tracks: endFrame() disposes every published instance.
    const platform::dds::FrameSummary summary = dds_->states().endFrame(realtimeNowNs());
    counters_.tracksDisposed += summary.disposed;
    counters_.publishErrors += summary.errors;
  }
  std::string problem;
  if (!outputs_.close(&problem)) {
    ++counters_.outputErrors;
    logLine("closing outputs: %s", problem.c_str());
  }
}

void App::processFrame(FrameIndex index) {
  const std::int64_t startNs = clock_->nowNs();
  const Frame& frame = pool_.frame(index);
  const std::int64_t captureNs = captureNs_[index];
  const std::int64_t t = frame.timestampNs;
  stats_.record(Stage::Queue, startNs - captureNs);
  if (!haveUtcOffset_) {
    // Camera stamps are CLOCK_MONOTONIC; a replay's are the recording's, mapped so that its
    // first frame is "now" (see the contract).
    toUtcNs_ = source_->capturesOnMonotonicClock() ? monotonicToUtcNs_ : realtimeNowNs() - t;
    haveUtcOffset_ = true;
  } else if (t <= lastTimestampNs_) {
    ++counters_.pipelineErrors;
    logLine("frame %lld skipped: timestamp %lld ns is not after the previous frame's %lld ns",
            static_cast<long long>(frame.frameId), static_cast<long long>(t),
            static_cast<long long>(lastTimestampNs_));
    pool_.release(index);
    return;
  }
  lastTimestampNs_ = t;

  poseInput_->poll(t, poses_);
  const telemetry::PoseEstimate pose = poses_.poseAt(t);
  switch (pose.status) {
    case telemetry::PoseStatus::Ok:
      break;
    case telemetry::PoseStatus::NoPose:
      ++counters_.noPose;
      break;
    case telemetry::PoseStatus::Stale:
      ++counters_.stalePose;
      break;
    case telemetry::PoseStatus::Invalid:
      ++counters_.invalidPose;
      break;
  }
  logPoseEpisode(pose.status, frame.frameId, pose);

  const perception::PipelineStatus status = perception_->process(frame.image, t, pose);
  const perception::PipelineTimings& timings = perception_->timings();
  if (status != perception::PipelineStatus::Ok) {
    ++counters_.pipelineErrors;
    logLine("frame %lld not processed: %s", static_cast<long long>(frame.frameId),
            perception_->lastError());
    pool_.release(index);
    return;
  }
  stats_.recordMs(Stage::Preprocess, timings.preprocess_ms);
  stats_.recordMs(Stage::Detector, timings.detector_ms);
  stats_.recordMs(Stage::Decode, timings.decode_ms);
  stats_.recordMs(Stage::Crops, timings.crops_ms);
  stats_.recordMs(Stage::Lift, timings.lift_ms);
  countObservations();

  const std::int64_t trackStartNs = clock_->nowNs();
  const std::size_t detections =
      tracking::toWorldDetections(perception_->observations(), worldDetections_);
  const auto report = tracker_.step(
      t, std::span<const tracking::WorldDetection>(worldDetections_.data(), detections));
  if (!report) {
    ++counters_.trackerErrors;
    logLine("frame %lld: tracker: %s", static_cast<long long>(frame.frameId),
            tracking::toString(report.error()));
  }
  const std::int64_t publishStartNs = clock_->nowNs();
  stats_.record(Stage::Track, publishStartNs - trackStartNs);
  publishFrame(t, frame.frameId);
  const std::int64_t publishedNs = clock_->nowNs();
  stats_.record(Stage::Publish, publishedNs - publishStartNs);
  stats_.record(Stage::EndToEnd, publishedNs - captureNs);

  outputs_.writeDetections(frame.frameId, perception_->observations());
  if (outputs_.wantsVideo()) {
    const perception::FrameLiftSummary& lift = perception_->liftSummary();
    const bool posed = lift.poseStatus == perception::LiftStatus::Ok;
    outputs_.writeVideo(perception_->correctedFrame(), perception_->observations(),
                        posed ? &perception_->lifter() : nullptr,
                        posed ? &lift.cameraPose : nullptr);
  }
  counters_.outputErrors = outputs_.errors();
  pool_.release(index);
  ++counters_.framesProcessed;
  lastPose_ = pose;
  periodic(clock_->nowNs(), pose);
  if (seams_.observer != nullptr) {
    seams_.observer->onFrameDone(counters_.framesProcessed);
  }
}

void App::countObservations() {
  const std::span<const perception::VehicleObservation> observations = perception_->observations();
  counters_.detections += observations.size();
  for (const perception::VehicleObservation& observation : observations) {
    if (observation.liftStatus == perception::LiftStatus::Ok) {
      ++counters_.lifted;
    } else if (isOffDtm(observation.liftStatus)) {
      ++counters_.outsideDtm;
    }
  }
}

void App::logPoseEpisode(telemetry::PoseStatus status, std::int64_t frameId,
                         const telemetry::PoseEstimate& pose) {
  // Once per episode: when the pose goes bad (with its context) and when it is good again.
  if (status == lastPoseStatus_) {
    ++poseEpisodeFrames_;
    return;
  }
  if (status == telemetry::PoseStatus::Ok) {
    logLine("pose ok again at frame %lld after %llu frame(s) with pose %s",
            static_cast<long long>(frameId), static_cast<unsigned long long>(poseEpisodeFrames_),
            telemetry::toString(lastPoseStatus_));
  } else {
    logLine(
        "pose %s from frame %lld (nearest sample %.3f s away; telemetry %s: %llu samples, "
        "%llu refused): detections are kept image-only",
        telemetry::toString(status), static_cast<long long>(frameId),
        pose.ageNs >= 0 ? static_cast<double>(pose.ageNs) / 1e9 : -1.0, poseInput_->name(),
        static_cast<unsigned long long>(poseInput_->counters().received),
        static_cast<unsigned long long>(poseInput_->counters().linkRejected +
                                        poseInput_->counters().bufferRejected));
  }
  lastPoseStatus_ = status;
  poseEpisodeFrames_ = 1;
}

void App::publishFrame(std::int64_t timestampNs, std::int64_t frameId) {
  const std::span<const tracking::TrackState> tracks = tracker_.tracks();
  stateCount_ = 0;
  for (const tracking::TrackState& track : tracks) {
    // Tentative tracks are never published (the publisher would skip them too).
    if (track.status == tracking::TrackStatus::Tentative || stateCount_ >= states_.size()) {
      continue;
    }
    states_[stateCount_] =
        toVehicleState(track, config_.dds.droneId, toUtcNs_, frame_, &terrain_, &asm_);
    published_[stateCount_] = track;
    ++stateCount_;
  }
  const std::span<const messages::VehicleState> states(states_.data(), stateCount_);
  if (dds_) {
    for (const messages::VehicleState& state : states) {
      const platform::dds::PublishResult result = dds_->states().publish(state);
      if (!result.ok()) {
        if (counters_.publishErrors++ == 0) {
          logLine("publishing track %u failed: %s (further failures are only counted)",
                  static_cast<unsigned>(state.trackId), platform::dds::toString(result.outcome));
        }
        continue;
      }
      ++counters_.statesPublished;
      if (seams_.observer != nullptr) {
        seams_.observer->onPublished(state);
      }
    }
    const platform::dds::FrameSummary summary = dds_->states().endFrame(timestampNs + toUtcNs_);
    counters_.tracksDisposed += summary.disposed;
    counters_.publishErrors += summary.errors;
  }
  outputs_.writeTracks(
      frameId, std::span<const tracking::TrackState>(published_.data(), stateCount_), states);
}

void App::publishStatus(std::int64_t nowUtcNs, const telemetry::PoseEstimate& pose) {
  messages::DroneStatus status;
  status.droneId = config_.dds.droneId;
  status.time_ns = nowUtcNs;
  status.position = pose.pose.position;
  const Eigen::Quaterniond& q = pose.pose.bodyToNed;
  status.attitudeQuaternion = {q.w(), q.x(), q.y(), q.z()};
  status.gimbalEuler_deg = {static_cast<float>(pose.pose.gimbal.angles.rollDeg),
                            static_cast<float>(pose.pose.gimbal.angles.pitchDeg),
                            static_cast<float>(pose.pose.gimbal.angles.yawDeg)};
  const diagnostics::LatencyHistogram& e2e = stats_.period(Stage::EndToEnd);
  status.latencyMedian_ms = static_cast<float>(static_cast<double>(e2e.medianNs()) / 1e6);
  status.latencyP99_ms = static_cast<float>(static_cast<double>(e2e.p99Ns()) / 1e6);
  status.inferenceMedian_ms =
      static_cast<float>(static_cast<double>(stats_.period(Stage::Detector).medianNs()) / 1e6);
  const LoopCounters c = counters();
  status.frameRate_hz = static_cast<float>(
      static_cast<double>(c.framesProcessed - framesAtStatus_) * config_.dds.statusRate_hz);
  status.framesProcessed = c.framesProcessed;
  status.framesDropped = c.framesDropped;
  status.corruptFrames = c.badFrames;
  status.stalePoses = c.stalePose + c.noPose + c.invalidPose;
  status.outsideDtm = c.outsideDtm;
  status.publishErrors = c.publishErrors;
  status.activeTracks = static_cast<std::uint32_t>(stateCount_);
  status.setModelId(perception_->modelId());
  if (!dds_->status().write(status).ok()) {
    ++counters_.publishErrors;
  }
  framesAtStatus_ = c.framesProcessed;
}

void App::periodic(std::int64_t nowNs, const telemetry::PoseEstimate& pose) {
  if (dds_) {
    if (nowNs >= nextStatusNs_) {
      const double period_s = 1.0 / config_.dds.statusRate_hz;
      publishStatus(nowNs + monotonicToUtcNs_, pose);
      nextStatusNs_ = nowNs + static_cast<std::int64_t>(period_s * 1e9);
    }
    if (config_.dds.occupancyRate_hz > 0.0 && nowNs >= nextOccupancyNs_) {
      // The observed area: the frame's ground footprint, as perception computed it.
      const std::span<const Eigen::Vector2d> corners = perception_->footprint().corners();
      const config::OccupancyGridSpec& spec = config_.dds.grid;
      grid_.droneId = config_.dds.droneId;
      grid_.time_ns = lastTimestampNs_ + toUtcNs_;
      grid_.originEast_m = spec.originEast_m;
      grid_.originNorth_m = spec.originNorth_m;
      grid_.resolution_m = static_cast<float>(spec.resolution_m);
      messages::rasterizeOccupancy(
          corners, std::span<const messages::VehicleState>(states_.data(), stateCount_), grid_);
      if (!dds_->occupancy().write(grid_).ok()) {
        ++counters_.publishErrors;
      }
      nextOccupancyNs_ = nowNs + static_cast<std::int64_t>(1e9 / config_.dds.occupancyRate_hz);
    }
  }
  if (notifier_.watchdogIntervalNs() > 0 && nowNs >= nextWatchdogNs_) {
    notifier_.watchdog();
    nextWatchdogNs_ = nowNs + notifier_.watchdogIntervalNs();
  }
  if (nowNs >= nextStatsNs_) {
    const double period_s = config_.app.statsPeriod_s;
    const LoopCounters c = counters();
    std::array<char, 1024> line{};
    formatStatsLine(line, c, stats_, static_cast<double>(c.framesProcessed - framesAtStats_),
                    period_s);
    if (!run_.quiet) {
      logLine("%s", line.data());
    }
    notifier_.status(line.data());
    framesAtStats_ = c.framesProcessed;
    stats_.startPeriod();
    nextStatsNs_ = nowNs + static_cast<std::int64_t>(period_s * 1e9);
  }
}

LoopCounters App::counters() const {
  LoopCounters c = counters_;
  c.framesIn = captureCounters_.framesIn.load(std::memory_order_relaxed);
  c.badFrames = captureCounters_.badFrames.load(std::memory_order_relaxed);
  c.sourceTimeouts = captureCounters_.timeouts.load(std::memory_order_relaxed);
  c.deviceLosses = captureCounters_.deviceLosses.load(std::memory_order_relaxed);
  c.deviceReopens = captureCounters_.reopens.load(std::memory_order_relaxed);
  c.framesDropped = queue_ ? queue_->dropped() : 0;
  if (poseInput_) {
    c.telemetrySamples = poseInput_->counters().received;
    c.telemetryRejected =
        poseInput_->counters().linkRejected + poseInput_->counters().bufferRejected;
  }
  return c;
}

std::string App::summaryLine() const {
  std::array<char, 2048> line{};
  formatSummaryLine(line, counters(), stats_, runWall_s_);
  return line.data();
}

}  // namespace vp::app
