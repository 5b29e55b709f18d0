// detection/detection_stage: one frame's image-side detection - detector network on every
// tile, decoding, rotated NMS across tiles, and the second stage on every kept vehicle.
//
// Contract: init() loads the detector (input = the preprocessor's tile size; outputs named
// heatmap 1, offset 2, size 2, direction 2 channels on one grid at a stride that divides the
// input) and, when a crop model path is given, the crop network (vehicle_cropper.hpp), and
// sizes every buffer for maxTiles tiles. run() takes a preprocessed frame, runs the detector
// per tile, decodes and suppresses (decoder.hpp), then for each kept detection - best first,
// at most maxCrops - cuts the crop from the corrected full-resolution frame at a GSD from the
// caller's GsdProvider, else the options' fixed GSD, else the frame's median box length
// (ground_sample_distance.hpp), and applies the crop network's outputs (a detection whose
// first-stage box reaches the frame's border keeps that box with secondStage.frameEdgeKeepBox,
// and meets the verifier's border threshold); after the last
// suppression, parts of one bus or truck are merged (large_vehicle_merge.hpp). It writes at most
// out.size() detections (kMaxDetectionsPerFrame is the intended capacity) and returns a
// status, never throws and performs no heap allocation after init(). A detection whose
// second stage could not run (no GSD, beyond maxCrops) keeps its first-stage values (uniform
// types, no gamma) and is counted in stats(). run() is the two halves below one after the other:
// detect() (detector, decoding, suppression: the detector engine and the decoder) and refine()
// (the second stage on the kept detections: the crop engine); the pipelined loop runs detect()
// of one frame on one thread while refine() of the frame before runs on another - the halves
// share no mutable state, and refine() alone writes stats(). Otherwise not thread-safe; the
// detector engine uses engine.threads workers, the crop engine cropEngineThreads.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <span>
#include <string>

#include "detection/decoder.hpp"
#include "detection/detection.hpp"
#include "detection/ground_sample_distance.hpp"
#include "detection/large_vehicle_merge.hpp"
#include "detection/vehicle_cropper.hpp"
#include "inference/engine.hpp"
#include "preprocess/preprocessor.hpp"

namespace vp::detection {

struct DetectionStageOptions {
  std::string detectorModelPath;      // models/detector/detector_int8.onnx
  std::string cropModelPath;          // models/detector/crop_int8.onnx; empty: no second stage
  inference::EngineOptions engine{};  // backend and threads of the detector network
  // The crop network is tiny (~6 MMAC): a thread pool costs more than it saves per crop
  // (measured: 2 threads made 30 crops 300x slower on a loaded 2-core machine).
  int cropEngineThreads = 1;  // [1, 16]
  // Backend of the crop network when it should differ from engine.backend (diagnostics: which
  // stage carries the int8 error); empty = engine.backend.
  std::optional<inference::Backend> cropBackend{};
  DecoderOptions decoder{};
  SecondStageOptions secondStage{};
  LargeVehicleMergeOptions largeMerge{};  // after the second stage (large_vehicle_merge.hpp)
  GsdOptions gsd{};
  int maxCrops = kMaxDetectionsPerFrame;  // second-stage runs per frame, [0, 512]
};

enum class DetectionStatus {
  Ok,
  NotInitialised,
  NoTiles,         // the preprocessed frame has no tiles (preprocessing failed?)
  TooManyTiles,    // more than init()'s maxTiles
  WrongTileSize,   // tile size differs from the detector input
  EmptyFrame,      // no corrected frame to crop from
  DetectorFailed,  // Engine::run failed
  DecodeFailed,    // decoder refused the outputs
};
const char* toString(DetectionStatus status);

struct DetectionStats {
  int tiles = 0;
  int candidates = 0;          // decoded peaks over all tiles, before NMS
  int cutCandidates = 0;       // of which touched an inner tile edge
  int detections = 0;          // written to the output
  int droppedForCapacity = 0;  // kept by NMS but beyond the output's size
  int crops = 0;               // second-stage runs that succeeded
  int refinedDuplicates = 0;   // detections that became duplicates after refinement, removed
  int rejectedByVerifier = 0;  // below SecondStageOptions::minVehicleProbability, removed
  int largeVehicleParts = 0;   // parts of a bus or truck merged into another detection
  int cropFailures = 0;        // second stage skipped or failed (no GSD, engine error, ...)
  double frameGsd_m = 0.0;     // the frame-level GSD estimate used (0: provider or none)
  double detector_ms = 0.0;    // detector engine, all tiles
  double decode_ms = 0.0;      // decoding + NMS
  double crops_ms = 0.0;       // crops + crop engine + output application
};

// What detect() leaves for refine() besides the detections (in the caller's array).
struct FirstStageOutput {
  std::size_t kept = 0;      // detections written by detect(), best first
  bool secondStage = false;  // the crop network runs on this frame
  // The gain the corrected frame's pixels still need to look like the working image (the
  // preprocessor's exposure gain when only the working image got it): refine() applies it to
  // the crops.
  float frameGain = 1.0F;
  DetectionStats stats{};  // the first stage's fields (tiles ... decode_ms)
};

class DetectionStage {
 public:
  DetectionStage() = default;
  DetectionStage(const DetectionStage&) = delete;
  DetectionStage& operator=(const DetectionStage&) = delete;

