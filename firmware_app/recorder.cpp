#include "recorder.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <tuple>
#include <utility>

#include "loop_log.hpp"
#include "platform/system/realtime.hpp"
#include "rig_config/rig_config.hpp"

namespace vp::app {

namespace {

namespace fs = std::filesystem;

constexpr std::uint64_t kBytesPerMib = 1ULL << 20;
// Room kept for the frame's frames.csv row beside its image when the budget is checked.
constexpr std::uint64_t kRowReserve = 128;
// The writer looks at the telemetry ring at least this often while no frame comes.
constexpr auto kWriterPoll = std::chrono::milliseconds(50);
// The site file's name in the recording (as vp_simulate names it).
constexpr const char* kSiteFile = "site.geojson";
// The surface model's name in the recording (as vp_simulate names it).
constexpr const char* kDsmFile = "dsm.tif";

}  // namespace

Recorder::~Recorder() {
  finish();
}

bool Recorder::open(const RecorderSetup& setup, std::string* why) {
  options_ = setup.options;
  writeDelay_ns_ = setup.writeDelay_ns;
  const auto fail = [&](const std::string& problem) {
    if (why) {
      *why = "app.record.dir " + options_.dir + ": " + problem;
    }
    return false;
  };
  if (options_.dir.empty()) {
    return fail("no directory to record into");
  }
  directory_ = options_.dir;
  const camera::Intrinsics& camera = setup.rig.camera.intrinsics;
  std::string problem;
  if (!buffers_.init(static_cast<std::size_t>(options_.queueFrames), camera.width_px,
                     camera.height_px, &problem)) {
    if (why) {
      *why = "app.record.queue_frames: " + problem;
    }
    return false;
  }
  samples_.resize(kTelemetryRing);

  sequence::SequenceInfo info;
  info.name = fs::path(directory_).lexically_normal().filename().string();
  if (info.name.empty() || info.name == "." || info.name == "..") {
    info.name = "recording";
  }
  info.frameRate_hz = setup.frameRate_hz / options_.everyNthFrame;
  info.source = "vp_firmware_app recording of " + setup.source;
  writer_.imageExtension = ".jpg";
  writer_.jpegQuality = options_.jpegQuality;
  writer_.flushRows = true;
  const std::string& dsmPath = setup.rig.terrain.dsmPath;
  std::string rigYaml = config::formatRigYaml(
      setup.rig, "dtm.tif", "the rig vp_firmware_app ran with while recording this sequence",
      dsmPath.empty() ? "" : kDsmFile);
  if (!setup.sitePath.empty()) {
    // The replay reads the site where rig.yaml names it (docs/site_map.md).
    rigYaml += std::string("site:\n  file: ") + kSiteFile + "\n";
  }
  if (!writer_.open(directory_, info, rigYaml, setup.rig.terrain.dtmPath, &problem)) {
    return fail(problem);
  }
  // The site map and the surface model travel with the recording: a replay screens the
  // detections with the same site and lifts onto the same surface.
  siteBytes_ = 0;
  for (const auto& [from, name, what] : {std::tuple<const std::string&, const char*, const char*>{
                                             setup.sitePath, kSiteFile, "site file"},
                                         {dsmPath, kDsmFile, "surface model (terrain.dsm_path)"}}) {
    if (from.empty()) {
      continue;
    }
    std::error_code error;
    const fs::path copy = fs::path(directory_) / name;
    fs::copy_file(from, copy, fs::copy_options::overwrite_existing, error);
    if (!error) {
      siteBytes_ += static_cast<std::uint64_t>(fs::file_size(copy, error));
    }
    if (error) {
      return fail(std::string("cannot copy the ") + what + " " + from + " into the recording as " +
                  name + ": " + error.message());
    }
  }
  bytes_.store(writer_.bytesOnDisk() + siteBytes_, std::memory_order_relaxed);
  thread_ = std::thread(&Recorder::writerLoop, this);
  char budget[64];
  if (options_.maxDisk_mib > 0) {
    std::snprintf(budget, sizeof(budget), "%d MiB", options_.maxDisk_mib);
  } else {
    std::snprintf(budget, sizeof(budget), "none");
  }
  logLine(
      "recording to %s: JPEG quality %d, one frame in %d, %d buffers of %dx%d, disk budget "
      "%s, keep %d MiB free, when full: %s",
      directory_.c_str(), options_.jpegQuality, options_.everyNthFrame, options_.queueFrames,
      camera.width_px, camera.height_px, budget, options_.minFreeDisk_mib,
      config::toString(options_.onFull));
  return true;
}

void Recorder::wake() {
  wake_.fetch_add(1, std::memory_order_release);
  // As FrameQueue::notify: the writer between its check and its sleep holds the mutex.
  { const std::lock_guard<std::mutex> lock(mutex_); }
  wakeup_.notify_one();
}

void Recorder::offerBadFrame() {
  framesIn_.fetch_add(1, std::memory_order_relaxed);
  skipped_.fetch_add(1, std::memory_order_relaxed);  // no image to record
}

void Recorder::offerFrame(const Frame& frame) {
  framesIn_.fetch_add(1, std::memory_order_relaxed);
  const std::uint64_t n = offeredGood_++;
  if (ended_.load(std::memory_order_acquire) ||
      n % static_cast<std::uint64_t>(options_.everyNthFrame) != 0) {
    skipped_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  // frames.csv needs ids and times that advance: a frame that does not is not recorded (the
  // loop skips it too), checked here so that it never reaches the writer.
  if (haveLast_ && (frame.frameId <= lastId_ || frame.timestamp_ns <= lastTimestamp_ns_)) {
    dropped_.fetch_add(1, std::memory_order_relaxed);
    if (!loggedOrder_) {
      loggedOrder_ = true;
      logLine(
          "recording: frame %lld not recorded: id or timestamp (%lld ns) not after the last "
          "recorded frame's (%lld, %lld ns); further ones are only counted",
          static_cast<long long>(frame.frameId), static_cast<long long>(frame.timestamp_ns),
          static_cast<long long>(lastId_), static_cast<long long>(lastTimestamp_ns_));
    }
    return;
  }
  const std::optional<FrameIndex> index = buffers_.acquire();
  if (!index) {
    // The writer is behind (a slow disk): the loop never waits for it.
    const std::uint64_t drops = dropped_.fetch_add(1, std::memory_order_relaxed);
    if (!loggedDrop_) {
      loggedDrop_ = true;
      logLine(
          "recording: frame %lld dropped: all %zu buffers wait for the writer (%llu dropped "
          "so far; further drops are only counted)",
          static_cast<long long>(frame.frameId), buffers_.capacity(),
          static_cast<unsigned long long>(drops + 1));
    }
    return;
  }
  Frame& slot = buffers_.frame(*index);
  frame.image.copyTo(slot.image);  // same size and type: a copy into the buffer, no allocation
  slot.frameId = frame.frameId;
  slot.timestamp_ns = frame.timestamp_ns;
  slot.status = frame.status;
  haveLast_ = true;
  lastId_ = frame.frameId;
  lastTimestamp_ns_ = frame.timestamp_ns;
  ready_.tryPush(*index);  // never full: it holds at most the pool's frames
  wake();
}

void Recorder::onSample(const telemetry::PoseSample& sample) {
  if (ended_.load(std::memory_order_acquire)) {
    return;
  }
  const std::uint64_t tail = sampleTail_.load(std::memory_order_relaxed);
  if (tail - sampleHead_.load(std::memory_order_acquire) >= samples_.size()) {
    const std::uint64_t drops = telemetryDropped_.fetch_add(1, std::memory_order_relaxed);
    if (!loggedSampleDrop_) {
      loggedSampleDrop_ = true;
      logLine(
          "recording: pose sample at %lld ns dropped: the telemetry ring (%zu samples) is "
          "full (%llu dropped so far; further drops are only counted)",
          static_cast<long long>(sample.timestamp_ns), samples_.size(),
          static_cast<unsigned long long>(drops + 1));
    }
    return;
  }
  samples_[tail % samples_.size()] = sample;
  sampleTail_.store(tail + 1, std::memory_order_release);
}

void Recorder::drainTelemetry() {
  std::uint64_t head = sampleHead_.load(std::memory_order_relaxed);
  const std::uint64_t tail = sampleTail_.load(std::memory_order_acquire);
  for (; head != tail; ++head) {
    const telemetry::PoseSample& sample = samples_[head % samples_.size()];
    if (!closed_) {
      sequence::TelemetryRecord record;
      record.timestamp_ns = sample.timestamp_ns;
      record.position = sample.position;
      record.bodyToNed = sample.bodyToNed;
      record.gimbal = sample.gimbal;
      if (writer_.writeTelemetry(record, &why_)) {
        telemetryRecorded_.fetch_add(1, std::memory_order_relaxed);
      } else {
        // A sample the format refuses (NaN, a quaternion far from unit norm, time going back
        // or jumping more than 60 s): the pose buffer refuses it too. Counted; the first logged.
        telemetryDropped_.fetch_add(1, std::memory_order_relaxed);
        if (!loggedSampleRefusal_) {
          loggedSampleRefusal_ = true;
          logLine("recording: pose sample not recorded: %s (further ones are only counted)",
                  why_.c_str());
        }
      }
    }
    sampleHead_.store(head + 1, std::memory_order_release);
  }
}

bool Recorder::makeRoom(std::uint64_t bytes) {
  const std::uint64_t budget = static_cast<std::uint64_t>(options_.maxDisk_mib) * kBytesPerMib;
  const std::uint64_t reserve = static_cast<std::uint64_t>(options_.minFreeDisk_mib) * kBytesPerMib;
  for (;;) {
    const bool overBudget =
        budget > 0 && writer_.bytesOnDisk() + siteBytes_ + bytes + kRowReserve > budget;
    bool lowSpace = false;
    if (reserve > 0) {
      std::error_code error;
      const fs::space_info space = fs::space(directory_, error);
      lowSpace = !error && space.available < bytes + reserve;
    }
    if (!overBudget && !lowSpace) {
      return true;
    }
    if (options_.onFull == config::RecordFullPolicy::Ring && writer_.framesKept() > 0) {
      if (!writer_.removeOldestFrame(&why_)) {
        writeErrors_.fetch_add(1, std::memory_order_relaxed);
        logLine("recording: %s", why_.c_str());
        endRecording("a frame could not be removed");
        return false;
      }
      removed_.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    endRecording(overBudget ? "disk budget app.record.max_disk_mib reached"
                            : "free space below app.record.min_free_disk_mib");
    return false;
  }
}

void Recorder::writeFrame(FrameIndex index) {
  const Frame& frame = buffers_.frame(index);
  if (closed_) {
    skipped_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  if (writeDelay_ns_ > 0) {
    std::this_thread::sleep_for(std::chrono::nanoseconds(writeDelay_ns_));
  }
  const sequence::FrameRecord record{frame.frameId, frame.timestamp_ns, ""};
  if (!writer_.encodeFrame(record, frame.image, encoded_, &why_)) {
    // Not a disk problem: a frame the format cannot hold after the last one (a pause of more
    // than 60 s: one recording is one continuous segment) or an encoder failure.
    dropped_.fetch_add(1, std::memory_order_relaxed);
    logLine("recording: frame %lld: %s", static_cast<long long>(frame.frameId), why_.c_str());
    endRecording("a frame the sequence cannot hold");
    return;
  }
  if (!makeRoom(encoded_.bytes.size())) {
    skipped_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  if (!writer_.writeEncodedFrame(encoded_, &why_)) {
    dropped_.fetch_add(1, std::memory_order_relaxed);
    writeErrors_.fetch_add(1, std::memory_order_relaxed);
    logLine("recording: frame %lld: %s", static_cast<long long>(frame.frameId), why_.c_str());
    endRecording("a write failed");
    return;
  }
  recorded_.fetch_add(1, std::memory_order_relaxed);
  bytes_.store(writer_.bytesOnDisk() + siteBytes_, std::memory_order_relaxed);
}

std::string Recorder::notes() const {
  const RecordCounters c = counters();
  std::string text = std::to_string(c.recorded) + " frames recorded of " +
                     std::to_string(c.framesIn) + " taken from the source (" +
                     std::to_string(c.dropped) + " dropped, " + std::to_string(c.skipped) +
                     " skipped)";
  if (c.removed > 0) {
    text += "; ring: the " + std::to_string(c.removed) +
            " oldest frames were deleted to stay within the disk budget";
  }
  if (c.telemetryDropped > 0) {
    text += "; " + std::to_string(c.telemetryDropped) + " pose samples not recorded";
  }
  return text;
}

void Recorder::endRecording(const char* reason) {
  if (closed_) {
    return;
  }
  ended_.store(true, std::memory_order_release);  // the producers stop offering
  drainTelemetry();  // the samples that came with the frames written so far
  closed_ = true;
  writer_.setNotes(notes() + "; ended early: " + reason);
  const bool closed = writer_.close(&why_);
  if (!closed) {
    writeErrors_.fetch_add(1, std::memory_order_relaxed);
  }
  logLine(
      "recording ended: %s; %s%s%s", reason, directory_.c_str(),
      closed ? " is a complete sequence" : ": finishing it failed: ", closed ? "" : why_.c_str());
}

void Recorder::writerLoop() {
  platform::setCurrentThreadName("vp-record");
  for (;;) {
    const std::uint32_t seen = wake_.load(std::memory_order_acquire);
    drainTelemetry();
    if (const std::optional<FrameIndex> index = ready_.tryPop()) {
      writeFrame(*index);
      buffers_.release(*index);
      continue;
    }
    if (finishing_.load(std::memory_order_acquire)) {
      drainTelemetry();
      break;
    }
    std::unique_lock<std::mutex> lock(mutex_);
    wakeup_.wait_for(lock, kWriterPoll,
                     [&] { return wake_.load(std::memory_order_acquire) != seen; });
  }
  if (!closed_) {
    closed_ = true;
    ended_.store(true, std::memory_order_release);
    writer_.setNotes(notes());
    if (!writer_.close(&why_)) {
      writeErrors_.fetch_add(1, std::memory_order_relaxed);
      logLine("recording: finishing %s failed: %s", directory_.c_str(), why_.c_str());
    }
  }
}

void Recorder::finish() {
  if (!thread_.joinable()) {
    return;
  }
  finishing_.store(true, std::memory_order_release);
  wake();
  thread_.join();
  const RecordCounters c = counters();
  logLine(
      "recording finished: %s: %llu frames recorded, %llu dropped, %llu skipped, %llu "
      "removed (ring), %llu pose samples (%llu dropped), %.1f MiB",
      directory_.c_str(), static_cast<unsigned long long>(c.recorded),
      static_cast<unsigned long long>(c.dropped), static_cast<unsigned long long>(c.skipped),
      static_cast<unsigned long long>(c.removed),
      static_cast<unsigned long long>(c.telemetryRecorded),
      static_cast<unsigned long long>(c.telemetryDropped),
      static_cast<double>(c.bytes) / static_cast<double>(kBytesPerMib));
}

RecordCounters Recorder::counters() const {
  RecordCounters c;
  c.framesIn = framesIn_.load(std::memory_order_relaxed);
  c.recorded = recorded_.load(std::memory_order_relaxed);
  c.dropped = dropped_.load(std::memory_order_relaxed);
  c.skipped = skipped_.load(std::memory_order_relaxed);
  c.removed = removed_.load(std::memory_order_relaxed);
  c.telemetryRecorded = telemetryRecorded_.load(std::memory_order_relaxed);
  c.telemetryDropped = telemetryDropped_.load(std::memory_order_relaxed);
  c.writeErrors = writeErrors_.load(std::memory_order_relaxed);
  c.bytes = bytes_.load(std::memory_order_relaxed);
  return c;
}

}  // namespace vp::app
