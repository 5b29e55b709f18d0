#include "preprocess/preprocessor.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace vp::preprocess {

namespace {

using Clock = std::chrono::steady_clock;

double millisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

bool fail(std::string* why, const std::string& message) {
  if (why != nullptr) {
    *why = "preprocess: " + message;
  }
  return false;
}

bool overlaps(const cv::Mat& a, const cv::Mat& b) {
  return !a.empty() && !b.empty() && a.datastart < b.dataend && b.datastart < a.dataend;
}

}  // namespace

const char* toString(PreprocessStatus status) {
  switch (status) {
    case PreprocessStatus::Ok:
      return "ok";
    case PreprocessStatus::NotInitialised:
      return "not initialised";
    case PreprocessStatus::EmptyFrame:
      return "empty frame";
    case PreprocessStatus::WrongFrameType:
      return "wrong frame type";
    case PreprocessStatus::WrongFrameSize:
      return "wrong frame size";
    case PreprocessStatus::FrameIsOutput:
      return "frame is the preprocessor's own buffer";
  }
  return "unknown";
}

bool validate(const PreprocessOptions& options, std::string* why) {
  if (!(options.workingScale > 0.0 && options.workingScale <= 1.0)) {
    return fail(why,
                "working_scale: must be in (0, 1], got " + std::to_string(options.workingScale));
  }
  if (!(options.workingGsd_m >= 0.0 && options.workingGsd_m <= 1.0)) {
    return fail(why, "working_gsd_m: must be in [0, 1] m (0 = a fixed working_scale), got " +
                         std::to_string(options.workingGsd_m));
  }
  if (options.workingGsd_m > 0.0 &&
      !(options.minWorkingScale > 0.0 && options.minWorkingScale <= options.workingScale &&
        options.workingScale <= options.maxWorkingScale && options.maxWorkingScale <= 1.0)) {
    return fail(why,
                "min_working_scale / working_scale / max_working_scale: need 0 < min <= "
                "working_scale <= max <= 1, got " +
                    std::to_string(options.minWorkingScale) + " / " +
                    std::to_string(options.workingScale) + " / " +
                    std::to_string(options.maxWorkingScale));
  }
  if (options.workingGsd_m > 0.0 && options.maxWorkingGsd_m != 0.0 &&
      !(options.maxWorkingGsd_m >= options.workingGsd_m && options.maxWorkingGsd_m <= 1.0)) {
    return fail(why, "max_working_gsd_m: must be 0 (off) or in [working_gsd_m, 1] m, got " +
                         std::to_string(options.maxWorkingGsd_m) + " with working_gsd_m " +
                         std::to_string(options.workingGsd_m));
  }
  if (options.networkWidth_px < 32 || options.networkHeight_px < 32) {
    return fail(why, "network input: must be >= 32 x 32 px, got " +
                         std::to_string(options.networkWidth_px) + " x " +
                         std::to_string(options.networkHeight_px));
  }
  const int smallerSide = std::min(options.networkWidth_px, options.networkHeight_px);
  if (options.tileOverlap_px < 0 || options.tileOverlap_px >= smallerSide / 2) {
    return fail(why, "tile_overlap_px: must be in [0, " + std::to_string(smallerSide / 2) +
                         ") (half the network input), got " +
                         std::to_string(options.tileOverlap_px));
  }
  if (options.padValue < 0 || options.padValue > 255) {
    return fail(why, "pad_value: must be in [0, 255], got " + std::to_string(options.padValue));
  }
  if (options.threads < 1 || options.threads > 16) {
    return fail(why, "threads: must be in [1, 16], got " + std::to_string(options.threads));
  }
  std::string detail;
  if (options.whiteBalance && !validate(options.whiteBalanceOptions, &detail)) {
    return fail(why, detail);
  }
  if (!validate(options.exposure, &detail)) {
    return fail(why, detail);
  }
  return true;
}

