#include "detection/detection_stage.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace vp::detection {

namespace {

using Clock = std::chrono::steady_clock;

double millisecondsBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

bool fail(std::string* why, const std::string& message) {
  if (why != nullptr) {
    *why = "detection stage: " + message;
  }
  return false;
}

// The detector's four heads, in headIndex_ order, with their channel counts.
struct Head {
  const char* name;
  int channels;
};
constexpr std::array<Head, 4> kHeads{
    {{"heatmap", 1}, {"offset", 2}, {"size", 2}, {"direction", 2}}};

}  // namespace

const char* toString(DetectionStatus status) {
  switch (status) {
    case DetectionStatus::Ok:
      return "ok";
    case DetectionStatus::NotInitialised:
      return "detection stage not initialised";
    case DetectionStatus::NoTiles:
      return "the preprocessed frame has no tiles";
    case DetectionStatus::TooManyTiles:
      return "more tiles than the detection stage was sized for";
    case DetectionStatus::WrongTileSize:
      return "tile size differs from the detector input";
    case DetectionStatus::EmptyFrame:
      return "no corrected frame to cut crops from";
    case DetectionStatus::DetectorFailed:
      return "detector run failed";
    case DetectionStatus::DecodeFailed:
      return "detector outputs could not be decoded";
  }
  return "unknown";
}

bool DetectionStage::init(const DetectionStageOptions& options, int maxTiles, std::string* why) {
  initialised_ = false;
  std::string detail;
  if (!validate(options.decoder, &detail) || !validate(options.gsd, &detail)) {
    return fail(why, detail);
  }
  if (options.maxCrops < 0 || options.maxCrops > kMaxDetectionsPerFrame) {
    return fail(why, "max_crops: must be in [0, " + std::to_string(kMaxDetectionsPerFrame) +
                         "], got " + std::to_string(options.maxCrops));
  }
  if (options.cropEngineThreads < 1 || options.cropEngineThreads > 16) {
    return fail(why, "crop_engine_threads: must be in [1, 16], got " +
                         std::to_string(options.cropEngineThreads));
  }
  if (maxTiles < 1 || maxTiles > preprocess::kMaxTiles) {
    return fail(why, "max tiles must be in [1, " + std::to_string(preprocess::kMaxTiles) + "]");
  }
  const std::string& path = options.detectorModelPath;
  if (!detector_.load(path, options.engine, &detail)) {
    return fail(why, "detector model: " + detail);
  }
  const inference::TensorShape input = detector_.inputShape();
  inputWidth_ = input.w;
  inputHeight_ = input.h;
  for (std::size_t k = 0; k < kHeads.size(); ++k) {
    bool found = false;
    for (std::size_t i = 0; i < detector_.outputCount(); ++i) {
      const inference::OutputTensor& out = detector_.output(i);
      if (out.name != kHeads[k].name) {
        continue;
      }
      if (out.shape.c != kHeads[k].channels) {
        return fail(why, path + ": output '" + out.name + "' has " + std::to_string(out.shape.c) +
                             " channels, expected " + std::to_string(kHeads[k].channels));
      }
      if (k == 0) {
        gridWidth_ = out.shape.w;
        gridHeight_ = out.shape.h;
      } else if (out.shape.w != gridWidth_ || out.shape.h != gridHeight_) {
        return fail(why, path + ": output '" + out.name + "' is on a " +
                             std::to_string(out.shape.w) + "x" + std::to_string(out.shape.h) +
                             " grid, the heatmap on " + std::to_string(gridWidth_) + "x" +
                             std::to_string(gridHeight_));
      }
      headIndex_[k] = i;
      found = true;
    }
    if (!found) {
      return fail(why, path + ": no output named '" + kHeads[k].name +
                           "' (the detector needs heatmap, offset, size, direction)");
    }
  }
  if (gridWidth_ <= 0 || gridHeight_ <= 0 || inputWidth_ % gridWidth_ != 0 ||
      inputHeight_ % gridHeight_ != 0 || inputWidth_ / gridWidth_ != inputHeight_ / gridHeight_) {
    return fail(why, path + ": output grid " + std::to_string(gridWidth_) + "x" +
                         std::to_string(gridHeight_) + " is not the input " +
                         std::to_string(inputWidth_) + "x" + std::to_string(inputHeight_) +
                         " divided by one integer stride");
  }
  stridePx_ = inputWidth_ / gridWidth_;
  if (!decoder_.init(options.decoder, gridWidth_, gridHeight_, stridePx_, maxTiles, &detail)) {
    return fail(why, detail);
  }
  inference::EngineOptions cropEngine = options.engine;
  cropEngine.threads = options.cropEngineThreads;
  cropEngine.backend = options.cropBackend.value_or(options.engine.backend);
  if (!options.cropModelPath.empty() &&
      !cropper_.init(options.cropModelPath, cropEngine, options.secondStage, &detail)) {
    return fail(why, detail);
  }
  options_ = options;
  maxTiles_ = maxTiles;
  stats_ = DetectionStats{};
  initialised_ = true;
  return true;
}

