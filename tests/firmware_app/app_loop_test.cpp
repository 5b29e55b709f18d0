// Tests of the firmware app's loop (firmware_app/app.hpp) on simulated sequences: zero heap
// allocations per frame on the processing thread, bad input (corrupt and truncated frames,
// NaN pose, telemetry gap, a camera that disappears and comes back) counted while the loop goes
// on, and a source faster than the loop (drops counted, every frame accounted for).
#include <linux/videodev2.h>
#include <pthread.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include "../platform/v4l2/fake_v4l2_device.hpp"
#include "alloc_counter.hpp"
#include "app.hpp"
#include "app_test_support.hpp"
#include "core/transient_arena.hpp"
#include "inference/dnnl_int8.hpp"
#include "output_files/detections_file.hpp"
#include "output_files/trajectory_file.hpp"
#include "time_scale.hpp"

namespace vp::app {
namespace {

namespace fs = std::filesystem;

// Small frames: the detector's one 672 x 512 tile at working scale 1 (the real pipeline runs in
// seconds), 24 frames at 10 Hz.
constexpr int kWidth_px = test::kLoopWidth_px;
constexpr int kHeight_px = test::kLoopHeight_px;
constexpr int kFrames = test::kLoopFrames;

std::string sequence() {
  return test::loopSequence();
}

config::AppConfig loopConfig(const std::string& sequenceDir) {
  config::AppConfig config = test::defaultConfigFor(sequenceDir);
  config.dds.enabled = false;
  config.source.paced = false;
  config.perception.preprocess.workingScale = 1.0;
  config.app.statsPeriod_s = 3600.0;
  return config;
}

std::unique_ptr<test::TruthPerception> truth(const std::string& sequenceDir) {
  auto perception = std::make_unique<test::TruthPerception>();
  std::string why;
  EXPECT_TRUE(perception->init(sequenceDir, &why)) << why;
  return perception;
}

// The shipped pipeline over every frame with the CSV outputs on: no heap allocation on the
// processing thread over frames 6..kFrames, and, pipelined, none on the detector thread either.
void expectZeroAllocationsWithThePipeline(
    config::PipelineMode mode, inference::Backend backend = inference::Backend::XnnpackInt8) {
  const std::string dir = sequence();
  ASSERT_FALSE(dir.empty());
  const std::string out = test::scratchDir(std::string("alloc_pipeline_") + config::toString(mode) +
                                           "_" + toString(backend));
  config::AppConfig config = loopConfig(dir);
  config.app.pipeline = mode;
  config.perception.detection.engine.backend = backend;
  config.app.trajectoryCsv = out + "/tracks.csv";
  config.app.detectionsCsv = out + "/detections.csv";
  test::AllocationWindow window(5, kFrames);
  {
    App app;
    AppSeams seams;
    seams.observer = &window;
    std::string why;
    ASSERT_TRUE(app.init(config, test::everyFrame(), std::move(seams), &why)) << why;
    ASSERT_TRUE(app.run(&why)) << why;
    const LoopCounters c = app.counters();
    EXPECT_EQ(c.framesIn, static_cast<std::uint64_t>(kFrames));
    EXPECT_EQ(c.framesProcessed, static_cast<std::uint64_t>(kFrames));
    EXPECT_EQ(c.framesDropped, 0U);
    EXPECT_EQ(c.pipelineErrors, 0U);
    EXPECT_EQ(c.noPose + c.stalePose + c.invalidPose, 0U);  // the recording covers every frame
    EXPECT_EQ(app.framesInPool(), app.poolCapacity());
    std::printf(
        "real pipeline (pipeline %s), %d x %d, %d frames: %llu detections (%llu lifted) by the "
        "shipped detector; %s\n",
        config::toString(mode), kWidth_px, kHeight_px, kFrames,
        static_cast<unsigned long long>(c.detections), static_cast<unsigned long long>(c.lifted),
        app.summaryLine().c_str());
  }
  ASSERT_TRUE(window.counted());
  // Pipelined, the window counts the detector thread too (it announced itself at its start).
  EXPECT_EQ(window.sawDetectorThread(), mode == config::PipelineMode::On);
  std::printf("processing-thread%s allocations over frames 6..%d (DDS off, CSV outputs on): %zu\n",
              mode == config::PipelineMode::On ? " and detector-thread" : "", kFrames,
              window.count());
  EXPECT_EQ(window.count(), 0U);
}

TEST(AppLoop, ZeroAllocationsPerFrameOnTheProcessingThreadWithThePipeline) {
  expectZeroAllocationsWithThePipeline(config::PipelineMode::Off);
}

TEST(AppLoop, ZeroAllocationsPerFrameOnBothThreadsOfThePipelinedLoop) {
  expectZeroAllocationsWithThePipeline(config::PipelineMode::On);
}

// The oneDNN backend (int8-dnnl, what `auto` picks on VNNI CPUs): its convolutions' per-call
// heap blocks come from an arena reserved at load (inference/dnnl_int8.hpp), so the loop
// allocates nothing with it either, serial and pipelined.
TEST(AppLoop, ZeroAllocationsPerFrameWithTheOneDnnBackend) {
  if (!inference::dnnlInt8Available() || !inference::cpuHasVnni())
    GTEST_SKIP() << "int8-dnnl is not what this build and CPU would use (no oneDNN or no VNNI)";
  if (!core::TransientArena::redirects())
    GTEST_SKIP() << "AddressSanitizer build: the arena does not redirect operator new";
  expectZeroAllocationsWithThePipeline(config::PipelineMode::Off, inference::Backend::DnnlInt8);
  expectZeroAllocationsWithThePipeline(config::PipelineMode::On, inference::Backend::DnnlInt8);
}

TEST(AppLoop, ZeroAllocationsWithInjectedVehiclesAndTracksAndTheFigureWithDds) {
  const std::string dir = sequence();
  ASSERT_FALSE(dir.empty());
  const std::string out = test::scratchDir("alloc_truth");
  // DDS off: the whole loop, tracker and trajectory rows included, allocates nothing; so does
  // the traffic analysis on the intersection's site (gates, lanes, zones) with its files, two
  // periods closing inside the counted frames.
  {
    config::AppConfig config = loopConfig(dir);
    config.app.trajectoryCsv = out + "/tracks.csv";
    config.app.detectionsCsv = out + "/detections.csv";
    config.app.trafficDir = out;
    config.traffic.period_s = 1.0;
    test::AllocationWindow window(5, kFrames);
    App app;
    AppSeams seams;
    seams.perception = truth(dir);
    seams.observer = &window;
    std::string why;
    ASSERT_TRUE(app.init(config, test::everyFrame(), std::move(seams), &why)) << why;
    ASSERT_TRUE(app.run(&why)) << why;
    const LoopCounters c = app.counters();
    EXPECT_EQ(c.framesProcessed, static_cast<std::uint64_t>(kFrames));
    EXPECT_GT(c.lifted, static_cast<std::uint64_t>(kFrames));  // vehicles in every frame
    EXPECT_TRUE(c.traffic);
    EXPECT_GE(c.trafficPeriods, 2U);
    EXPECT_GT(c.gateCrossings, 0U);
    EXPECT_EQ(c.trafficErrors, 0U);
    ASSERT_TRUE(window.counted());
    std::printf(
        "truth vehicles, DDS off: %llu observations, %llu lifted; processing-thread "
        "allocations over frames 6..%d: %zu\n",
        static_cast<unsigned long long>(c.detections), static_cast<unsigned long long>(c.lifted),
        kFrames, window.count());
    EXPECT_EQ(window.count(), 0U);
    output_files::TrajectoryFile tracks;
    ASSERT_TRUE(output_files::readTrajectoryFile(out + "/tracks.csv", &tracks, &why)) << why;
    EXPECT_GT(tracks.rows.size(), 0U);
  }
  // DDS on (no reader; a unique domain on loopback): Cyclone's write path allocates per sample
  // (docs/dds.md); reported, not asserted.
  {
    config::AppConfig config = loopConfig(dir);
    setenv("CYCLONEDDS_URI",
           "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface "
           "address=\"127.0.0.1\"/></Interfaces><AllowMulticast>false</AllowMulticast></General>"
           "</Domain></CycloneDDS>",
           1);
    config.dds.enabled = true;
    config.dds.domainId = static_cast<std::uint32_t>(1 + getpid() % 200);
    config.dds.partition = "alloc_" + std::to_string(getpid());
    config.traffic.period_s = 1.0;  // the traffic topics written in the counted frames too
    test::AllocationWindow window(5, kFrames);
    App app;
    AppSeams seams;
    seams.perception = truth(dir);
    seams.observer = &window;
    std::string why;
    ASSERT_TRUE(app.init(config, test::everyFrame(), std::move(seams), &why)) << why;
    const std::uint64_t publishedBefore = window.published();
    ASSERT_TRUE(app.run(&why)) << why;
    ASSERT_TRUE(window.counted());
    const double frames = kFrames - 5;
    std::printf(
        "truth vehicles, DDS on: %llu states published in total; processing-thread "
        "allocations over frames 6..%d: %zu (%.1f per frame)\n",
        static_cast<unsigned long long>(window.published() - publishedBefore), kFrames,
        window.count(), static_cast<double>(window.count()) / frames);
    RecordProperty("allocations_per_frame_dds_on",
                   std::to_string(static_cast<double>(window.count()) / frames));
  }
}

// Writes `bytes` over a file (a corrupt image) or cuts it (a truncated one).
void damage(const fs::path& file, bool truncate) {
  const auto size = fs::file_size(file);
  if (truncate) {
    fs::resize_file(file, size / 2);
    return;
  }
  std::ofstream(file, std::ios::binary | std::ios::trunc) << "not a PNG at all";
}

std::string frameFile(const std::string& dir, std::size_t index) {
  sequence::SequenceReader reader;
  std::string why;
  EXPECT_TRUE(reader.open(dir, &why)) << why;
  return dir + "/" + reader.frames()[index].file;
}

TEST(AppFaults, CorruptAndTruncatedFramesAreCountedAndSkipped) {
  const std::string dir = test::copySequence(sequence(), "damaged_frames");
  damage(frameFile(dir, 3), false);
  damage(frameFile(dir, 9), true);
  // The same with the pipelined loop (app.pipeline: on).
  for (const config::PipelineMode mode : {config::PipelineMode::Off, config::PipelineMode::On}) {
    SCOPED_TRACE(config::toString(mode));
    config::AppConfig config = loopConfig(dir);
    config.app.pipeline = mode;
    App app;
    AppSeams seams;
    seams.perception = truth(dir);
    std::string why;
    ASSERT_TRUE(app.init(config, test::everyFrame(), std::move(seams), &why)) << why;
    ASSERT_TRUE(app.run(&why)) << why;
    const LoopCounters c = app.counters();
    EXPECT_EQ(c.badFrames, 2U);
    EXPECT_EQ(c.framesIn, static_cast<std::uint64_t>(kFrames));  // bad frames came in too
    EXPECT_EQ(c.framesProcessed, static_cast<std::uint64_t>(kFrames - 2));  // the rest goes on
    EXPECT_EQ(app.framesInPool(), app.poolCapacity());
  }
}

// Keeps the recorded telemetry but replaces the position of the samples in [from_ns, to_ns)
// with NaN, as a broken link would deliver them.
class NanPoseInput final : public PoseInput {
 public:
  NanPoseInput(const sequence::SequenceReader& reader, std::int64_t from_ns, std::int64_t to_ns)
      : records_(reader.telemetry()), fromNs_(from_ns), toNs_(to_ns) {}
  void poll(std::int64_t frameTime_ns, telemetry::PoseBuffer& buffer) override {
    constexpr std::int64_t kLookahead_ns = 200'000'000;
    while (next_ < records_.size() &&
           records_[next_].timestamp_ns <= frameTime_ns + kLookahead_ns) {
      const sequence::TelemetryRecord& record = records_[next_++];
      telemetry::PoseSample sample;
      sample.timestamp_ns = record.timestamp_ns;
      sample.position = record.position;
      sample.bodyToNed = record.bodyToNed;
      sample.gimbal = record.gimbal;
      if (record.timestamp_ns >= fromNs_ && record.timestamp_ns < toNs_) {
        sample.position.latitude_deg = std::numeric_limits<double>::quiet_NaN();
      }
      push(sample, buffer);
    }
  }
  const char* name() const override { return "recording with NaN"; }