bool Preprocessor::init(const PreprocessOptions& options, const camera::CameraModel& camera,
                        cv::Size frameSize, std::string* why) {
  initialised_ = false;
  if (!validate(options, why)) {
    return false;
  }
  const camera::Intrinsics& k = camera.intrinsics();
  if (frameSize.width <= 0 || frameSize.height <= 0) {
    return fail(why, "frame size must be > 0, got " + std::to_string(frameSize.width) + "x" +
                         std::to_string(frameSize.height));
  }
  if (k.width_px != frameSize.width || k.height_px != frameSize.height) {
    return fail(why, "frame size " + std::to_string(frameSize.width) + "x" +
                         std::to_string(frameSize.height) + " differs from the camera model's " +
                         std::to_string(k.width_px) + "x" + std::to_string(k.height_px) +
                         " (calibrate at the capture resolution)");
  }
  std::string detail;
  if (!parallel_.init(options.threads, &detail)) {
    return fail(why, detail);
  }

  // 1. Undistortion: only when the lens is not already a pinhole.
  remapActive_ = options.undistort && camera.distortion().model != camera::LensModel::Pinhole;
  frameCamera_ = camera;
  if (remapActive_) {
    if (!remap_.init(camera, k, &detail)) {
      return fail(why, detail);
    }
    if (!frameCamera_.init(k, camera::Distortion{}, &detail)) {
      return fail(why, "undistorted camera: " + detail);
    }
  }
  if (remapActive_ || options.whiteBalance) {
    corrected_.create(frameSize, CV_8UC3);
    corrected_.setTo(cv::Scalar::all(0));
  } else {
    corrected_.release();
  }

  // 2. White balance.
  if (options.whiteBalance && !balancer_.init(options.whiteBalanceOptions, frameSize, &detail)) {
    return fail(why, detail);
  }

  // 3.-4. Working image and tiles, per rung of the scale ladder (one rung at a fixed scale).
  frameSize_ = frameSize;
  options_ = options;
  std::array<double, kMaxScaleRungs> ladder{};
  std::size_t count = 1;
  ladder[0] = options.workingScale;
  if (options.workingGsd_m > 0.0) {
    count = buildScaleLadder(options.workingScale, options.minWorkingScale, options.maxWorkingScale,
                             ladder);
  }
  rungs_.clear();
  rungs_.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    Rung rung;
    std::string problem;
    if (!buildRung(rung, ladder[i], &problem)) {
      if (ladder[i] == options.workingScale) {
        return fail(why, problem);
      }
      if (ladder[i] > options.workingScale) {
        break;  // larger rungs need even more tiles: the ladder ends here
      }
      continue;
    }
    scales_[rungs_.size()] = ladder[i];
    rungs_.push_back(std::move(rung));
  }
  cv::Size largest(options.networkWidth_px, options.networkHeight_px);
  for (const Rung& rung : rungs_) {
    largest.width = std::max(largest.width, rung.geometry.workingWidth_px);
    largest.height = std::max(largest.height, rung.geometry.workingHeight_px);
    if (rung.scale == options.workingScale) {
      rung_ = static_cast<std::size_t>(&rung - rungs_.data());
    }
  }
  working_.create(largest, CV_8UC3);
  for (Rung& rung : rungs_) {
    const FrameGeometry& g = rung.geometry;
    rung.content = working_(cv::Rect(0, 0, g.workingWidth_px, g.workingHeight_px));
    for (std::size_t i = 0; i < rung.tileCount; ++i) {
      TileView& tile = rung.tiles[i];
      tile.data = working_.ptr<std::uint8_t>(tile.rect.y0_px) +
                  static_cast<std::size_t>(tile.rect.x0_px) * 3;
      tile.strideBytes = working_.step[0];
    }
  }
  // The rung each height's rung runs at (fewerTilesRung depends on that rung alone): once here.
  std::array<std::size_t, kMaxScaleRungs> tileCounts{};
  for (std::size_t i = 0; i < rungs_.size(); ++i) {
    tileCounts[i] = rungs_[i].tileCount;
  }
  for (std::size_t i = 0; i < rungs_.size(); ++i) {
    runRung_[i] = options.workingGsd_m > 0.0 && options.maxWorkingGsd_m > 0.0
                      ? fewerTilesRung(workingScales(), {tileCounts.data(), rungs_.size()}, i,
                                       options.maxWorkingGsd_m / options.workingGsd_m)
                      : i;
  }
  idealRung_ = rung_;
  output_ = PreprocessedFrame{};
  selectRung(rung_);
  lastError_[0] = '\0';
  initialised_ = true;
  return true;
}