DetectionStatus DetectionStage::run(const preprocess::PreprocessedFrame& frame,
                                    std::span<Detection> out, std::size_t* count,
                                    const GsdProvider* gsdProvider) {
  *count = 0;
  stats_ = DetectionStats{};
  FirstStageOutput first;
  const DetectionStatus status = detect(frame, out, &first);
  if (status != DetectionStatus::Ok) {
    return status;
  }
  return refine(frame.frame, frame.geometry, first, out, count, gsdProvider);
}

DetectionStatus DetectionStage::detect(const preprocess::PreprocessedFrame& frame,
                                       std::span<Detection> out, FirstStageOutput* first) {
  *first = FirstStageOutput{};
  first->frameGain = frame.frameGain;
  if (!initialised_) {
    return DetectionStatus::NotInitialised;
  }
  if (frame.tiles.empty()) {
    return DetectionStatus::NoTiles;
  }
  if (frame.tiles.size() > static_cast<std::size_t>(maxTiles_)) {
    return DetectionStatus::TooManyTiles;
  }
  const bool secondStage = cropper_.initialised() && options_.maxCrops > 0;
  if (secondStage && (frame.frame.empty() || frame.frame.type() != CV_8UC3)) {
    return DetectionStatus::EmptyFrame;
  }

  // First stage: detector per tile, decoded into frame pixels.
  double detector_ms = 0.0;
  double decode_ms = 0.0;
  decoder_.beginFrame();
  for (const preprocess::TileView& tile : frame.tiles) {
    if (tile.rect.width_px != inputWidth_ || tile.rect.height_px != inputHeight_ ||
        tile.data == nullptr) {
      return DetectionStatus::WrongTileSize;
    }
    const Clock::time_point start = Clock::now();
    const inference::ImageView view{tile.data, inputWidth_, inputHeight_, tile.strideBytes};
    if (detector_.run(view) != inference::RunStatus::Ok) {
      return DetectionStatus::DetectorFailed;
    }
    const Clock::time_point ran = Clock::now();
    HeadTensors heads;
    heads.heatmap = detector_.output(headIndex_[0]).data;
    heads.offset = detector_.output(headIndex_[1]).data;
    heads.size = detector_.output(headIndex_[2]).data;
    heads.direction = detector_.output(headIndex_[3]).data;
    heads.gridWidth = gridWidth_;
    heads.gridHeight = gridHeight_;
    heads.stride_px = stridePx_;
    if (decoder_.decodeTile(heads, tile, frame.geometry) != DecodeStatus::Ok) {
      return DetectionStatus::DecodeFailed;
    }
    detector_ms += millisecondsBetween(start, ran);
    decode_ms += millisecondsBetween(ran, Clock::now());
  }
  const Clock::time_point nmsStart = Clock::now();
  first->kept = decoder_.finishFrame(out);
  decode_ms += millisecondsBetween(nmsStart, Clock::now());
  first->secondStage = secondStage;
  DetectionStats& stats = first->stats;
  stats.detector_ms = detector_ms;
  stats.decode_ms = decode_ms;
  stats.tiles = static_cast<int>(frame.tiles.size());
  stats.candidates = static_cast<int>(decoder_.candidateCount());
  stats.cutCandidates = static_cast<int>(decoder_.cutCandidateCount());
  stats.droppedForCapacity = static_cast<int>(decoder_.droppedForCapacity());
  return DetectionStatus::Ok;
}

