#include "platform/replay/video_replay.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <system_error>

namespace vp::platform::replay {

namespace {

void setWhy(std::string* why, std::string message) {
  if (why != nullptr) {
    *why = std::move(message);
  }
}

}  // namespace

bool VideoReplay::open(const std::string& path, const ReplayOptions& options, std::string* why) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    setWhy(why, path + ": video file not found");
    return false;
  }
  if (!capture_.open(path, cv::CAP_FFMPEG) || !capture_.isOpened()) {
    setWhy(why, path + ": cannot open the video (OpenCV's FFmpeg backend does not decode it)");
    return false;
  }
  path_ = path;
  options_ = options;
  width_ = static_cast<int>(capture_.get(cv::CAP_PROP_FRAME_WIDTH));
  height_ = static_cast<int>(capture_.get(cv::CAP_PROP_FRAME_HEIGHT));
  frameRate_hz_ = capture_.get(cv::CAP_PROP_FPS);
  frameCount_ = static_cast<std::int64_t>(std::llround(capture_.get(cv::CAP_PROP_FRAME_COUNT)));
  if (width_ <= 0 || height_ <= 0) {
    setWhy(why, path + ": the video reports no frame size");
    return false;
  }
  if (!(frameRate_hz_ > 0.0) || !std::isfinite(frameRate_hz_)) {
    setWhy(why, path + ": the video reports no frame rate");
    return false;
  }
  const double interval_ns = 1e9 / frameRate_hz_;
  loopPeriodNs_ =
      frameCount_ > 0 ? std::llround(static_cast<double>(frameCount_) * interval_ns) : 0;
  pending_ = false;
  index_ = 0;
  lastPtsNs_ = -1;
  loop_ = 0;
  started_ = false;
  counters_ = VideoCounters{};
  return true;
}

bool VideoReplay::decode(std::string* why) {
  if (capture_.read(decoded_) && !decoded_.empty()) {
    return true;
  }
  if (!options_.loop) {
    return false;
  }
  // Looping: the file again from its start (reopening is the seek every container supports).
  const double interval_ns = 1e9 / frameRate_hz_;
  if (loopPeriodNs_ <= 0) {
    loopPeriodNs_ = lastPtsNs_ + std::llround(interval_ns);
  }
  capture_.release();
  if (!capture_.open(path_, cv::CAP_FFMPEG) || !capture_.read(decoded_) || decoded_.empty()) {
    setWhy(why, path_ + ": cannot read the video again to loop");
    return false;
  }
  ++loop_;
  ++counters_.loops;
  index_ = 0;
  lastPtsNs_ = -1;
  return true;
}

ReplayStatus VideoReplay::next(Frame& out, std::string* why) {
  if (out.image.type() != CV_8UC3 || out.image.cols != width_ || out.image.rows != height_) {
    setWhy(why, path_ + ": output frame is " + std::to_string(out.image.cols) + "x" +
                    std::to_string(out.image.rows) + " type " + std::to_string(out.image.type()) +
                    ", the video gives " + std::to_string(width_) + "x" + std::to_string(height_) +
                    " BGR8");
    return ReplayStatus::Error;
  }
  if (!pending_) {
    if (!decode(why)) {
      return ReplayStatus::End;
    }
    const std::int64_t index = index_++;
    // The container's presentation time of the frame just decoded; by index when it has none.
    const double pos_ms = capture_.get(cv::CAP_PROP_POS_MSEC);
    std::int64_t pts_ns = std::isfinite(pos_ms) ? std::llround(pos_ms * 1e6) : -1;
    if (pts_ns < 0 || pts_ns <= lastPtsNs_ || (index > 0 && pts_ns == 0)) {
      pts_ns = std::llround(static_cast<double>(index) * 1e9 / frameRate_hz_);
      if (pts_ns <= lastPtsNs_) {
        pts_ns = lastPtsNs_ + 1;
      }
      ++counters_.indexTimestamps;
    }
    lastPtsNs_ = pts_ns;
    pendingNs_ = pts_ns + static_cast<std::int64_t>(loop_) * loopPeriodNs_;
    pendingId_ = index + static_cast<std::int64_t>(loop_) * std::max<std::int64_t>(frameCount_, 1);
    pending_ = true;
    if (decoded_.type() != CV_8UC3 || decoded_.cols != width_ || decoded_.rows != height_) {
      pending_ = false;
      ++counters_.badFrames;
      setWhy(why, path_ + ": frame " + std::to_string(index) + " decoded as " +
                      std::to_string(decoded_.cols) + "x" + std::to_string(decoded_.rows) +
                      " type " + std::to_string(decoded_.type()) + ", the video is " +
                      std::to_string(width_) + "x" + std::to_string(height_) + " BGR8");
      return ReplayStatus::BadFrame;
    }
  }
  if (!started_) {
    started_ = true;
    startNs_ = clock_.now_ns();
  }
  if (options_.paced && !clock_.sleepUntil_ns(startNs_ + pendingNs_)) {
    return ReplayStatus::Stopped;  // pending_ stays: the next call delivers this frame
  }
  decoded_.copyTo(out.image);  // same size and type: into the pool's buffer, no allocation
  out.timestamp_ns = pendingNs_;
  out.frameId = pendingId_;
  out.status = FrameStatus::Ok;
  pending_ = false;
  ++counters_.frames;
  return ReplayStatus::Frame;
}

}  // namespace vp::platform::replay
