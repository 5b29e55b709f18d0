// Tests of the pipelined loop (app.pipeline: on; firmware_app/app.hpp, docs/firmware_app.md) on
// simulated sequences with the shipped pipeline: the same detections and trajectory files and
// counts as the serial loop, the two halves really overlapping with at most one frame between
// them, a frame refused in the middle counted while the loop goes on, a stop with every frame
// back in the pool, and a source faster than the loop with the latency still bounded.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <string>
#include <utility>

#include "app.hpp"
#include "app_test_support.hpp"

namespace vp::app {
namespace {

constexpr int kFrames = test::kLoopFrames;

config::AppConfig pipelineConfig(const std::string& sequenceDir, config::PipelineMode mode) {
  config::AppConfig config = test::defaultConfigFor(sequenceDir);
  config.dds.enabled = false;
  config.source.paced = false;
  config.perception.preprocess.workingScale = 1.0;
  config.app.statsPeriod_s = 3600.0;
  config.app.pipeline = mode;
  return config;
}

// The shipped stage, watched: how many frames are between detect() and the end of finish(), the
// most ever, how often the two halves ran at the same time, and (refuseAt >= 0) the frame of
// that index handed to the pipeline as an empty image, which preprocessing refuses.
class WatchedStage final : public test::ForwardingPerception {
 public:
  WatchedStage(std::unique_ptr<FramePerception> inner, int refuseAt)
      : ForwardingPerception(std::move(inner)), refuseAt_(refuseAt) {}

  perception::PipelineStatus process(const cv::Mat& bgrFrame, std::int64_t timestamp_ns,
                                     const telemetry::PoseEstimate& pose) override {
    return ForwardingPerception::process(pick(bgrFrame), timestamp_ns, pose);
  }
  perception::PipelineStatus detect(std::size_t slot, const cv::Mat& bgrFrame,
                                    std::int64_t timestamp_ns,
                                    const telemetry::PoseEstimate& pose) override {
    const int between = between_.fetch_add(1) + 1;
    maxBetween_.store(std::max(maxBetween_.load(), between));
    detecting_.store(true);
    if (finishing_.load()) {
      overlaps_.fetch_add(1);
    }
    const perception::PipelineStatus status =
        ForwardingPerception::detect(slot, pick(bgrFrame), timestamp_ns, pose);
    detecting_.store(false);
    return status;
  }
  perception::PipelineStatus finish(std::size_t slot) override {
    finishing_.store(true);
    if (detecting_.load()) {
      overlaps_.fetch_add(1);
    }
    const perception::PipelineStatus status = ForwardingPerception::finish(slot);
    finishing_.store(false);
    between_.fetch_sub(1);
    return status;
  }

  int maxBetween() const { return maxBetween_.load(); }
  int overlaps() const { return overlaps_.load(); }

 private:
  const cv::Mat& pick(const cv::Mat& frame) { return frameIndex_++ == refuseAt_ ? empty_ : frame; }

