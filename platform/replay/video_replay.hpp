// platform/replay/video_replay: a video file (MP4, MOV, AVI: OpenCV's FFmpeg backend) played
// back as the app's frame source, like a recorded sequence's frames (sequence_replay.hpp).
//
// Contract: open() opens the file and reads its size, frame rate and frame count; it fails
// naming the file (missing, not decodable, no frame rate). next() decodes the next frame on
// the calling (capture) thread and copies it into the caller's pool frame in place (CV_8UC3 of
// the video's size); the frame id is the frame's index in the file (continued across loops)
// and the timestamp its presentation time from the first frame (the container's PTS; frame
// index / frame rate when the container gives none or a PTS that does not increase, counted in
// counters().indexTimestamps). Paced, next() first waits until the frame is due on the clock
// (t0 + its timestamp, t0 the time of the first next()); unpaced it returns as fast as frames
// decode. A stop request cuts the wait short: next() returns Stopped and the next call delivers
// that same frame. Looping, the file is opened again after its last frame and timestamps keep
// increasing by loopPeriod_ns() (frame count x frame interval) per loop. The end of the file
// (or a frame the decoder cannot read, which FFmpeg reports the same way) is End; a frame of
// another size than the first is a BadFrame and the next call goes on. Nothing throws.
//
// Allocation: the decoder allocates per frame (FFmpeg buffers, OpenCV's conversion to BGR) on
// the capture thread; the frame is then copied into the pool's preallocated buffer, so the
// processing thread sees the same memory as with a camera.
#pragma once

#include <cstdint>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include "core/frame_pool.hpp"
#include "platform/clock/monotonic_clock.hpp"
#include "platform/replay/sequence_replay.hpp"

namespace vp::platform::replay {

struct VideoCounters {
  std::uint64_t frames = 0;           // delivered
  std::uint64_t badFrames = 0;        // decoded at another size
  std::uint64_t loops = 0;            // completed passes
  std::uint64_t indexTimestamps = 0;  // frames timed by index / frame rate (no usable PTS)
};

class VideoReplay {
 public:
  explicit VideoReplay(Clock& clock) : clock_(clock) {}

  bool open(const std::string& path, const ReplayOptions& options, std::string* why);
  ReplayStatus next(Frame& out, std::string* why);

  const std::string& path() const { return path_; }
  int width_px() const { return width_; }
  int height_px() const { return height_; }
  double frameRate_hz() const { return frameRate_hz_; }
  std::int64_t frameCount() const { return frameCount_; }  // the container's (an estimate)
  std::int64_t loopPeriod_ns() const { return loopPeriodNs_; }
  const VideoCounters& counters() const { return counters_; }

 private:
  bool decode(std::string* why);  // the next frame into decoded_; false at the end

  Clock& clock_;
  std::string path_;
  ReplayOptions options_{};
  cv::VideoCapture capture_;
  cv::Mat decoded_;       // the decoder's output (capture thread)
  bool pending_ = false;  // decoded_ holds a frame a stop kept from being delivered
  std::int64_t pendingNs_ = 0;
  std::int64_t pendingId_ = 0;
  int width_ = 0;
  int height_ = 0;
  double frameRate_hz_ = 0.0;
  std::int64_t frameCount_ = 0;
  std::int64_t loopPeriodNs_ = 0;
  std::int64_t index_ = 0;  // index of the next frame in the file
  std::int64_t lastPtsNs_ = -1;
  std::uint64_t loop_ = 0;
  bool started_ = false;
  std::int64_t startNs_ = 0;
  VideoCounters counters_{};
};

}  // namespace vp::platform::replay
