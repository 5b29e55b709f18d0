// detection/decoder: the detector's dense outputs of one or more tiles -> candidate vehicles
// in frame pixels, then one rotated non-maximum suppression over the whole frame.
//
// Contract (the Python reference is tools/detector/evaluate.py, decode() and Predictor):
//  - decodeTile(): a cell is a peak when its heatmap probability is >= every one of its 8
//    neighbours (cells outside the grid do not count) and >= scoreThreshold; the topK best
//    peaks of the tile are kept (ties: lower cell index first). At peak (ix, iy), stride s:
//      centre  = ((ix + offset_u) * s + (s - 1) / 2, (iy + offset_v) * s + (s - 1) / 2)  tile px
//      length, width = exp(size_0), exp(size_1)                                     working px
//      angle   = atan2(direction_1, direction_0) wrapped to [0, 2 pi)
//    then tile px + the tile's offset = working px, and working -> frame pixels with the
//    pixel-centre map u_frame = (u + 0.5) / scaleX - 0.5 (sizes / sqrt(scaleX scaleY)), as
//    Predictor maps them back. Candidates whose centre falls outside the frame (in the
//    padding) are dropped (dropCentresOutsideFrame; the Python code keeps them).
//  - A candidate whose box reaches within cutEdgeMargin_px of an inner tile edge (one shared
//    with an overlapping neighbour) is marked cut: the vehicle is probably only partly in
//    this tile.
//  - finishFrame(): greedy suppression in the order (whole before cut, then score, tile,
//    cell). A candidate is dropped when it overlaps an already kept one by rotated IoU >
//    nmsIou, or - from a different tile - by intersection / smaller area > duplicateOverlap
//    (the same vehicle seen by two tiles, possibly cut in one). So a vehicle seen by two
//    tiles is kept once, and a cut copy loses to the whole one. The kept detections are
//    written best score first; directionKnown is true (the detector always predicts a
//    direction), typeProbabilities uniform, gamma empty (the second stage fills them).
// Fixed memory after init(); no allocation, no exceptions. Not thread-safe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "detection/detection.hpp"
#include "preprocess/preprocessor.hpp"

namespace vp::detection {

// Defaults are the shipped configuration's (perception.*, config/default.yaml).
struct DecoderOptions {
  // Heatmap probability, [0, 1]. 0.4: chosen on the tuning seeds for detector v1, re-checked
  // for v4 and v5 (docs/model_card.md); tools/detector/evaluate.py decodes at 0.3.
  float scoreThreshold = 0.4F;
  int topKPerTile = 200;                // peaks kept per tile, >= 1 (evaluate.decode: 200)
  double nmsIou = 0.5;                  // rotated IoU above which the weaker box goes, (0, 1]
  double duplicateOverlap = 0.5;        // cross-tile intersection / smaller area, (0, 1]
  double cutEdgeMargin_px = 4.0;        // working px (one stride-4 cell), >= 0
  bool dropCentresOutsideFrame = true;  // centres in the padding are not vehicles
};

bool validate(const DecoderOptions& options, std::string* why);

// One tile's detector outputs: float NHWC tensors (channels contiguous per cell) on a
// gridWidth x gridHeight grid at stride_px: heatmap 1 channel (probability), offset 2,
// size 2 (log px), direction 2 (cos, sin; any length).
struct HeadTensors {
  const float* heatmap = nullptr;
  const float* offset = nullptr;
  const float* size = nullptr;
  const float* direction = nullptr;
  int gridWidth = 0;
  int gridHeight = 0;
  int stride_px = 4;
};

enum class DecodeStatus {
  Ok,
  NotInitialised,
  MissingTensor,  // a null tensor pointer
  GridMismatch,   // grid size or stride other than the one given to init()
  TooManyTiles,   // more tiles in one frame than init() allowed
};
const char* toString(DecodeStatus status);

class DetectionDecoder {
 public:
  DetectionDecoder() = default;

  // Start-up: candidate storage for maxTiles x topKPerTile and the peak scratch of one grid.
  bool init(const DecoderOptions& options, int gridWidth, int gridHeight, int stride_px,
            int maxTiles, std::string* why = nullptr);
  bool initialised() const { return gridWidth_ > 0; }
  const DecoderOptions& options() const { return options_; }

  void beginFrame();  // forgets the previous frame's candidates
  DecodeStatus decodeTile(const HeadTensors& heads, const preprocess::TileView& tile,
                          const preprocess::FrameGeometry& geometry);
  // Suppression over all tiles of the frame; writes at most out.size() detections, best
  // first, and returns how many. Candidates that would have been kept beyond out.size() are
  // counted in droppedForCapacity().
  std::size_t finishFrame(std::span<Detection> out);

  std::size_t candidateCount() const { return candidateCount_; }
  std::size_t cutCandidateCount() const;
  std::size_t droppedForCapacity() const { return droppedForCapacity_; }

 private:
  struct Candidate {
    Detection detection{};
    double radius_px = 0.0;  // half diagonal: quick rejection before the exact overlap
    double areaPx2 = 0.0;
    int cell = 0;
    bool cut = false;
  };
  struct Peak {
    float score = 0.0F;
    int cell = 0;
  };

  bool overlapsKept(const Candidate& candidate, std::size_t keptCount) const;

  DecoderOptions options_{};
  int gridWidth_ = 0;
  int gridHeight_ = 0;
  int stridePx_ = 0;
  int maxTiles_ = 0;
  int tilesThisFrame_ = 0;
  std::vector<Peak> peaks_;            // one grid's worth
  std::vector<Candidate> candidates_;  // maxTiles x topK
  std::vector<std::uint32_t> order_;   // suppression order scratch
  std::vector<std::uint32_t> kept_;    // indices of kept candidates
  std::size_t candidateCount_ = 0;
  std::size_t droppedForCapacity_ = 0;
};

}  // namespace vp::detection