  int refuseAt_;
  int frameIndex_ = 0;  // frames seen, on the thread that calls detect() (or process())
  cv::Mat empty_;
  std::atomic<int> between_{0};
  std::atomic<int> maxBetween_{0};
  std::atomic<bool> detecting_{false};
  std::atomic<bool> finishing_{false};
  std::atomic<int> overlaps_{0};
};

struct LoopRun {
  LoopCounters counters{};
  std::string detections;
  std::string tracks;
  int maxBetween = 0;
  int overlaps = 0;
  bool poolFull = false;
  std::size_t poolCapacity = 0;
  std::uint64_t queueCount = 0;
};

// Every frame (the source waits for the loop) through the shipped pipeline into the files.
LoopRun runAll(const std::string& dir, config::PipelineMode mode, const std::string& name,
               int refuseAt = -1) {
  const std::string out = test::scratchDir(name);
  config::AppConfig config = pipelineConfig(dir, mode);
  config.app.trajectoryCsv = out + "/tracks.csv";
  config.app.detectionsCsv = out + "/detections.csv";
  WatchedStage* watched = nullptr;
  LoopRun result;
  {
    App app;
    AppSeams seams;
    seams.wrapPerception = [&](std::unique_ptr<FramePerception> inner) {
      auto stage = std::make_unique<WatchedStage>(std::move(inner), refuseAt);
      watched = stage.get();
      return stage;
    };
    std::string why;
    EXPECT_TRUE(app.init(config, test::everyFrame(), std::move(seams), &why)) << why;
    EXPECT_TRUE(app.run(&why)) << why;
    result.counters = app.counters();
    result.poolFull = app.framesInPool() == app.poolCapacity();
    result.poolCapacity = app.poolCapacity();
    result.queueCount = app.stats().total(Stage::Queue).count();
    if (watched != nullptr) {
      result.maxBetween = watched->maxBetween();
      result.overlaps = watched->overlaps();
    }
  }
  result.detections = test::readText(out + "/detections.csv");
  result.tracks = test::readText(out + "/tracks.csv");
  return result;
}

TEST(AppPipeline, GivesTheSerialLoopsFilesAndCountsWithTheHalvesOverlapping) {
  const std::string dir = test::loopSequence();
  ASSERT_FALSE(dir.empty());
  const LoopRun serial = runAll(dir, config::PipelineMode::Off, "pipeline_serial");
  const LoopRun pipelined = runAll(dir, config::PipelineMode::On, "pipeline_on");
  ASSERT_EQ(serial.counters.framesProcessed, static_cast<std::uint64_t>(kFrames));
  EXPECT_EQ(pipelined.counters.framesProcessed, serial.counters.framesProcessed);
  EXPECT_GT(serial.counters.detections, 0U);  // the shipped detector finds the vehicles
  EXPECT_EQ(pipelined.counters.detections, serial.counters.detections);
  EXPECT_EQ(pipelined.counters.lifted, serial.counters.lifted);
  EXPECT_EQ(pipelined.counters.pipelineErrors, 0U);
  EXPECT_EQ(pipelined.counters.telemetrySamples, serial.counters.telemetrySamples);
  // Byte for byte: the same detections and tracks, in the same frame order.
  EXPECT_FALSE(serial.detections.empty());
  EXPECT_FALSE(serial.tracks.empty());
  EXPECT_EQ(pipelined.detections, serial.detections);
  EXPECT_EQ(pipelined.tracks, serial.tracks);
  EXPECT_TRUE(pipelined.poolFull);
  // One frame more in flight than the serial loop's pool (queue depth 1 + 2).
  EXPECT_EQ(pipelined.poolCapacity, serial.poolCapacity + 1);
  // The halves ran on two threads at the same time, never more than two frames between
  // detect() and the end of finish(): the one being finished and at most one waiting.
  EXPECT_GT(pipelined.overlaps, 0);
  EXPECT_LE(pipelined.maxBetween, 2);
  EXPECT_EQ(serial.overlaps, 0);  // the serial loop never splits
  std::printf("pipelined: %llu detections over %d frames; halves overlapped %d times\n",
              static_cast<unsigned long long>(pipelined.counters.detections), kFrames,
              pipelined.overlaps);
}

TEST(AppPipeline, AFrameRefusedInTheMiddleIsCountedAndTheLoopGoesOnAsSerially) {
  const std::string dir = test::loopSequence();
  ASSERT_FALSE(dir.empty());
  constexpr int kRefused = 11;
  const LoopRun serial =
      runAll(dir, config::PipelineMode::Off, "pipeline_refused_serial", kRefused);
  const LoopRun pipelined = runAll(dir, config::PipelineMode::On, "pipeline_refused_on", kRefused);
  EXPECT_EQ(serial.counters.pipelineErrors, 1U);
  EXPECT_EQ(pipelined.counters.pipelineErrors, 1U);
  EXPECT_EQ(pipelined.counters.framesProcessed, static_cast<std::uint64_t>(kFrames - 1));
  EXPECT_EQ(pipelined.counters.framesProcessed, serial.counters.framesProcessed);
  EXPECT_EQ(pipelined.detections, serial.detections);
  EXPECT_EQ(pipelined.tracks, serial.tracks);
  // The refused frame has no row; the frames after it have theirs.
  EXPECT_EQ(pipelined.detections.find("\n" + std::to_string(kRefused) + ","), std::string::npos);
  EXPECT_TRUE(pipelined.poolFull);
}

// Requests a stop from the processing thread once `at` frames are done.
class StopAt final : public LoopObserver {
 public:
  explicit StopAt(std::uint64_t at) : at_(at) {}
  void onFrameDone(std::uint64_t processed) override {
    if (processed == at_ && app != nullptr) {
      app->requestStop();
    }
  }
  App* app = nullptr;