bool Preprocessor::buildRung(Rung& rung, double scale, std::string* why) {
  // Python's int(round(w * s)) (half to even), as the training code sizes its working images.
  FrameGeometry& geometry = rung.geometry;
  geometry.frameWidth_px = frameSize_.width;
  geometry.frameHeight_px = frameSize_.height;
  geometry.workingWidth_px =
      std::max(1, static_cast<int>(std::nearbyint(frameSize_.width * scale)));
  geometry.workingHeight_px =
      std::max(1, static_cast<int>(std::nearbyint(frameSize_.height * scale)));
  geometry.scaleX = static_cast<double>(geometry.workingWidth_px) / frameSize_.width;
  geometry.scaleY = static_cast<double>(geometry.workingHeight_px) / frameSize_.height;
  const cv::Size content(geometry.workingWidth_px, geometry.workingHeight_px);
  std::string detail;
  if (!rung.resizer.init(frameSize_, content, parallel_.slots(), &detail)) {
    *why = detail;
    return false;
  }
  std::array<TileRect, kMaxTiles> rects{};
  rung.tileCount = layoutTiles(content.width, content.height, options_.networkWidth_px,
                               options_.networkHeight_px, options_.tileOverlap_px, rects);
  if (rung.tileCount == 0) {
    const int nx = tilesAlongAxis(content.width, options_.networkWidth_px, options_.tileOverlap_px);
    const int ny =
        tilesAlongAxis(content.height, options_.networkHeight_px, options_.tileOverlap_px);
    *why = "working image " + std::to_string(content.width) + "x" + std::to_string(content.height) +
           " needs " + std::to_string(nx) + " x " + std::to_string(ny) + " tiles, more than " +
           std::to_string(kMaxTiles) + ": lower working_scale or raise tile sizes";
    return false;
  }
  for (std::size_t i = 0; i < rung.tileCount; ++i) {
    rung.tiles[i].rect = rects[i];
    rung.tiles[i].index = static_cast<int>(i);
  }
  rung.scale = scale;
  return true;
}

void Preprocessor::selectRung(std::size_t index) {
  rung_ = index;
  const Rung& rung = rungs_[index];
  // A smaller rung's tiles reach into what a larger one wrote: padding again everywhere (one
  // grey value in every channel; memset, as cv::Mat::setTo allocates).
  std::memset(working_.data, options_.padValue, working_.total() * working_.elemSize());
  output_.geometry = rung.geometry;
  output_.tiles = std::span<const TileView>(rung.tiles.data(), rung.tileCount);
}

bool Preprocessor::adaptToGsd(double frameGsd_m) {
  if (!initialised_ || !(options_.workingGsd_m > 0.0) || rungs_.size() < 2) {
    return false;
  }
  idealRung_ = chooseRung(workingScales(), idealRung_, frameGsd_m / options_.workingGsd_m);
  const std::size_t next = runRung_[idealRung_];
  if (next == rung_) {
    return false;
  }
  selectRung(next);
  return true;
}

