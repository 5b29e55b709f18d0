#include "detection/decoder.hpp"

#include <algorithm>
#include <cmath>

#include "geometry/rotated_box.hpp"

namespace vp::detection {

namespace {

bool fail(std::string* why, const std::string& message) {
  if (why != nullptr) {
    *why = "detection decoder: " + message;
  }
  return false;
}

bool inUnitInterval(double value, bool allowZero) {
  return std::isfinite(value) && (allowZero ? value >= 0.0 : value > 0.0) && value <= 1.0;
}

// Axis-aligned extent of a rotated box: half sizes along u and v.

}  // namespace

const char* toString(DecodeStatus status) {
  switch (status) {
    case DecodeStatus::Ok:
      return "ok";
    case DecodeStatus::NotInitialised:
      return "decoder not initialised";
    case DecodeStatus::MissingTensor:
      return "a detector output tensor is missing";
    case DecodeStatus::GridMismatch:
      return "detector output grid differs from the decoder's";
    case DecodeStatus::TooManyTiles:
      return "more tiles than the decoder was sized for";
  }
  return "unknown";
}

bool validate(const DecoderOptions& options, std::string* why) {
  if (!inUnitInterval(options.scoreThreshold, true)) {
    return fail(
        why, "score_threshold: must be in [0, 1], got " + std::to_string(options.scoreThreshold));
  }
  if (options.topKPerTile < 1 || options.topKPerTile > kMaxDetectionsPerFrame) {
    return fail(why, "top_k_per_tile: must be in [1, " + std::to_string(kMaxDetectionsPerFrame) +
                         "], got " + std::to_string(options.topKPerTile));
  }
  if (!inUnitInterval(options.nmsIou, false)) {
    return fail(why, "nms_iou: must be in (0, 1], got " + std::to_string(options.nmsIou));
  }
  if (!inUnitInterval(options.duplicateOverlap, false)) {
    return fail(why, "duplicate_overlap: must be in (0, 1], got " +
                         std::to_string(options.duplicateOverlap));
  }
  if (!(options.cutEdgeMargin_px >= 0.0) || !std::isfinite(options.cutEdgeMargin_px)) {
    return fail(why, "cut_edge_margin_px: must be finite and >= 0");
  }
  return true;
}

bool DetectionDecoder::init(const DecoderOptions& options, int gridWidth, int gridHeight,
                            int stride_px, int maxTiles, std::string* why) {
  if (!validate(options, why)) {
    return false;
  }
  if (gridWidth <= 0 || gridHeight <= 0 || stride_px <= 0 || maxTiles <= 0) {
    return fail(why, "grid " + std::to_string(gridWidth) + "x" + std::to_string(gridHeight) +
                         ", stride " + std::to_string(stride_px) + " and max tiles " +
                         std::to_string(maxTiles) + " must all be > 0");
  }
  options_ = options;
  gridWidth_ = gridWidth;
  gridHeight_ = gridHeight;
  stridePx_ = stride_px;
  maxTiles_ = maxTiles;
  peaks_.assign(static_cast<std::size_t>(gridWidth) * static_cast<std::size_t>(gridHeight), Peak{});
  const std::size_t capacity =
      static_cast<std::size_t>(maxTiles) * static_cast<std::size_t>(options.topKPerTile);
  candidates_.assign(capacity, Candidate{});
  order_.assign(capacity, 0);
  kept_.assign(capacity, 0);
  beginFrame();
  return true;
}

void DetectionDecoder::beginFrame() {
  candidateCount_ = 0;
  droppedForCapacity_ = 0;
  tilesThisFrame_ = 0;
}

std::size_t DetectionDecoder::cutCandidateCount() const {
  std::size_t count = 0;
  for (std::size_t i = 0; i < candidateCount_; ++i) {
    count += candidates_[i].cut ? 1U : 0U;
  }
  return count;
}

DecodeStatus DetectionDecoder::decodeTile(const HeadTensors& heads,
                                          const preprocess::TileView& tile,
                                          const preprocess::FrameGeometry& geometry) {
  if (!initialised()) {
    return DecodeStatus::NotInitialised;
  }
  if (heads.heatmap == nullptr || heads.offset == nullptr || heads.size == nullptr ||
      heads.direction == nullptr) {
    return DecodeStatus::MissingTensor;
  }
  if (heads.gridWidth != gridWidth_ || heads.gridHeight != gridHeight_ ||
      heads.stride_px != stridePx_) {
    return DecodeStatus::GridMismatch;
  }
  if (tilesThisFrame_ >= maxTiles_) {
    return DecodeStatus::TooManyTiles;
  }
  ++tilesThisFrame_;

  // 3 x 3 peaks above the threshold (evaluate.decode: hm >= max of the neighbourhood).
  const int w = gridWidth_;
  const int h = gridHeight_;
  const float* hm = heads.heatmap;
  std::size_t peakCount = 0;
  for (int iy = 0; iy < h; ++iy) {
    for (int ix = 0; ix < w; ++ix) {
      const float value = hm[iy * w + ix];
      if (!(value >= options_.scoreThreshold)) {
        continue;
      }
      bool peak = true;
      for (int dy = -1; dy <= 1 && peak; ++dy) {
        const int y = iy + dy;
        if (y < 0 || y >= h) {
          continue;
        }
        for (int dx = -1; dx <= 1; ++dx) {
          const int x = ix + dx;
          if (x >= 0 && x < w && hm[y * w + x] > value) {
            peak = false;
            break;
          }
        }
      }
      if (peak) {
        peaks_[peakCount++] = Peak{value, iy * w + ix};
      }
    }
  }
  const auto better = [](const Peak& a, const Peak& b) {
    return a.score > b.score || (a.score == b.score && a.cell < b.cell);
  };
  const std::size_t topK = std::min(peakCount, static_cast<std::size_t>(options_.topKPerTile));
  std::partial_sort(peaks_.begin(), peaks_.begin() + static_cast<std::ptrdiff_t>(topK),
                    peaks_.begin() + static_cast<std::ptrdiff_t>(peakCount), better);

  const double stride = stridePx_;
  const double cellCentre = (stride - 1.0) / 2.0;
  const double sizeScale = 1.0 / std::sqrt(geometry.scaleX * geometry.scaleY);
  const double margin = options_.cutEdgeMargin_px;
  const preprocess::TileRect& rect = tile.rect;
  for (std::size_t p = 0; p < topK; ++p) {
    const int cell = peaks_[p].cell;
    const int ix = cell % w;
    const int iy = cell / w;
    const float* offset = heads.offset + 2 * static_cast<std::size_t>(cell);
    const float* size = heads.size + 2 * static_cast<std::size_t>(cell);
    const float* direction = heads.direction + 2 * static_cast<std::size_t>(cell);
    geometry::RotatedBox box;
    box.cx = (ix + static_cast<double>(offset[0])) * stride + cellCentre;  // tile px
    box.cy = (iy + static_cast<double>(offset[1])) * stride + cellCentre;
    box.length = std::exp(static_cast<double>(size[0]));  // working px
    box.width = std::exp(static_cast<double>(size[1]));
    box.angle = geometry::wrapTwoPi(
        std::atan2(static_cast<double>(direction[1]), static_cast<double>(direction[0])));
    if (!std::isfinite(box.cx) || !std::isfinite(box.cy) || !std::isfinite(box.angle) ||
        !(box.length > 0.0) || !(box.width > 0.0) || !std::isfinite(box.length) ||
        !std::isfinite(box.width)) {
      continue;  // a broken output cannot make a box
    }
    // Cut by an inner tile edge? (tile px; the tile's outer pixel edges are at -0.5, size-0.5)
    double halfU = 0.0;
    double halfV = 0.0;
    geometry::axisAlignedHalfExtents(box, &halfU, &halfV);
    const bool cut = (rect.innerLeft && box.cx - halfU < -0.5 + margin) ||
                     (rect.innerTop && box.cy - halfV < -0.5 + margin) ||
                     (rect.innerRight && box.cx + halfU > rect.width_px - 0.5 - margin) ||
                     (rect.innerBottom && box.cy + halfV > rect.height_px - 0.5 - margin);

    Candidate& candidate = candidates_[candidateCount_];
    Detection& d = candidate.detection;
    d = Detection{};
    d.box.cx = geometry.workingToFrameU(rect.x0_px + box.cx);
    d.box.cy = geometry.workingToFrameV(rect.y0_px + box.cy);
    d.box.length = box.length * sizeScale;
    d.box.width = box.width * sizeScale;
    d.box.angle = box.angle;
    if (options_.dropCentresOutsideFrame &&
        (d.box.cx < -0.5 || d.box.cx >= geometry.frameWidth_px - 0.5 || d.box.cy < -0.5 ||
         d.box.cy >= geometry.frameHeight_px - 0.5)) {
      continue;
    }
    d.score = peaks_[p].score;
    d.directionKnown = true;
    d.typeProbabilities.fill(1.0F / static_cast<float>(shape::kVehicleTypeCount));
    d.tile = static_cast<std::int16_t>(tile.index);
    candidate.radius_px = 0.5 * std::hypot(d.box.length, d.box.width);
    candidate.areaPx2 = d.box.length * d.box.width;
    candidate.cell = cell;
    candidate.cut = cut;
    ++candidateCount_;
  }
  return DecodeStatus::Ok;
}

bool DetectionDecoder::overlapsKept(const Candidate& candidate, std::size_t keptCount) const {
  const geometry::RotatedBox& a = candidate.detection.box;
  for (std::size_t k = 0; k < keptCount; ++k) {
    const Candidate& other = candidates_[kept_[k]];
    const geometry::RotatedBox& b = other.detection.box;
    if (std::hypot(a.cx - b.cx, a.cy - b.cy) >= candidate.radius_px + other.radius_px) {
      continue;  // the circumscribed circles are apart: no overlap possible
    }
    const double intersection = geometry::intersectionArea(a, b);
    const double unionArea = candidate.areaPx2 + other.areaPx2 - intersection;
    if (unionArea > 0.0 && intersection / unionArea > options_.nmsIou) {
      return true;
    }
    if (candidate.detection.tile != other.detection.tile &&
        intersection / std::min(candidate.areaPx2, other.areaPx2) > options_.duplicateOverlap) {
      return true;
    }
  }
  return false;
}

std::size_t DetectionDecoder::finishFrame(std::span<Detection> out) {
  const auto n = static_cast<std::uint32_t>(candidateCount_);
  for (std::uint32_t i = 0; i < n; ++i) {
    order_[i] = i;
  }
  // Whole before cut, then score, then tile and cell (deterministic).
  std::sort(order_.begin(), order_.begin() + n, [this](std::uint32_t i, std::uint32_t j) {
    const Candidate& a = candidates_[i];
    const Candidate& b = candidates_[j];
    if (a.cut != b.cut) {
      return !a.cut;
    }
    if (a.detection.score != b.detection.score) {
      return a.detection.score > b.detection.score;
    }
    if (a.detection.tile != b.detection.tile) {
      return a.detection.tile < b.detection.tile;
    }
    return a.cell < b.cell;
  });
  std::size_t keptCount = 0;
  droppedForCapacity_ = 0;
  for (std::uint32_t i = 0; i < n; ++i) {
    const Candidate& candidate = candidates_[order_[i]];
    if (overlapsKept(candidate, keptCount)) {
      continue;
    }
    if (keptCount == out.size()) {
      ++droppedForCapacity_;
      continue;
    }
    kept_[keptCount++] = order_[i];
  }
  // Best score first in the output.
  std::sort(kept_.begin(), kept_.begin() + static_cast<std::ptrdiff_t>(keptCount),
            [this](std::uint32_t i, std::uint32_t j) {
              const Candidate& a = candidates_[i];
              const Candidate& b = candidates_[j];
              if (a.detection.score != b.detection.score) {
                return a.detection.score > b.detection.score;
              }
              if (a.detection.tile != b.detection.tile) {
                return a.detection.tile < b.detection.tile;
              }
              return a.cell < b.cell;
            });
  for (std::size_t k = 0; k < keptCount; ++k) {
    out[k] = candidates_[kept_[k]].detection;
  }
  return keptCount;
}

}  // namespace vp::detection