 private:
  const std::vector<sequence::TelemetryRecord>& records_;
  std::int64_t fromNs_;
  std::int64_t toNs_;
  std::size_t next_ = 0;
};

// Lift statuses per frame from the detections file.
std::map<std::int64_t, std::map<std::string, int>> liftStatusesByFrame(const std::string& path) {
  output_files::DetectionsFile file;
  std::string why;
  EXPECT_TRUE(output_files::readDetectionsFile(path, &file, &why)) << why;
  std::map<std::int64_t, std::map<std::string, int>> byFrame;
  for (const output_files::DetectionRecord& row : file.rows) {
    ++byFrame[row.frameId][output_files::toString(row.liftStatus)];
  }
  return byFrame;
}

TEST(AppFaults, NanPoseIsRefusedCountedAndTheLoopRecovers) {
  const std::string dir = sequence();
  sequence::SequenceReader reader;
  std::string why;
  ASSERT_TRUE(reader.open(dir, &why)) << why;
  const auto& frames = reader.frames();
  // NaN from just after frame 8's time to frame 15's: frames 9..14 find no good sample after
  // them (Invalid while extrapolating past the last good one), later frames are fine again.
  const std::int64_t from = frames[8].timestamp_ns + 1;
  const std::int64_t to = frames[15].timestamp_ns;
  const std::string out = test::scratchDir("nan_pose");
  config::AppConfig config = loopConfig(dir);
  config.app.detectionsCsv = out + "/detections.csv";
  App app;
  AppSeams seams;
  seams.perception = truth(dir);
  seams.poseInput = std::make_unique<NanPoseInput>(reader, from, to);
  ASSERT_TRUE(app.init(config, test::everyFrame(), std::move(seams), &why)) << why;
  ASSERT_TRUE(app.run(&why)) << why;
  const LoopCounters c = app.counters();
  EXPECT_EQ(c.framesProcessed, static_cast<std::uint64_t>(kFrames));
  EXPECT_GT(c.telemetryRejected, 0U);
  EXPECT_GT(c.invalidPose + c.stalePose, 0U);
  const auto statuses = liftStatusesByFrame(out + "/detections.csv");
  int refused = 0;
  for (const auto& [frameId, counts] : statuses) {
    const bool bad = counts.count("invalid_pose") + counts.count("stale_pose") > 0;
    refused += bad ? 1 : 0;
    if (frameId <= frames[7].frameId || frameId >= frames[17].frameId) {
      EXPECT_FALSE(bad) << "frame " << frameId;
      EXPECT_GT(counts.count("ok"), 0U) << "frame " << frameId;  // lifted again
    }
  }
  EXPECT_GE(refused, 3);
  std::printf("NaN pose: %llu samples refused, frames with invalid pose %llu, stale %llu\n",
              static_cast<unsigned long long>(c.telemetryRejected),
              static_cast<unsigned long long>(c.invalidPose),
              static_cast<unsigned long long>(c.stalePose));
}

TEST(AppFaults, TelemetryGapGivesStalePosesAndLiftingResumesAfterIt) {
  const std::string dir = test::copySequence(sequence(), "telemetry_gap");
  sequence::SequenceReader reader;
  std::string why;
  ASSERT_TRUE(reader.open(dir, &why)) << why;
  const auto& frames = reader.frames();
  const std::int64_t gapFrom = frames[8].timestamp_ns;
  const std::int64_t gapTo = frames[16].timestamp_ns;
  {
    // Drop the telemetry rows of the gap (a recorder that lost the link omits rows).
    std::ifstream in(dir + "/telemetry.csv");
    std::stringstream kept;
    std::string line;
    std::getline(in, line);
    kept << line << "\n";
    int dropped = 0;
    while (std::getline(in, line)) {
      const std::int64_t t = std::stoll(line.substr(0, line.find(',')));
      if (t > gapFrom && t < gapTo) {
        ++dropped;
        continue;
      }
      kept << line << "\n";
    }
    ASSERT_GT(dropped, 0);
    std::ofstream(dir + "/telemetry.csv", std::ios::trunc) << kept.str();
  }
  const std::string out = test::scratchDir("telemetry_gap_out");
  config::AppConfig config = loopConfig(dir);
  config.app.detectionsCsv = out + "/detections.csv";
  App app;
  AppSeams seams;
  seams.perception = truth(dir);
  ASSERT_TRUE(app.init(config, test::everyFrame(), std::move(seams), &why)) << why;
  ASSERT_TRUE(app.run(&why)) << why;
  const LoopCounters c = app.counters();
  EXPECT_EQ(c.framesProcessed, static_cast<std::uint64_t>(kFrames));
  // 0.8 s without telemetry: the frames more than pose.max_age_s (0.2 s) from both ends.
  EXPECT_GE(c.stalePose, 3U);
  const auto statuses = liftStatusesByFrame(out + "/detections.csv");
  int stale = 0;
  for (const auto& [frameId, counts] : statuses) {
    stale += counts.count("stale_pose") > 0 ? 1 : 0;
    if (frameId >= frames[18].frameId) {
      EXPECT_GT(counts.count("ok"), 0U) << "frame " << frameId << " not lifted after the gap";
    }
  }
  // Frames with vehicles show it in the file; a frame without any has no row to show it.
  EXPECT_GE(stale, 3);
  EXPECT_LE(stale, static_cast<int>(c.stalePose));
}

// Recorded telemetry with a gimbal pitch of 999 deg in one row and, after another row, a
// repeat of its timestamp with the height 5.5 m off. Both rows are named (file and line) as
// warnings at start-up; the recording still plays, both samples are refused and counted, and
// every frame is lifted with the good samples around them (before, the 999 deg row was taken
// as -81 deg and its frames were lifted metres off with status ok).
TEST(AppFaults, ImplausibleRecordedTelemetryRowsAreNamedRefusedAndCounted) {
  const std::string dir = test::copySequence(sequence(), "bad_telemetry_rows");
  std::vector<std::string> lines;
  {
    std::ifstream in(dir + "/telemetry.csv");
    for (std::string line; std::getline(in, line);) {
      lines.push_back(line);
    }
  }
  ASSERT_GT(lines.size(), 20U);
  const auto fields = [](const std::string& line) {
    std::vector<std::string> out;
    std::stringstream stream(line);
    for (std::string field; std::getline(stream, field, ',');) {
      out.push_back(field);
    }
    return out;
  };
  const auto join = [](const std::vector<std::string>& f) {
    std::string out;
    for (std::size_t i = 0; i < f.size(); ++i) {
      out += (i ? "," : "") + f[i];
    }
    return out;
  };
  const std::size_t gimbalRow = lines.size() / 3;  // index into lines; file line = index + 1
  std::vector<std::string> bad = fields(lines[gimbalRow]);
  ASSERT_EQ(bad.size(), 12U);
  bad[9] = "999";  // gimbal_pitch_deg
  lines[gimbalRow] = join(bad);
  const std::size_t repeatedRow = 2 * lines.size() / 3;
  std::vector<std::string> repeat = fields(lines[repeatedRow]);
  repeat[3] = std::to_string(std::stod(repeat[3]) + 5.5);  // height_m
  lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(repeatedRow) + 1, join(repeat));
  {
    std::ofstream out(dir + "/telemetry.csv", std::ios::trunc);
    for (const std::string& line : lines) {
      out << line << "\n";
    }
  }

