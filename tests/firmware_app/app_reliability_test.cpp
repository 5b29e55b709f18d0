// The loop's reliability under stops, bad outputs and bad inputs (docs/firmware_app.md): a
// stop ends a long paced wait at once; the counters account for every frame taken from the
// source, those still waiting at the stop included; a write that fails mid-run is counted when
// it happens and leaves whole rows; errors are named once (no repeated prefix); and the exit
// status of a run says when nothing was processed or an output failed.
#include <signal.h>
#include <sys/resource.h>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "app.hpp"
#include "app_options.hpp"
#include "app_test_support.hpp"
#include "output_files/detections_file.hpp"
#include "output_files/trajectory_file.hpp"

namespace vp::app {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

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

// The truth perception, slowed down to `delay` per frame: a source faster than the loop.
class SlowPerception final : public test::ForwardingPerception {
 public:
  SlowPerception(std::unique_ptr<FramePerception> inner, std::chrono::milliseconds delay)
      : ForwardingPerception(std::move(inner)), delay_(delay) {}
  perception::PipelineStatus process(const cv::Mat& frame, std::int64_t timestamp_ns,
                                     const telemetry::PoseEstimate& pose) override {
    std::this_thread::sleep_for(delay_);
    return ForwardingPerception::process(frame, timestamp_ns, pose);
  }

 private:
  std::chrono::milliseconds delay_;
};

// Requests a stop from the processing thread once `at` frames are done.
class StopAfter final : public LoopObserver {
 public:
  explicit StopAfter(std::uint64_t at) : at_(at) {}
  void onFrameDone(std::uint64_t processed) override {
    done_.store(processed);
    if (processed == at_ && app != nullptr) {
      app->requestStop();
    }
  }
  App* app = nullptr;
  std::uint64_t done() const { return done_.load(); }