DetectionStatus DetectionStage::refine(const cv::Mat& correctedFrame,
                                       const preprocess::FrameGeometry& geometry,
                                       const FirstStageOutput& first, std::span<Detection> out,
                                       std::size_t* count, const GsdProvider* gsdProvider) {
  *count = 0;
  stats_ = first.stats;
  if (!initialised_) {
    return DetectionStatus::NotInitialised;
  }
  const Clock::time_point secondStart = Clock::now();
  const bool secondStage = first.secondStage;
  const std::size_t kept = std::min(first.kept, out.size());
  // Second stage, best detections first.
  if (secondStage && kept > 0) {
    cropper_.setFrameGain(first.frameGain);
    double frameGsd = options_.gsd.fixedGsd_m;
    if (!(frameGsd > 0.0)) {
      frameGsd = medianLengthGsd(out.first(kept), options_.gsd, gsdScratch_);
    }
    stats_.frameGsd_m = frameGsd;
    const std::size_t crops = std::min(kept, static_cast<std::size_t>(options_.maxCrops));
    // With frameEdgeKeepBox: which first-stage boxes reach the border (the vehicle is cut), for
    // the crops and the verifier; markFrameEdge() below sets the flag and insideShare of the
    // final boxes.
    const bool edgeKeepBox = options_.secondStage.frameEdgeKeepBox;
    if (edgeKeepBox) {
      const FrameEdgeBounds bounds = frameEdgeBounds(geometry);
      for (Detection& d : out.first(kept)) {
        d.atFrameEdge = reachesFrameEdge(bounds, d.box);
      }
    }
    for (std::size_t i = 0; i < crops; ++i) {
      double gsd = gsdProvider != nullptr ? gsdProvider->groundSampleDistance_m(out[i]) : 0.0;
      if (!(gsd > 0.0) || !std::isfinite(gsd)) {
        gsd = frameGsd;
      }
      if (cropper_.classify(correctedFrame, gsd, &out[i], edgeKeepBox && out[i].atFrameEdge) ==
          SecondStageStatus::Ok) {
        ++stats_.crops;
      } else {
        ++stats_.cropFailures;
      }
    }
    stats_.cropFailures += static_cast<int>(kept - crops);
  }
  // The verifier: boxes the crop network says show no vehicle go (order kept; a detection
  // without a verifier probability stays).
  std::size_t verified = kept;
  const float minVehicle = options_.secondStage.minVehicleProbability;
  // A vehicle at the border has its own threshold (higher or lower than inside: the real sets
  // label cut vehicles differently); minVehicleProbability 0 still turns the verifier off.
  const float minVehicleAtEdge = options_.secondStage.frameEdgeKeepBox
                                     ? options_.secondStage.frameEdgeMinVehicleProbability
                                     : minVehicle;
  if (secondStage && minVehicle > 0.0F && cropper_.hasVerifier()) {
    verified = 0;
    for (std::size_t i = 0; i < kept; ++i) {
      const float threshold = out[i].atFrameEdge ? minVehicleAtEdge : minVehicle;
      if (!(out[i].vehicleProbability < threshold)) {
        out[verified++] = out[i];
      }
    }
  }
  stats_.rejectedByVerifier = static_cast<int>(kept - verified);
  // The second stage moves and resizes boxes (refinement): two first-stage peaks of one
  // vehicle (e.g. its copies from two overlapping tiles, one of them offset) can land on the
  // same car. A last suppression on the refined boxes keeps the better one. Cars do not
  // overlap each other on the ground, so the "contained in" test is safe within a tile too.
  const std::size_t suppressed =
      secondStage ? suppressRefinedDuplicates(out.first(verified), stats_.frameGsd_m) : verified;
  stats_.refinedDuplicates = static_cast<int>(verified - suppressed);
  // Parts of one bus or truck become one box; it keeps the better part's front/back (a look at
  // the merged box's ends was tried: the union can reach past the vehicle's end, and the end
  // crop then sees road).
  std::size_t refinedKept = suppressed;
  if (secondStage) {
    refinedKept =
        mergeLargeVehicleParts(out.first(suppressed), stats_.frameGsd_m, options_.largeMerge);
    stats_.largeVehicleParts = static_cast<int>(suppressed - refinedKept);
  }
  markFrameEdge(geometry, out.first(refinedKept));
  stats_.crops_ms = millisecondsBetween(secondStart, Clock::now());
  stats_.detections = static_cast<int>(refinedKept);
  *count = refinedKept;
  return DetectionStatus::Ok;
}