  // Start-up: the rows the pose buffer will refuse, by file and line.
  platform::MonotonicClock clock;
  platform::replay::SequenceReplay replay(clock);
  std::string why;
  ASSERT_TRUE(replay.open(dir, {}, &why)) << why;
  RecordingPoseInput input;
  input.open(replay, false, 0.2, telemetry::PoseLimits{});
  ASSERT_EQ(input.warnings().size(), 2U);
  const std::string file = (fs::path(dir) / "telemetry.csv").string();
  EXPECT_EQ(input.warnings()[0], file + ":" + std::to_string(gimbalRow + 1) +
                                     ": gimbal_pitch_deg 999 outside [-120, 30]: sample refused "
                                     "(outside the pose limits)");
  EXPECT_EQ(
      input.warnings()[1].rfind(file + ":" + std::to_string(repeatedRow + 2) + ": timestamp ", 0),
      0U)
      << input.warnings()[1];
  EXPECT_NE(input.warnings()[1].find("repeated with other values: height differs by (m) 5.5"),
            std::string::npos)
      << input.warnings()[1];

  // The run: both refused and counted, every frame posed and lifted.
  const std::string out = test::scratchDir("bad_telemetry_rows_out");
  config::AppConfig config = loopConfig(dir);
  config.app.detectionsCsv = out + "/detections.csv";
  App app;
  AppSeams seams;
  seams.perception = truth(dir);
  ASSERT_TRUE(app.init(config, test::everyFrame(), std::move(seams), &why)) << why;
  ASSERT_TRUE(app.run(&why)) << why;
  const LoopCounters c = app.counters();
  EXPECT_EQ(c.framesProcessed, static_cast<std::uint64_t>(kFrames));
  EXPECT_EQ(c.telemetryRejected, 2U);
  EXPECT_EQ(c.noPose + c.stalePose + c.invalidPose, 0U);
  for (const auto& [frameId, counts] : liftStatusesByFrame(out + "/detections.csv")) {
    EXPECT_GT(counts.count("ok"), 0U) << "frame " << frameId;
    EXPECT_EQ(counts.count("invalid_pose") + counts.count("stale_pose") + counts.count("no_pose"),
              0U)
        << "frame " << frameId;
  }
}

// A camera (emulated driver) that is unplugged after 5 frames and plugged in again at the
// camera's second reopen attempt, with 5 more frames. Every call comes from the capture thread.
class UnpluggingCamera final : public platform::v4l2::V4l2Device {
 public:
  static constexpr int kCameraWidth_px = 64;
  static constexpr int kCameraHeight_px = 48;