PreprocessStatus Preprocessor::process(const cv::Mat& bgrFrame) {
  char* message = lastError_.data();
  const std::size_t size = lastError_.size();
  if (!initialised_) {
    std::snprintf(message, size, "preprocess: init() has not succeeded");
    return PreprocessStatus::NotInitialised;
  }
  if (bgrFrame.empty() || bgrFrame.data == nullptr) {
    std::snprintf(message, size, "preprocess: empty frame (expected %dx%d, CV_8UC3)",
                  frameSize_.width, frameSize_.height);
    return PreprocessStatus::EmptyFrame;
  }
  if (bgrFrame.type() != CV_8UC3 || bgrFrame.dims != 2) {
    std::snprintf(message, size,
                  "preprocess: frame has %d channel(s) of OpenCV depth %d, expected 3 x 8 bit "
                  "(CV_8UC3, BGR)",
                  bgrFrame.channels(), bgrFrame.depth());
    return PreprocessStatus::WrongFrameType;
  }
  if (bgrFrame.cols != frameSize_.width || bgrFrame.rows != frameSize_.height) {
    std::snprintf(message, size, "preprocess: frame is %dx%d, expected %dx%d", bgrFrame.cols,
                  bgrFrame.rows, frameSize_.width, frameSize_.height);
    return PreprocessStatus::WrongFrameSize;
  }
  if (overlaps(bgrFrame, corrected_) || overlaps(bgrFrame, working_)) {
    std::snprintf(message, size,
                  "preprocess: the frame shares memory with the preprocessor's own output");
    return PreprocessStatus::FrameIsOutput;
  }
  lastError_[0] = '\0';
  const Clock::time_point start = Clock::now();
  const cv::Mat* current = &bgrFrame;

  if (remapActive_) {
    auto body = [&](int begin, int end, int /*slot*/) {
      remap_.applyRows(bgrFrame, corrected_, begin, end);
    };
    parallel_.run(frameSize_.height, body);
    current = &corrected_;
  }
  const Clock::time_point undistorted = Clock::now();
  output_.timings.undistort_ms =
      std::chrono::duration<double, std::milli>(undistorted - start).count();

  // White balance: the gains are estimated on the (undistorted) frame; they are applied
  // inside the resize sweep below, which reads every source row once and writes both the
  // balanced full-resolution row (output().frame, for the crops and the annotated video) and
  // the working image - except after undistortion, where the resize would read and write the
  // one owned buffer: there the gains go on in place first.
  // The exposure gain is multiplied into the white balance's gains when there is an owned
  // frame to write (white balance or undistortion); otherwise it goes into the working image
  // only and output().frameGain hands it to the crops: no full-size copy of the frame.
  const std::array<float, 3>* gains = nullptr;
  cv::Mat* gained = nullptr;
  output_.whiteBalance = options_.whiteBalance ? balancer_.estimate(*current) : WhiteBalanceGains{};
  output_.exposure =
      options_.exposure.enabled ? estimateExposure(*current, options_.exposure) : ExposureGain{};
  output_.frameGain = 1.0F;
  if (!options_.whiteBalance && !remapActive_ && output_.exposure.applied) {
    gains_ = {output_.exposure.gain, output_.exposure.gain, output_.exposure.gain};
    gains = &gains_;
    output_.frameGain = output_.exposure.gain;
  } else if (options_.whiteBalance || output_.exposure.applied) {
    WhiteBalanceGains combined = output_.whiteBalance;
    for (float& gain : combined.gain) {
      gain *= output_.exposure.gain;
    }
    balancer_.setGains(combined);
    gains_ = combined.gain;
    if (remapActive_) {
      auto body = [&](int begin, int end, int /*slot*/) {
        balancer_.applyRows(corrected_, corrected_, begin, end);
      };
      parallel_.run(frameSize_.height, body);
    } else {
      gains = &gains_;
      gained = &corrected_;
    }
  }
  const Clock::time_point balanced = Clock::now();
  output_.timings.whiteBalance_ms =
      std::chrono::duration<double, std::milli>(balanced - undistorted).count();

  const cv::Mat& source = *current;
  resize(ResizeSource::bgr(source), gains, gained);
  output_.timings.resize_ms = millisecondsSince(balanced);
  output_.timings.total_ms = millisecondsSince(start);
  if (gained != nullptr) {
    output_.frame = corrected_;  // header copy: no allocation
    return PreprocessStatus::Ok;
  }
  output_.frame = source;  // header copy: no allocation
  return PreprocessStatus::Ok;
}

