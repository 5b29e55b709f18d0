// Replay of a video file as the frame source: frames in order into the pool's own buffer, times
// from the container's PTS, pacing on the clock, a stop that keeps the frame, looping, and the
// start-up errors naming the file. Videos are written by the test (cv::VideoWriter).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include "core/frame_pool.hpp"
#include "platform/clock/monotonic_clock.hpp"
#include "platform/replay/video_replay.hpp"

namespace vp::platform::replay {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth_px = 64;
constexpr int kHeight_px = 48;
constexpr int kFrames = 12;
constexpr double kFps = 10.0;

// Frame i is a flat grey of 20 * i (lossy codecs keep a flat image's level within a few units
// (mp4v: 5)).
std::string writeVideo(const fs::path& path, int fourcc) {
  cv::VideoWriter writer(path.string(), cv::CAP_FFMPEG, fourcc, kFps,
                         cv::Size(kWidth_px, kHeight_px));
  if (!writer.isOpened()) {
    return "";
  }
  for (int i = 0; i < kFrames; ++i) {
    writer.write(cv::Mat(kHeight_px, kWidth_px, CV_8UC3, cv::Scalar::all(20.0 * i)));
  }
  writer.release();
  return path.string();
}

class VideoReplayTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("vp_video_replay_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_);
    ASSERT_TRUE(pool.init(2, kWidth_px, kHeight_px));
  }
  void TearDown() override { fs::remove_all(root_); }

  fs::path root_;
  FramePool pool;
  ManualClock clock{5'000'000'000};
};

TEST_F(VideoReplayTest, Mp4AndAviFramesComeInOrderIntoThePoolBufferTimedByPts) {
  for (const auto& [name, fourcc] :
       {std::pair{"clip.mp4", cv::VideoWriter::fourcc('m', 'p', '4', 'v')},
        std::pair{"clip.avi", cv::VideoWriter::fourcc('M', 'J', 'P', 'G')}}) {
    SCOPED_TRACE(name);
    const std::string path = writeVideo(root_ / name, fourcc);
    ASSERT_FALSE(path.empty()) << "cv::VideoWriter cannot write " << name;
    VideoReplay replay(clock);
    std::string why;
    ASSERT_TRUE(replay.open(path, {false, false}, &why)) << why;
    EXPECT_EQ(replay.width_px(), kWidth_px);
    EXPECT_EQ(replay.height_px(), kHeight_px);
    EXPECT_DOUBLE_EQ(replay.frameRate_hz(), kFps);
    EXPECT_EQ(replay.frameCount(), kFrames);
    EXPECT_EQ(replay.loopPeriod_ns(), kFrames * 100'000'000LL);
    Frame& frame = pool.frame(0);
    const uchar* buffer = frame.image.data;
    for (int i = 0; i < kFrames; ++i) {
      ASSERT_EQ(replay.next(frame, &why), ReplayStatus::Frame) << why;
      EXPECT_EQ(frame.image.data, buffer) << "decoded into another buffer";
      EXPECT_EQ(frame.frameId, i);
      EXPECT_EQ(frame.timestamp_ns, i * 100'000'000LL);
      EXPECT_NEAR(cv::mean(frame.image)[0], 20.0 * i, 8.0);  // neighbours are 20 apart
    }
    EXPECT_EQ(replay.next(frame, &why), ReplayStatus::End);
    EXPECT_EQ(replay.counters().frames, static_cast<std::uint64_t>(kFrames));
    EXPECT_EQ(replay.counters().indexTimestamps, 0U) << "the container's PTS were not used";
  }
}

// Stops on the first frame's paced wait (tests/platform/replay's ManualClock honours it).
class StopAfter final : public StopCondition {
 public:
  bool stopRequested() const override { return stop; }
  bool stop = false;
};

TEST_F(VideoReplayTest, PacedFramesWaitForTheirTimeAndAStopKeepsTheFrame) {
  const std::string path =
      writeVideo(root_ / "clip.avi", cv::VideoWriter::fourcc('M', 'J', 'P', 'G'));
  VideoReplay replay(clock);
  std::string why;
  ASSERT_TRUE(replay.open(path, {true, false}, &why)) << why;
  Frame& frame = pool.frame(0);
  const std::int64_t t0 = clock.now_ns();
  ASSERT_EQ(replay.next(frame, &why), ReplayStatus::Frame);
  EXPECT_EQ(clock.now_ns(), t0);
  StopAfter stop;
  clock.setStopCondition(&stop);
  stop.stop = true;
  EXPECT_EQ(replay.next(frame, &why), ReplayStatus::Stopped);
  stop.stop = false;
  ASSERT_EQ(replay.next(frame, &why), ReplayStatus::Frame);
  EXPECT_EQ(frame.frameId, 1) << "the stopped frame was lost";
  EXPECT_EQ(clock.now_ns(), t0 + 100'000'000);
  ASSERT_EQ(replay.next(frame, &why), ReplayStatus::Frame);
  EXPECT_EQ(clock.now_ns(), t0 + 200'000'000);
  clock.setStopCondition(nullptr);
}

TEST_F(VideoReplayTest, LoopingStartsOverWithIncreasingTimesAndIds) {
  const std::string path =
      writeVideo(root_ / "clip.avi", cv::VideoWriter::fourcc('M', 'J', 'P', 'G'));
  VideoReplay replay(clock);
  std::string why;
  ASSERT_TRUE(replay.open(path, {false, true}, &why)) << why;
  Frame& frame = pool.frame(0);
  std::int64_t last = -1;
  for (int i = 0; i < 2 * kFrames + 3; ++i) {
    ASSERT_EQ(replay.next(frame, &why), ReplayStatus::Frame) << why;
    EXPECT_GT(frame.timestamp_ns, last);
    last = frame.timestamp_ns;
    EXPECT_EQ(frame.frameId, i);
    EXPECT_EQ(frame.timestamp_ns, i * 100'000'000LL);
  }
  EXPECT_EQ(replay.counters().loops, 2U);
}

TEST_F(VideoReplayTest, MissingOrUndecodableFilesAndAWrongPoolFrameAreNamed) {
  VideoReplay replay(clock);
  std::string why;
  EXPECT_FALSE(replay.open((root_ / "none.mp4").string(), {}, &why));
  EXPECT_EQ(why, (root_ / "none.mp4").string() + ": video file not found");
  std::ofstream(root_ / "junk.mp4") << "not a video at all";
  EXPECT_FALSE(replay.open((root_ / "junk.mp4").string(), {}, &why));
  EXPECT_NE(why.find("junk.mp4: cannot open the video"), std::string::npos) << why;

  const std::string path =
      writeVideo(root_ / "clip.avi", cv::VideoWriter::fourcc('M', 'J', 'P', 'G'));
  ASSERT_TRUE(replay.open(path, {false, false}, &why)) << why;
  FramePool small;
  ASSERT_TRUE(small.init(1, 32, 24));
  EXPECT_EQ(replay.next(small.frame(0), &why), ReplayStatus::Error);
  EXPECT_NE(why.find("output frame is 32x24"), std::string::npos) << why;
  EXPECT_EQ(replay.next(pool.frame(0), &why), ReplayStatus::Frame) << "the wrong call advanced";
  EXPECT_EQ(pool.frame(0).frameId, 0);
}

}  // namespace
}  // namespace vp::platform::replay