  UnpluggingCamera() {
    test::FakeNodeSpec spec;
    spec.formats = {V4L2_PIX_FMT_YUYV};
    spec.width_px = kCameraWidth_px;
    spec.height_px = kCameraHeight_px;
    device_.addNode(spec);
    pushFrames(5);
  }
  int open(const char* path) override {
    if (unplugged_ && !replugged_ && ++reopenAttempts_ >= 2) {
      device_.replug(kPath);
      pushFrames(5);
      replugged_ = true;
    }
    return device_.open(path);
  }
  int close(int fd) override { return device_.close(fd); }
  int ioctl(int fd, unsigned long request, void* argument) override {
    const int result = device_.ioctl(fd, request, argument);
    if (request == VIDIOC_DQBUF && result >= 0) {
      ++dequeued_;
    }
    return result;
  }
  void* mmap(int fd, std::size_t length, std::int64_t offset, int* error) override {
    return device_.mmap(fd, length, offset, error);
  }
  int munmap(void* address, std::size_t length) override { return device_.munmap(address, length); }
  int poll(int fd, int timeout_ms, short* revents) override {
    if (dequeued_ == 5 && !unplugged_) {
      device_.unplug(kPath);
      unplugged_ = true;
      unpluggedAt_ns_.store(platform::monotonicNow_ns());
    }
    return device_.poll(fd, timeout_ms, revents);
  }
  std::vector<std::string> listVideoNodes() override { return device_.listVideoNodes(); }
  const test::FakeV4l2Device& fake() const { return device_; }
  int reopenAttempts() const { return reopenAttempts_; }
  std::int64_t unpluggedAt_ns() const { return unpluggedAt_ns_.load(); }

