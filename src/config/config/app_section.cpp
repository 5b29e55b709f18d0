// config/app_section: `app:` (frame pool, queue, real-time settings, statistics, file
// outputs, the recording `app.record:`) into the firmware app's LoopConfig
// (config/loop_config.hpp).
#include <array>
#include <string>
#include <string_view>

#include "config/sections.hpp"
#include "rig_config/section_reader.hpp"

namespace vp::config::detail {
namespace {

const Range kQueueDepthRange = Range::closed(1.0, 8.0);
const Range kPoolSizeRange = Range::closed(0.0, 64.0);  // FramePool::kMaxFrames
const Range kPriorityRange = Range::closed(0.0, 99.0);
const Range kCpuRange = Range::closed(0.0, 1023.0);
const Range kStatsPeriodRangeS = Range::closed(0.1, 3600.0);
const Range kVideoFpsRange = Range{0.0, 1000.0, true};
const Range kJpegQualityRange = Range::closed(1.0, 100.0);
const Range kEveryNthRange = Range::closed(1.0, 1000.0);
const Range kRecordQueueRange = Range::closed(1.0, 64.0);  // FramePool::kMaxFrames
// 2^31 - 1 MiB: the int's range (2 PiB, more than any disk).
const Range kDiskRange_mib = Range::closed(0.0, 2147483647.0);

constexpr std::string_view kRecordFullNames = "stop, ring";
constexpr std::string_view kPipelineNames = "off, on";

std::optional<PipelineMode> pipelineFromString(const std::string& text) {
  return enumFromString(text, std::array{PipelineMode::Off, PipelineMode::On},
                        [](PipelineMode mode) { return toString(mode); });
}

std::optional<RecordFullPolicy> recordFullFromString(const std::string& text) {
  return enumFromString(text, std::array{RecordFullPolicy::Stop, RecordFullPolicy::Ring},
                        [](RecordFullPolicy policy) { return toString(policy); });
}

RecordConfig readRecord(MapReader section, const std::string& baseDir) {
  const RecordConfig d;
  RecordConfig r;
  r.dir = readOptionalPath(section, "dir", baseDir, "");
  r.jpegQuality = section.integer("jpeg_quality", kJpegQualityRange, d.jpegQuality);
  r.everyNthFrame = section.integer("every_nth_frame", kEveryNthRange, d.everyNthFrame);
  r.queueFrames = section.integer("queue_frames", kRecordQueueRange, d.queueFrames);
  r.maxDisk_mib = section.integer("max_disk_mib", kDiskRange_mib, d.maxDisk_mib);
  r.minFreeDisk_mib = section.integer("min_free_disk_mib", kDiskRange_mib, d.minFreeDisk_mib);
  r.onFull =
      section.choice<RecordFullPolicy>("on_full", recordFullFromString, kRecordFullNames, d.onFull);
  section.warnUnknownKeys();
  return r;
}

}  // namespace

LoopConfig readLoop(MapReader section, const std::string& baseDir) {
  const LoopConfig d;
  LoopConfig a;
  a.queueDepth = section.integer("queue_depth", kQueueDepthRange, d.queueDepth);
  a.pipeline =
      section.choice<PipelineMode>("pipeline", pipelineFromString, kPipelineNames, d.pipeline);
  a.framePoolSize = section.integer("frame_pool_size", kPoolSizeRange, d.framePoolSize);
  // The pipeline holds one frame more: the one between its two threads.
  const bool pipelined = a.pipeline == PipelineMode::On;
  const int minPool = a.queueDepth + (pipelined ? 3 : 2);
  if (a.framePoolSize != 0 && a.framePoolSize < minPool) {
    section.fail("frame_pool_size", std::string("must be 0 (automatic) or >= queue_depth + ") +
                                        (pipelined ? "3 (pipeline on) = " : "2 = ") +
                                        std::to_string(minPool) + ", got " +
                                        std::to_string(a.framePoolSize));
  }
  a.lockMemory = section.boolean("lock_memory", d.lockMemory);
  a.realtimePriority = section.integer("realtime_priority", kPriorityRange, d.realtimePriority);
  if (section.has("capture_cpus")) {
    a.captureCpus = section.integers("capture_cpus", kCpuRange, -1);
  }
  if (section.has("processing_cpus")) {
    a.processingCpus = section.integers("processing_cpus", kCpuRange, -1);
  }
  a.statsPeriod_s = section.number("stats_period_s", kStatsPeriodRangeS, d.statsPeriod_s);
  a.trajectoryCsv = readOptionalPath(section, "trajectory_csv", baseDir, "");
  a.detectionsCsv = readOptionalPath(section, "detections_csv", baseDir, "");
  a.trafficDir = readOptionalPath(section, "traffic_dir", baseDir, "");
  a.annotatedVideo = readOptionalPath(section, "annotated_video", baseDir, "");
  a.annotatedVideoFps = section.number("annotated_video_fps", kVideoFpsRange, d.annotatedVideoFps);
  a.record = readRecord(section.section("record"), baseDir);
  section.warnUnknownKeys();
  return a;
}

}  // namespace vp::config::detail