 private:
  std::uint64_t at_;
};

TEST(AppPipeline, AStopCompletesTheFramesTakenAndReturnsEveryFrameToThePool) {
  const std::string dir = test::loopSequence();
  ASSERT_FALSE(dir.empty());
  constexpr std::uint64_t kStopAt = 8;
  for (const config::PipelineMode mode : {config::PipelineMode::Off, config::PipelineMode::On}) {
    SCOPED_TRACE(config::toString(mode));
    config::AppConfig config = pipelineConfig(dir, mode);
    App app;
    StopAt stop(kStopAt);
    stop.app = &app;
    AppSeams seams;
    seams.observer = &stop;
    std::string why;
    ASSERT_TRUE(app.init(config, test::everyFrame(), std::move(seams), &why)) << why;
    ASSERT_TRUE(app.run(&why)) << why;
    EXPECT_TRUE(app.stopRequested());
    const LoopCounters c = app.counters();
    // Serial: the frame being processed ends the loop. Pipelined: the frames the detector thread
    // had already taken are completed, not lost: the one waiting in its slot and the one it may
    // have taken as the stopping frame's slot came free.
    EXPECT_GE(c.framesProcessed, kStopAt);
    EXPECT_LE(c.framesProcessed, kStopAt + (mode == config::PipelineMode::On ? 2 : 0));
    EXPECT_LT(c.framesIn, static_cast<std::uint64_t>(kFrames));
    EXPECT_EQ(c.framesProcessed + c.framesDropped, c.framesIn);
    EXPECT_EQ(app.framesInPool(), app.poolCapacity());
  }
}

TEST(AppPipeline, SourceFasterThanTheLoopDropsTheOldestWithOneFrameBetweenTheThreads) {
  // Unpaced replay, drop-oldest (depth 1): the channel keeps only the newest frame; the detector
  // thread takes one only when a hand-off slot is free.
  const std::string dir = test::loopSequence();
  ASSERT_FALSE(dir.empty());
  config::AppConfig config = pipelineConfig(dir, config::PipelineMode::On);
  RunSettings run;
  run.quiet = true;
  WatchedStage* watched = nullptr;
  App app;
  AppSeams seams;
  seams.wrapPerception = [&](std::unique_ptr<FramePerception> inner) {
    auto stage = std::make_unique<WatchedStage>(std::move(inner), -1);
    watched = stage.get();
    return stage;
  };
  std::string why;
  ASSERT_TRUE(app.init(config, run, std::move(seams), &why)) << why;
  ASSERT_TRUE(app.run(&why)) << why;
  const LoopCounters c = app.counters();
  EXPECT_EQ(c.framesIn, static_cast<std::uint64_t>(kFrames));
  EXPECT_GT(c.framesDropped, 0U);
  EXPECT_EQ(c.framesProcessed + c.framesDropped, c.framesIn);
  EXPECT_EQ(app.framesInPool(), app.poolCapacity());
  EXPECT_EQ(app.poolCapacity(), static_cast<std::size_t>(config.app.queueDepth + 3));
  EXPECT_EQ(app.stats().total(Stage::Queue).count(), c.framesProcessed);
  // Bounded latency: queue_depth frames wait in the channel, at most one between the threads.
  ASSERT_NE(watched, nullptr);
  EXPECT_LE(watched->maxBetween(), 2);
  std::printf(
      "pipelined, source faster than the loop: %llu in, %llu processed, %llu dropped; queue "
      "wait max %.1f ms, end-to-end max %.1f ms\n",
      static_cast<unsigned long long>(c.framesIn),
      static_cast<unsigned long long>(c.framesProcessed),
      static_cast<unsigned long long>(c.framesDropped),
      static_cast<double>(app.stats().total(Stage::Queue).max_ns()) / 1e6,
      static_cast<double>(app.stats().total(Stage::EndToEnd).max_ns()) / 1e6);
}

}  // namespace
}  // namespace vp::app