void Preprocessor::resize(const ResizeSource& source, const std::array<float, 3>* gains,
                          cv::Mat* gained) {
  Rung& rung = rungs_[rung_];
  auto body = [&](int begin, int end, int slot) {
    rung.resizer.applyRows(source, rung.content, begin, end, slot, gains, gained);
  };
  parallel_.run(rung.content.rows, body);
}

PreprocessStatus Preprocessor::process(const YuvFrame& frame) {
  char* message = lastError_.data();
  const std::size_t size = lastError_.size();
  const bool nv12 = frame.layout == YuvFrame::Layout::Nv12;
  const char* layout = nv12 ? "NV12" : "YUYV";
  if (!initialised_) {
    std::snprintf(message, size, "preprocess: init() has not succeeded");
    return PreprocessStatus::NotInitialised;
  }
  if (frame.data == nullptr || frame.width_px <= 0 || frame.height_px <= 0) {
    std::snprintf(message, size, "preprocess: empty %s frame (expected %dx%d)", layout,
                  frameSize_.width, frameSize_.height);
    return PreprocessStatus::EmptyFrame;
  }
  if (frame.width_px != frameSize_.width || frame.height_px != frameSize_.height) {
    std::snprintf(message, size, "preprocess: %s frame is %dx%d, expected %dx%d", layout,
                  frame.width_px, frame.height_px, frameSize_.width, frameSize_.height);
    return PreprocessStatus::WrongFrameSize;
  }
  const auto width = static_cast<std::size_t>(frame.width_px);
  const char* problem = nullptr;
  if (remapActive_ || options_.whiteBalance) {
    problem = "undistortion and white balance need a BGR frame";
  } else if (frame.width_px % 2 != 0 || (nv12 && frame.height_px % 2 != 0)) {
    problem = nv12 ? "width and height must be even" : "width must be even";
  } else if (frame.strideBytes < (nv12 ? width : 2 * width)) {
    problem = "rows are shorter than the width";
  } else if (nv12 && (frame.uv == nullptr || frame.uvStrideBytes < width)) {
    problem = "no UV plane, or its rows are shorter than the width";
  }
  if (problem != nullptr) {
    std::snprintf(message, size, "preprocess: %s frame refused: %s", layout, problem);
    return PreprocessStatus::WrongFrameType;
  }
  lastError_[0] = '\0';
  const Clock::time_point start = Clock::now();
  ResizeSource source;
  source.layout = nv12 ? ResizeSource::Layout::Nv12 : ResizeSource::Layout::Yuyv;
  source.data = frame.data;
  source.strideBytes = frame.strideBytes;
  source.uv = frame.uv;
  source.uvStrideBytes = frame.uvStrideBytes;
  // The exposure from the Y bytes (YUYV: every second byte), applied in the resize sweep.
  output_.exposure = options_.exposure.enabled
                         ? estimateExposureYuv(frame.data, frame.strideBytes, frame.width_px,
                                               frame.height_px, nv12 ? 1 : 2, options_.exposure)
                         : ExposureGain{};
  gains_ = {output_.exposure.gain, output_.exposure.gain, output_.exposure.gain};
  resize(source, output_.exposure.applied ? &gains_ : nullptr, nullptr);
  output_.frameGain = 1.0F;  // no full-resolution frame on this path
  output_.whiteBalance = WhiteBalanceGains{};
  output_.timings = PreprocessTimings{};
  output_.timings.resize_ms = millisecondsSince(start);
  output_.timings.total_ms = output_.timings.resize_ms;
  output_.frame = cv::Mat();  // no full-resolution BGR frame on this path
  return PreprocessStatus::Ok;
}

}  // namespace vp::preprocess