 private:
  std::uint64_t at_;
  std::atomic<std::uint64_t> done_{0};
};

std::string frameFile(const std::string& dir, std::size_t index) {
  sequence::SequenceReader reader;
  std::string why;
  EXPECT_TRUE(reader.open(dir, &why)) << why;
  return dir + "/" + reader.frames()[index].file;
}

TEST(AppAccounting, EveryFrameIsCountedWhenTheLoopStopsWithFramesWaiting) {
  // The source (unpaced PNGs, a few ms each, looping) outruns the loop (40 ms a frame), so a
  // frame always waits in the channel; the stop comes at frame 6, one frame is bad. Frames in
  // must equal processed + dropped + bad + refused, the frame left in the channel included.
  const std::string dir = test::copySequence(test::loopSequence(), "accounting");
  std::ofstream(frameFile(dir, 2), std::ios::binary | std::ios::trunc) << "not a PNG";
  config::AppConfig config = loopConfig(dir);
  config.source.loop = true;
  RunSettings run;
  run.quiet = true;
  StopAfter observer(6);
  AppSeams seams;
  seams.perception = std::make_unique<SlowPerception>(truth(dir), 40ms);
  seams.observer = &observer;
  App app;
  observer.app = &app;
  std::string why;
  ASSERT_TRUE(app.init(config, run, std::move(seams), &why)) << why;
  ASSERT_TRUE(app.run(&why)) << why;
  const LoopCounters c = app.counters();
  EXPECT_EQ(c.framesProcessed, 6U);
  EXPECT_GE(c.badFrames, 1U);  // once per pass over the sequence
  EXPECT_GT(c.framesDropped, 0U);
  EXPECT_EQ(c.framesIn, c.framesProcessed + c.framesDropped + c.badFrames + c.pipelineErrors)
      << "in " << c.framesIn << " processed " << c.framesProcessed << " dropped " << c.framesDropped
      << " bad " << c.badFrames << " refused " << c.pipelineErrors;
  EXPECT_EQ(app.framesInPool(), app.poolCapacity());
  EXPECT_TRUE(app.stopRequested());
}

TEST(AppAccounting, EveryFrameIsCountedWhenTheSourceEnds) {
  const std::string dir = test::copySequence(test::loopSequence(), "accounting_end");
  std::ofstream(frameFile(dir, 5), std::ios::binary | std::ios::trunc) << "not a PNG";
  config::AppConfig config = loopConfig(dir);
  RunSettings run;
  run.quiet = true;
  AppSeams seams;
  seams.perception = std::make_unique<SlowPerception>(truth(dir), 10ms);
  App app;
  std::string why;
  ASSERT_TRUE(app.init(config, run, std::move(seams), &why)) << why;
  ASSERT_TRUE(app.run(&why)) << why;
  const LoopCounters c = app.counters();
  EXPECT_EQ(c.framesIn, static_cast<std::uint64_t>(test::kLoopFrames));
  EXPECT_EQ(c.framesIn, c.framesProcessed + c.framesDropped + c.badFrames + c.pipelineErrors);
  EXPECT_FALSE(app.stopRequested());
}

TEST(AppStop, AStopEndsALongPacedWaitAtOnce) {
  // Frames 3.. are recorded 50 s later (a pause the reader accepts): a paced replay waits 50 s
  // for frame 3. A stop 200 ms into that wait must end the run within a second.
  const std::string dir = test::copySequence(test::loopSequence(), "long_wait");
  {
    std::istringstream in(test::readText(dir + "/frames.csv"));
    std::string out;
    std::string line;
    for (int i = 0; std::getline(in, line); ++i) {
      if (i >= 4) {  // header + frames 0..2 unchanged
        const std::size_t a = line.find(',');
        const std::size_t b = line.find(',', a + 1);
        const std::int64_t t = std::stoll(line.substr(a + 1, b - a - 1)) + 50'000'000'000;
        line = line.substr(0, a + 1) + std::to_string(t) + line.substr(b);
      }
      out += line + "\n";
    }
    std::ofstream(dir + "/frames.csv", std::ios::trunc) << out;
  }
  config::AppConfig config = loopConfig(dir);
  config.source.paced = true;
  RunSettings run;
  run.quiet = true;
  StopAfter observer(0);  // never stops by itself
  AppSeams seams;
  seams.perception = truth(dir);
  seams.observer = &observer;
  App app;
  std::string why;
  ASSERT_TRUE(app.init(config, run, std::move(seams), &why)) << why;
  std::chrono::steady_clock::time_point stoppedAt;
  std::thread stopper([&] {
    while (observer.done() < 3) {
      std::this_thread::sleep_for(10ms);
    }
    std::this_thread::sleep_for(200ms);
    stoppedAt = std::chrono::steady_clock::now();
    app.requestStop();
  });
  ASSERT_TRUE(app.run(&why)) << why;
  const auto ended = std::chrono::steady_clock::now();
  stopper.join();
  EXPECT_LT(ended - stoppedAt, 1s);
  EXPECT_EQ(app.counters().framesProcessed, 3U);
  EXPECT_EQ(app.framesInPool(), app.poolCapacity());
}

TEST(AppOutputs, AWriteFailingMidRunIsCountedWhenItHappensAndRowsStayWhole) {
  // A file-size limit stands in for a disk that fills during the run: the detections file takes
  // its header and a few frames, then every write fails. The loop goes on, counts each failed
  // frame, and the file ends with a complete row.
  const std::string dir = test::loopSequence();
  const std::string out = test::scratchDir("write_fails");
  config::AppConfig config = loopConfig(dir);
  RunSettings run;
  run.everyFrame = true;
  run.quiet = true;
  std::string why;
  // The size the whole run writes, without a limit.
  config.app.detectionsCsv = out + "/whole.csv";
  {
    AppSeams seams;
    seams.perception = truth(dir);
    App reference;
    ASSERT_TRUE(reference.init(config, run, std::move(seams), &why)) << why;
    ASSERT_TRUE(reference.run(&why)) << why;
  }
  const std::uintmax_t whole = fs::file_size(config.app.detectionsCsv);
  config.app.detectionsCsv = out + "/detections.csv";
  AppSeams seams;
  seams.perception = truth(dir);
  App app;
  ASSERT_TRUE(app.init(config, run, std::move(seams), &why)) << why;
  const std::uintmax_t header = fs::file_size(config.app.detectionsCsv);
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  struct sigaction previousSignal {};
  ASSERT_EQ(sigaction(SIGXFSZ, &ignore, &previousSignal), 0);
  rlimit previous{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &previous), 0);
  rlimit limit = previous;
  limit.rlim_cur = header + (whole - header) / 3;  // a third of the rows fit
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &limit), 0);
  const bool ran = app.run(&why);
  setrlimit(RLIMIT_FSIZE, &previous);
  sigaction(SIGXFSZ, &previousSignal, nullptr);
  ASSERT_TRUE(ran) << why;
  const LoopCounters c = app.counters();
  EXPECT_EQ(c.framesProcessed, static_cast<std::uint64_t>(test::kLoopFrames));
  EXPECT_GT(c.outputErrors, 0U);
  EXPECT_LT(c.outputErrors, c.framesProcessed) << "the first frames were written";
  const std::string text = test::readText(config.app.detectionsCsv);
  ASSERT_FALSE(text.empty());
  EXPECT_EQ(text.back(), '\n');
  output_files::DetectionsFile file;
  EXPECT_TRUE(output_files::readDetectionsFile(config.app.detectionsCsv, &file, &why)) << why;
  EXPECT_GT(file.rows.size(), 0U);
  std::string problems;
  EXPECT_EQ(runExitStatus(c, app.stopRequested(), 0, app.poolCapacity(), &problems),
            kExitRuntimeError);
  EXPECT_NE(problems.find("output write(s) failed"), std::string::npos) << problems;
}

