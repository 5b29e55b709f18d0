// Replay of a recorded sequence as frame and telemetry source: order, pacing, looping, and
// damaged frame files reported by name while the replay goes on.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/frame_pool.hpp"
#include "platform/clock/monotonic_clock.hpp"
#include "platform/replay/sequence_replay.hpp"

namespace vp::platform::replay {
namespace {

namespace fs = std::filesystem;

constexpr std::int64_t kFirstFrame_ns = 1700000000000000000;
constexpr std::int64_t kFrameInterval_ns = 100'000'000;

// A private copy of tests/fixtures/sequence_min (and the DTM its rig.yaml points at, ../dtm),
// so a test can damage frame files.
class ReplayTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("vp_replay_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_);
    fs::copy(fs::path(VP_FIXTURE_DIR) / "sequence_min", root_ / "sequence_min",
             fs::copy_options::recursive);
    fs::copy(fs::path(VP_FIXTURE_DIR) / "dtm", root_ / "dtm", fs::copy_options::recursive);
    ASSERT_TRUE(pool.init(2, 32, 24));
  }
  void TearDown() override { fs::remove_all(root_); }

  std::string sequence() const { return (root_ / "sequence_min").string(); }
  std::string framePath(int i) const {
    return (root_ / "sequence_min" / "frames" / ("00000" + std::to_string(i) + ".png")).string();
  }
  Frame& frame() { return pool.frame(0); }

