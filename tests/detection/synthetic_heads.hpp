// tests/detection/synthetic_heads: hand-made detector outputs (NHWC float tensors) with
// vehicles placed exactly where a test wants them, the inverse of the decoding formulas.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "detection/decoder.hpp"

namespace vp::detection::test {

class SyntheticHeads {
 public:
  SyntheticHeads(int gridWidth, int gridHeight, int stride_px = 4, float background = 0.01F)
      : width_(gridWidth),
        height_(gridHeight),
        stride_(stride_px),
        heatmap_(static_cast<std::size_t>(gridWidth * gridHeight), background),
        offset_(static_cast<std::size_t>(2 * gridWidth * gridHeight), 0.0F),
        size_(static_cast<std::size_t>(2 * gridWidth * gridHeight), 0.0F),
        direction_(static_cast<std::size_t>(2 * gridWidth * gridHeight), 0.0F) {}

  // A vehicle centred at tile pixel (u, v), length/width in working px, driving direction
  // `angle`: its centre cell gets `score`, its neighbours a Gaussian that stays below it.
  // directionNorm scales (cos, sin) (the network's vector need not be unit length).
  void addVehicle(double u, double v, double length, double width, double angle, float score,
                  double directionNorm = 0.7) {
    const double c0 = (stride_ - 1) / 2.0;
    const double fu = (u - c0) / stride_;
    const double fv = (v - c0) / stride_;
    const int ix = static_cast<int>(std::lround(fu));
    const int iy = static_cast<int>(std::lround(fv));
    for (int y = std::max(0, iy - 3); y <= std::min(height_ - 1, iy + 3); ++y) {
      for (int x = std::max(0, ix - 3); x <= std::min(width_ - 1, ix + 3); ++x) {
        const double r2 = (x - ix) * (x - ix) + (y - iy) * (y - iy);
        const auto blob =
            static_cast<float>(static_cast<double>(score) * 0.8 * std::exp(-0.5 * r2 / 2.25));
        float& cell = heatmap_[static_cast<std::size_t>(y * width_ + x)];
        cell = std::max(cell, x == ix && y == iy ? score : blob);
      }
    }
    const std::size_t k = 2 * static_cast<std::size_t>(iy * width_ + ix);
    offset_[k] = static_cast<float>(fu - ix);
    offset_[k + 1] = static_cast<float>(fv - iy);
    size_[k] = static_cast<float>(std::log(length));
    size_[k + 1] = static_cast<float>(std::log(width));
    direction_[k] = static_cast<float>(directionNorm * std::cos(angle));
    direction_[k + 1] = static_cast<float>(directionNorm * std::sin(angle));
  }

  float& heatmapAt(int x, int y) { return heatmap_[static_cast<std::size_t>(y * width_ + x)]; }
  float* offsetAt(int x, int y) { return &offset_[2 * static_cast<std::size_t>(y * width_ + x)]; }
  float* sizeAt(int x, int y) { return &size_[2 * static_cast<std::size_t>(y * width_ + x)]; }
  float* directionAt(int x, int y) {
    return &direction_[2 * static_cast<std::size_t>(y * width_ + x)];
  }

  HeadTensors heads() const {
    HeadTensors h;
    h.heatmap = heatmap_.data();
    h.offset = offset_.data();
    h.size = size_.data();
    h.direction = direction_.data();
    h.gridWidth = width_;
    h.gridHeight = height_;
    h.stride_px = stride_;
    return h;
  }

 private:
  int width_;
  int height_;
  int stride_;
  std::vector<float> heatmap_;
  std::vector<float> offset_;
  std::vector<float> size_;
  std::vector<float> direction_;
};

}  // namespace vp::detection::test