TEST(AppExitStatus, NoFrameProcessedIsAFailureUnlessStopped) {
  LoopCounters c;
  c.framesIn = 2;
  c.badFrames = 2;
  std::string why;
  EXPECT_EQ(runExitStatus(c, false, 0, 3, &why), kExitRuntimeError);
  EXPECT_EQ(why, "no frame was processed (2 frames in: 2 bad, 0 refused, 0 dropped)\n");
  EXPECT_EQ(runExitStatus(c, true, 0, 3, &why), kExitOk);  // stopped before the first frame
  EXPECT_EQ(why, "");
  c.framesProcessed = 1;
  EXPECT_EQ(runExitStatus(c, false, 0, 3, &why), kExitOk);
  EXPECT_EQ(runExitStatus(c, false, 1, 3, &why), kExitRuntimeError);
  EXPECT_EQ(why, "1 of 3 frames not returned to the pool\n");
}

TEST(AppErrors, AStageNamesItselfOnce) {
  // The detection stage prefixes its own messages; the pipeline must not add the same prefix.
  config::AppConfig config = loopConfig(test::loopSequence());
  config.perception.detection.detectorModelPath = "/nonexistent/detector.onnx";
  App app;
  std::string why;
  ASSERT_FALSE(app.init(config, RunSettings{}, AppSeams{}, &why));
  const std::size_t first = why.find("detection stage: ");
  ASSERT_NE(first, std::string::npos) << why;
  EXPECT_EQ(why.find("detection stage: ", first + 1), std::string::npos) << why;
  EXPECT_NE(why.find("/nonexistent/detector.onnx"), std::string::npos) << why;

  // The ASM reader names its file: the app adds the key, not the path a second time.
  config = loopConfig(test::loopSequence());
  config.asmPath = "/nonexistent/asm.yaml";
  App second;
  ASSERT_FALSE(second.init(config, RunSettings{}, AppSeams{}, &why));
  const std::size_t path = why.find("/nonexistent/asm.yaml");
  ASSERT_NE(path, std::string::npos) << why;
  EXPECT_EQ(why.find("/nonexistent/asm.yaml", path + 1), std::string::npos) << why;
  EXPECT_EQ(why.rfind("perception.asm: ", 0), 0U) << why;
}

}  // namespace
}  // namespace vp::app