 private:
  static constexpr const char* kPath = "/dev/video0";
  void pushFrames(int count) {
    for (int i = 0; i < count; ++i) {
      test::FakeFrame frame;
      frame.bytes.assign(static_cast<std::size_t>(kCameraWidth_px * kCameraHeight_px * 2),
                         static_cast<std::uint8_t>(100 + 10 * i));
      // 10 Hz capture times (the driver's timeval has only microseconds: frames made in a
      // tight loop would share one, and the loop skips a frame whose time does not advance).
      frame.timestamp_ns = nextTimestampNs_;
      nextTimestampNs_ += 100'000'000;
      device_.pushFrame(kPath, std::move(frame));
    }
  }

  test::FakeV4l2Device device_;
  std::int64_t nextTimestampNs_ = platform::monotonicNow_ns();
  int dequeued_ = 0;
  int reopenAttempts_ = 0;
  bool unplugged_ = false;
  std::atomic<std::int64_t> unpluggedAt_ns_{0};  // set on the capture thread, read after run()
  bool replugged_ = false;
};

TEST(AppFaults, CameraDisappearsAndComesBackAndProcessingResumes) {
  // The rig: a 64 x 48 pinhole camera over the fixture DTM, telemetry none (the frames are
  // processed image-only: NoPose is counted, never a made-up position).
  config::AppConfig config = test::defaultConfigFor("");
  config.source.kind = config::FrameSourceKind::V4l2;
  config.source.v4l2.width_px = UnpluggingCamera::kCameraWidth_px;
  config.source.v4l2.height_px = UnpluggingCamera::kCameraHeight_px;
  config.source.v4l2.dequeueTimeout_ms = 50;
  config.camera.intrinsics.width_px = UnpluggingCamera::kCameraWidth_px;
  config.camera.intrinsics.height_px = UnpluggingCamera::kCameraHeight_px;
  config.camera.intrinsics.fx_px = 80.0;
  config.camera.intrinsics.fy_px = 80.0;
  config.camera.intrinsics.cx_px = 31.5;
  config.camera.intrinsics.cy_px = 23.5;
  config.camera.distortion = camera::Distortion{};
  config.telemetry.source = config::TelemetrySourceKind::None;
  config.dds.enabled = false;
  config.perception.preprocess.workingScale = 1.0;
  config.app.statsPeriod_s = 3600.0;
  UnpluggingCamera device;
  // When each frame was done, on the loop's clock: the recovery time runs from the unplug to
  // the first frame processed after the reopen.
  struct FrameTimes final : LoopObserver {
    std::vector<std::int64_t> done_ns;
    void onFrameDone(std::uint64_t /*framesProcessed*/) override {
      done_ns.push_back(platform::monotonicNow_ns());
    }
  } times;
  App app;
  AppSeams seams;
  seams.v4l2Device = &device;
  seams.observer = &times;
  RunSettings run = test::everyFrame();
  run.maxFrames = 10;
  std::string why;
  ASSERT_TRUE(app.init(config, run, std::move(seams), &why)) << why;
  ASSERT_TRUE(app.run(&why)) << why;
  const LoopCounters c = app.counters();
  EXPECT_EQ(c.deviceLosses, 1U);
  EXPECT_EQ(c.deviceReopens, 1U);
  EXPECT_EQ(c.framesIn, 10U);
  EXPECT_EQ(c.framesProcessed, 10U);  // 5 before the loss, 5 after it
  EXPECT_EQ(c.noPose, 10U);
  EXPECT_EQ(app.framesInPool(), app.poolCapacity());
  EXPECT_TRUE(device.fake().violations().empty()) << device.fake().violations().front();

  // Back at the second reopen attempt: the backoff waits the initial step, then twice it.
  ASSERT_EQ(times.done_ns.size(), 10U);
  EXPECT_EQ(device.reopenAttempts(), 2);
  const std::int64_t backoff_ms = 3 * platform::v4l2::V4l2CameraConfig{}.reopenInitialBackoff_ms;
  const double recovery_ms = static_cast<double>(times.done_ns[5] - device.unpluggedAt_ns()) / 1e6;
  std::vector<double> intervals_ms;
  for (std::size_t i = 1; i < times.done_ns.size(); ++i) {
    if (i != 5) {
      intervals_ms.push_back(static_cast<double>(times.done_ns[i] - times.done_ns[i - 1]) / 1e6);
    }
  }
  std::sort(intervals_ms.begin(), intervals_ms.end());
  EXPECT_GE(recovery_ms, static_cast<double>(backoff_ms));
  EXPECT_LT(recovery_ms, static_cast<double>(backoff_ms) + 2000.0 * test::timeScale());
  std::printf(
      "camera unplugged: %llu loss, %llu reopen at attempt %d; from the unplug to the first "
      "frame processed after the reopen %.0f ms (backoff %lld ms; other frame intervals "
      "median %.1f ms); %llu of %llu frames processed\n",
      static_cast<unsigned long long>(c.deviceLosses),
      static_cast<unsigned long long>(c.deviceReopens), device.reopenAttempts(), recovery_ms,
      static_cast<long long>(backoff_ms), intervals_ms[intervals_ms.size() / 2],
      static_cast<unsigned long long>(c.framesProcessed),
      static_cast<unsigned long long>(c.framesIn));
}

TEST(AppSource, FasterThanTheLoopDropsTheOldestAndAccountsForEveryFrame) {
  // Unpaced replay of small PNGs (a few ms each) into the real pipeline (tens of ms per frame):
  // the channel (depth 1) keeps only the newest frame.
  const std::string dir = sequence();
  config::AppConfig config = loopConfig(dir);
  RunSettings run;
  run.quiet = true;
  App app;
  std::string why;
  ASSERT_TRUE(app.init(config, run, AppSeams{}, &why)) << why;
  ASSERT_TRUE(app.run(&why)) << why;
  const LoopCounters c = app.counters();
  EXPECT_EQ(c.framesIn, static_cast<std::uint64_t>(kFrames));
  EXPECT_GT(c.framesDropped, 0U);
  // Every frame the source delivered was either processed or dropped, none lost or leaked.
  EXPECT_EQ(c.framesProcessed + c.framesDropped, c.framesIn);
  EXPECT_EQ(app.framesInPool(), app.poolCapacity());
  // Bounded latency: at most queue_depth frames ever waited, so every processed frame waited at
  // most one frame's processing; the queue histogram saw each processed frame once.
  EXPECT_EQ(app.stats().total(Stage::Queue).count(), c.framesProcessed);
  std::printf(
      "source faster than the loop: %llu in, %llu processed, %llu dropped; queue wait "
      "max %.1f ms vs processing max %.1f ms\n",
      static_cast<unsigned long long>(c.framesIn),
      static_cast<unsigned long long>(c.framesProcessed),
      static_cast<unsigned long long>(c.framesDropped),
      static_cast<double>(app.stats().total(Stage::Queue).max_ns()) / 1e6,
      static_cast<double>(app.stats().total(Stage::EndToEnd).max_ns()) / 1e6);
}

}  // namespace
}  // namespace vp::app