DetectionStage::FrameEdgeBounds DetectionStage::frameEdgeBounds(
    const preprocess::FrameGeometry& geometry) const {
  // The decoder's cut margin (working px) in frame px; frame pixel edges at -0.5, size - 0.5.
  const double margin =
      options_.decoder.cutEdgeMargin_px / std::min(geometry.scaleX, geometry.scaleY);
  return {-0.5 + margin, geometry.frameWidth_px - 0.5 - margin,
          geometry.frameHeight_px - 0.5 - margin};
}

bool DetectionStage::reachesFrameEdge(const FrameEdgeBounds& bounds,
                                      const geometry::RotatedBox& box) {
  double halfU = 0.0;
  double halfV = 0.0;
  geometry::axisAlignedHalfExtents(box, &halfU, &halfV);
  return box.cx - halfU < bounds.low || box.cy - halfV < bounds.low ||
         box.cx + halfU > bounds.right || box.cy + halfV > bounds.bottom;
}

void DetectionStage::markFrameEdge(const preprocess::FrameGeometry& geometry,
                                   std::span<Detection> detections) const {
  const FrameEdgeBounds bounds = frameEdgeBounds(geometry);
  const geometry::RotatedBox frame{0.5 * geometry.frameWidth_px - 0.5,
                                   0.5 * geometry.frameHeight_px - 0.5,
                                   static_cast<double>(geometry.frameWidth_px),
                                   static_cast<double>(geometry.frameHeight_px), 0.0};
  for (Detection& d : detections) {
    d.atFrameEdge = reachesFrameEdge(bounds, d.box);
    const double boxArea = geometry::area(d.box);
    d.insideShare = !d.atFrameEdge || !(boxArea > 0.0)
                        ? 1.0F
                        : static_cast<float>(std::clamp(
                              geometry::intersectionArea(d.box, frame) / boxArea, 0.0, 1.0));
  }
}

std::size_t DetectionStage::suppressRefinedDuplicates(std::span<Detection> detections,
                                                      double gsd_m) const {
  // Order as the decoder left it (whole before cut, then score): the earlier one wins; a bus
  // part that wins over the longer box of its bus takes that box's extent
  // (absorbLongerDuplicate).
  std::size_t kept = 0;
  for (std::size_t i = 0; i < detections.size(); ++i) {
    const geometry::RotatedBox& a = detections[i].box;
    const double areaA = a.length * a.width;
    const double radiusA = 0.5 * std::hypot(a.length, a.width);
    bool duplicate = false;
    for (std::size_t k = 0; k < kept && !duplicate; ++k) {
      const geometry::RotatedBox& b = detections[k].box;
      if (std::hypot(a.cx - b.cx, a.cy - b.cy) >= radiusA + 0.5 * std::hypot(b.length, b.width)) {
        continue;
      }
      const double areaB = b.length * b.width;
      const double intersection = geometry::intersectionArea(a, b);
      const double unionArea = areaA + areaB - intersection;
      duplicate = (unionArea > 0.0 && intersection / unionArea > options_.decoder.nmsIou) ||
                  intersection / std::min(areaA, areaB) > options_.decoder.duplicateOverlap;
      if (duplicate) {
        absorbLongerDuplicate(detections[k], detections[i], gsd_m, options_.largeMerge);
      }
    }
    if (!duplicate) {
      detections[kept++] = detections[i];
    }
  }
  return kept;
}

}  // namespace vp::detection