  fs::path root_;
  FramePool pool;
  ManualClock clock{1'000'000'000};
};

TEST_F(ReplayTest, FramesComeInOrderWithRecordedIdsTimesAndPixels) {
  SequenceReplay replay(clock);
  std::string why;
  ASSERT_TRUE(replay.open(sequence(), {false, false}, &why)) << why;
  const uchar* buffer = frame().image.data;
  for (int i = 0; i < 2; ++i) {
    ASSERT_EQ(replay.next(frame(), &why), ReplayStatus::Frame) << why;
    EXPECT_EQ(frame().frameId, i);
    EXPECT_EQ(frame().timestamp_ns, kFirstFrame_ns + i * kFrameInterval_ns);
    EXPECT_EQ(frame().status, FrameStatus::Ok);
    EXPECT_EQ(frame().image.data, buffer);  // filled in place
    const cv::Mat expected = cv::imread(framePath(i), cv::IMREAD_COLOR);
    EXPECT_EQ(cv::norm(frame().image, expected, cv::NORM_INF), 0.0);
  }
  EXPECT_EQ(replay.next(frame(), &why), ReplayStatus::End);
  EXPECT_EQ(replay.counters().frames, 2u);
  EXPECT_EQ(clock.sleeps(), 0);  // unpaced
}

TEST_F(ReplayTest, PacedReplayWaitsUntilEachFrameIsDue) {
  SequenceReplay replay(clock);
  std::string why;
  ASSERT_TRUE(replay.open(sequence(), {true, true}, &why)) << why;
  const std::int64_t start_ns = clock.now_ns();
  for (int i = 0; i < 6; ++i) {
    ASSERT_EQ(replay.next(frame(), &why), ReplayStatus::Frame) << why;
    // Due at start + (t_i - t_first): the loop period here is 2 frames of 100 ms.
    EXPECT_EQ(clock.now_ns(), start_ns + i * kFrameInterval_ns);
  }
  // A pipeline that fell behind gets the next frame at once (no sleep into the past).
  clock.advance_ns(10 * kFrameInterval_ns);
  const std::int64_t late_ns = clock.now_ns();
  ASSERT_EQ(replay.next(frame(), &why), ReplayStatus::Frame);
  EXPECT_EQ(clock.now_ns(), late_ns);
}

TEST_F(ReplayTest, LoopingKeepsTimestampsAndIdsIncreasing) {
  SequenceReplay replay(clock);
  std::string why;
  ASSERT_TRUE(replay.open(sequence(), {false, true}, &why)) << why;
  EXPECT_EQ(replay.loopPeriod_ns(), 2 * kFrameInterval_ns);
  for (int i = 0; i < 7; ++i) {
    ASSERT_EQ(replay.next(frame(), &why), ReplayStatus::Frame) << why;
    EXPECT_EQ(frame().frameId, i);
    EXPECT_EQ(frame().timestamp_ns, kFirstFrame_ns + i * kFrameInterval_ns);
  }
  EXPECT_EQ(replay.counters().loops, 3u);
}

TEST_F(ReplayTest, CorruptTruncatedAndMissingFramesAreNamedAndSkipped) {
  {
    std::ofstream corrupt(framePath(0), std::ios::binary | std::ios::trunc);
    corrupt << "this is not a PNG file";
  }
  SequenceReplay replay(clock);
  std::string why;
  ASSERT_TRUE(replay.open(sequence(), {false, true}, &why)) << why;
  EXPECT_EQ(replay.next(frame(), &why), ReplayStatus::BadFrame);
  EXPECT_NE(why.find("frames/000000.png"), std::string::npos) << why;
  EXPECT_NE(why.find("frame 0"), std::string::npos) << why;
  ASSERT_EQ(replay.next(frame(), &why), ReplayStatus::Frame) << why;  // goes on
  EXPECT_EQ(frame().frameId, 1);

  // Truncate frame 1 to half its size, delete frame 0: the second loop reports both.
  const auto size = fs::file_size(framePath(1));
  fs::resize_file(framePath(1), size / 2);
  fs::remove(framePath(0));
  EXPECT_EQ(replay.next(frame(), &why), ReplayStatus::BadFrame);
  EXPECT_NE(why.find("frames/000000.png"), std::string::npos) << why;
  EXPECT_EQ(replay.next(frame(), &why), ReplayStatus::BadFrame);
  EXPECT_NE(why.find("frames/000001.png"), std::string::npos) << why;
  EXPECT_NE(why.find("(frame 1, frames.csv line 3, loop 1)"), std::string::npos) << why;
  EXPECT_EQ(replay.counters().badFrames, 3u);
  EXPECT_EQ(replay.counters().frames, 1u);
}

struct StopFlag final : StopCondition {
  std::atomic<bool> stop{false};
  bool stopRequested() const override { return stop.load(); }
};

// Rewrites frames.csv with these timestamps (the fixture's two frames).
void setFrameTimes(const std::string& sequence, std::int64_t t0_ns, std::int64_t t1_ns) {
  std::ofstream out(fs::path(sequence) / "frames.csv", std::ios::trunc);
  out << "frame_id,timestamp_ns,file\n0," << t0_ns << ",frames/000000.png\n1," << t1_ns
      << ",frames/000001.png\n";
}

TEST_F(ReplayTest, AStopCutsThePacedWaitShortAndTheFrameComesLater) {
  SequenceReplay replay(clock);
  std::string why;
  ASSERT_TRUE(replay.open(sequence(), {true, false}, &why)) << why;
  ASSERT_EQ(replay.next(frame(), &why), ReplayStatus::Frame) << why;
  StopFlag flag;
  flag.stop = true;
  clock.setStopCondition(&flag);
  const std::int64_t before_ns = clock.now_ns();
  EXPECT_EQ(replay.next(frame(), &why), ReplayStatus::Stopped);
  EXPECT_EQ(clock.now_ns(), before_ns);  // no time passed: the wait did not happen
  EXPECT_EQ(replay.counters().frames, 1u);
  EXPECT_EQ(replay.position(), 1u);  // frame 1 not delivered
  clock.setStopCondition(nullptr);
  ASSERT_EQ(replay.next(frame(), &why), ReplayStatus::Frame) << why;
  EXPECT_EQ(frame().frameId, 1);
}

TEST_F(ReplayTest, AStopEndsALongPacedWaitOnTheRealClockPromptly) {
  // The next frame is 50 s ahead (under the reader's largest gap): a stop 100 ms into the wait
  // must end it within the clock's poll period, not 50 s later.
  setFrameTimes(sequence(), kFirstFrame_ns, kFirstFrame_ns + 50'000'000'000);
  MonotonicClock realClock;
  StopFlag flag;
  realClock.setStopCondition(&flag);
  SequenceReplay replay(realClock);
  std::string why;
  ASSERT_TRUE(replay.open(sequence(), {true, false}, &why)) << why;
  ASSERT_EQ(replay.next(frame(), &why), ReplayStatus::Frame) << why;
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    flag.stop = true;
  });
  const auto start = std::chrono::steady_clock::now();
  const ReplayStatus status = replay.next(frame(), &why);
  const auto waited = std::chrono::steady_clock::now() - start;
  stopper.join();
  EXPECT_EQ(status, ReplayStatus::Stopped);
  EXPECT_LT(waited, std::chrono::seconds(2));
}

TEST_F(ReplayTest, AnAbsurdGapInFramesCsvIsAStartUpErrorNamingFileAndLine) {
  // The first frame at -0.1 s, the next at 1.7e18 ns: a paced replay would wait 54 years.
  setFrameTimes(sequence(), -100'000'000, kFirstFrame_ns);
  SequenceReplay replay(clock);
  std::string why;
  EXPECT_FALSE(replay.open(sequence(), {true, false}, &why));
  EXPECT_NE(why.find("frames.csv:3: timestamp_ns: jumps"), std::string::npos) << why;
}

TEST_F(ReplayTest, ATruncatedJpegIsABadFrameNamedByFileAndFrame) {
  // A JPEG cut short decodes "successfully" with libjpeg (grey rows, a warning on stderr); the
  // replay must refuse it. Frame 1 becomes a noisy JPEG of the rig's size, then loses its end.
  cv::Mat noise(24, 32, CV_8UC3);
  cv::randu(noise, cv::Scalar::all(0), cv::Scalar::all(255));
  std::vector<uchar> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", noise, jpeg, {cv::IMWRITE_JPEG_QUALITY, 95}));
  const fs::path jpegPath = root_ / "sequence_min" / "frames" / "000001.jpg";
  std::ofstream(jpegPath, std::ios::binary)
      .write(reinterpret_cast<const char*>(jpeg.data()), static_cast<std::streamsize>(jpeg.size()));
  {
    std::ofstream out(fs::path(sequence()) / "frames.csv", std::ios::trunc);
    out << "frame_id,timestamp_ns,file\n0," << kFirstFrame_ns << ",frames/000000.png\n1,"
        << kFirstFrame_ns + kFrameInterval_ns << ",frames/000001.jpg\n";
  }
  // Whole, it decodes.
  SequenceReplay whole(clock);
  std::string why;
  ASSERT_TRUE(whole.open(sequence(), {false, false}, &why)) << why;
  ASSERT_EQ(whole.next(frame(), &why), ReplayStatus::Frame) << why;
  ASSERT_EQ(whole.next(frame(), &why), ReplayStatus::Frame) << why;
  const std::size_t cut = jpeg.size() * 6 / 10;
  // The decoder alone takes the cut file for a good one (what the check is for).
  const std::vector<uchar> truncated(jpeg.begin(), jpeg.begin() + static_cast<long>(cut));
  EXPECT_FALSE(cv::imdecode(truncated, cv::IMREAD_COLOR).empty());
  fs::resize_file(jpegPath, cut);
  SequenceReplay replay(clock);
  ASSERT_TRUE(replay.open(sequence(), {false, false}, &why)) << why;
  ASSERT_EQ(replay.next(frame(), &why), ReplayStatus::Frame) << why;
  EXPECT_EQ(replay.next(frame(), &why), ReplayStatus::BadFrame);
  EXPECT_NE(why.find("frames/000001.jpg: truncated JPEG"), std::string::npos) << why;
  EXPECT_NE(why.find("(frame 1, frames.csv line 3)"), std::string::npos) << why;
  EXPECT_EQ(replay.counters().badFrames, 1u);
}

TEST_F(ReplayTest, WrongOutputFrameIsRefusedWithoutAdvancing) {
  SequenceReplay replay(clock);
  std::string why;
  ASSERT_TRUE(replay.open(sequence(), {false, false}, &why)) << why;
  Frame wrong;
  wrong.image.create(48, 64, CV_8UC3);
  EXPECT_EQ(replay.next(wrong, &why), ReplayStatus::Error);
  EXPECT_NE(why.find("output frame is 64x48"), std::string::npos) << why;
  EXPECT_NE(why.find("32x24"), std::string::npos) << why;
  EXPECT_EQ(wrong.image.cols, 64);
  EXPECT_EQ(replay.position(), 0u);
  ASSERT_EQ(replay.next(frame(), &why), ReplayStatus::Frame);
  EXPECT_EQ(frame().frameId, 0);
}

TEST_F(ReplayTest, OpenFailureNamesTheSequence) {
  SequenceReplay replay(clock);
  std::string why;
  EXPECT_FALSE(replay.open((root_ / "nowhere").string(), {}, &why));
  EXPECT_NE(why.find("nowhere"), std::string::npos) << why;
}

TEST_F(ReplayTest, TelemetryComesOutAsItFallsDue) {
  SequenceReplay replay(clock);
  std::string why;
  ASSERT_TRUE(replay.open(sequence(), {false, false}, &why)) << why;
  const auto& records = replay.reader().telemetry();
  ASSERT_EQ(records.size(), 4u);  // at -50, 0, +50, +100 ms around the first frame
  TelemetryReplay telemetry;
  telemetry.open(records, false, replay.loopPeriod_ns());
  std::vector<std::int64_t> due;
  while (const auto* record = telemetry.nextDue(kFirstFrame_ns)) {
    due.push_back(record->timestamp_ns);
  }
  EXPECT_EQ(due, (std::vector<std::int64_t>{kFirstFrame_ns - 50'000'000, kFirstFrame_ns}));
  const auto* next = telemetry.nextDue(kFirstFrame_ns + 60'000'000);
  ASSERT_NE(next, nullptr);
  EXPECT_EQ(next->timestamp_ns, kFirstFrame_ns + 50'000'000);
  EXPECT_EQ(next->gimbal.reference, records[2].gimbal.reference);
  EXPECT_EQ(telemetry.nextDue(kFirstFrame_ns + 60'000'000), nullptr);
  EXPECT_NE(telemetry.nextDue(kFirstFrame_ns + kFrameInterval_ns), nullptr);
  EXPECT_TRUE(telemetry.finished());
  EXPECT_EQ(telemetry.nextDue(kFirstFrame_ns * 2), nullptr);
}

TEST_F(ReplayTest, LoopedTelemetryFollowsTheFramesClock) {
  SequenceReplay replay(clock);
  std::string why;
  ASSERT_TRUE(replay.open(sequence(), {false, true}, &why)) << why;
  TelemetryReplay telemetry;
  telemetry.open(replay.reader().telemetry(), true, replay.loopPeriod_ns());
  std::vector<std::int64_t> times;
  const std::int64_t until_ns = kFirstFrame_ns + 3 * replay.loopPeriod_ns();
  while (const auto* record = telemetry.nextDue(until_ns)) {
    times.push_back(record->timestamp_ns);
  }
  ASSERT_FALSE(telemetry.finished());
  ASSERT_GE(times.size(), 12u);
  for (std::size_t i = 1; i < times.size(); ++i) {
    EXPECT_GE(times[i], times[i - 1]) << i;
  }
  EXPECT_LE(times.back(), until_ns);
  // The first record of the second pass: the first record shifted by one loop period.
  EXPECT_EQ(times[4], times[0] + replay.loopPeriod_ns());
}

}  // namespace
}  // namespace vp::platform::replay