  // Start-up: loads and checks the models; *why names the file and the problem.
  bool init(const DetectionStageOptions& options, int maxTiles, std::string* why = nullptr);
  bool initialised() const { return initialised_; }

  // Real-time path. *count receives the number of detections written to out.
  DetectionStatus run(const preprocess::PreprocessedFrame& frame, std::span<Detection> out,
                      std::size_t* count, const GsdProvider* gsdProvider = nullptr);
  // The first half of run(): the detector on every tile, decoding and suppression into out.
  // Touches only the detector engine and the decoder.
  DetectionStatus detect(const preprocess::PreprocessedFrame& frame, std::span<Detection> out,
                         FirstStageOutput* first);
  // The second half: the crop network on the first `first.kept` detections of out (in place),
  // cut from correctedFrame (the frame detect() saw), the verifier, the last suppression and the
  // frame-edge marks; *count receives the detections kept. Sets stats().
  DetectionStatus refine(const cv::Mat& correctedFrame, const preprocess::FrameGeometry& geometry,
                         const FirstStageOutput& first, std::span<Detection> out,
                         std::size_t* count, const GsdProvider* gsdProvider = nullptr);

  const DetectionStats& stats() const { return stats_; }
  // The crop network has the verifier output (minVehicleProbability can act).
  bool hasVerifier() const { return cropper_.hasVerifier(); }
  int detectorInputWidth() const { return inputWidth_; }
  int detectorInputHeight() const { return inputHeight_; }
  int stride_px() const { return stridePx_; }
  // The backend the detector network runs on (Auto resolved at load).
  inference::Backend detectorBackend() const { return detector_.backend(); }

 private:
  // Removes detections that overlap a better one after the second stage; returns the count kept.
  std::size_t suppressRefinedDuplicates(std::span<Detection> detections, double gsd_m) const;
  // The lines a box must stay within (frame px) not to count as reaching the frame's border:
  // the decoder's cut margin inside the frame's edges.
  struct FrameEdgeBounds {
    double low = 0.0;  // left and top
    double right = 0.0;
    double bottom = 0.0;
  };
  FrameEdgeBounds frameEdgeBounds(const preprocess::FrameGeometry& geometry) const;
  static bool reachesFrameEdge(const FrameEdgeBounds& bounds, const geometry::RotatedBox& box);
  // Sets Detection::atFrameEdge: the box's bounds come within the decoder's cut margin of the
  // frame's border; and Detection::insideShare, the share of its area inside the frame.
  void markFrameEdge(const preprocess::FrameGeometry& geometry,
                     std::span<Detection> detections) const;

  bool initialised_ = false;
  DetectionStageOptions options_{};
  inference::Engine detector_;
  VehicleCropper cropper_;
  DetectionDecoder decoder_;
  std::array<std::size_t, 4> headIndex_{};  // heatmap, offset, size, direction
  int inputWidth_ = 0;
  int inputHeight_ = 0;
  int gridWidth_ = 0;
  int gridHeight_ = 0;
  int stridePx_ = 0;
  int maxTiles_ = 0;
  std::array<double, kMaxDetectionsPerFrame> gsdScratch_{};
  DetectionStats stats_{};
};

}  // namespace vp::detection
