// preprocess/frame_remap: removes lens distortion from full-resolution frames through a
// precomputed fixed-point map, with no heap allocation per frame.
//
// Contract: init() evaluates the lens model once per output pixel (CameraModel::
// distortNormalized: ideal pinhole pixel of the output camera -> distorted source pixel) and
// stores the source position in OpenCV's fixed-point remap form: integer pixel plus a 5-bit
// sub-pixel fraction per axis (1/32 px; the rounding of cv::convertMaps to CV_16SC2).
// applyRows() interpolates bilinearly with the same integer weights as cv::remap
// (INTER_LINEAR, BORDER_CONSTANT 0), so the output equals camera::Undistorter::apply for the
// same map, bit for bit. Output pixels whose source lies beyond the lens model's valid field
// or outside the frame are black. Rows are independent: callers may split them over threads.
// Only 8-bit 3-channel frames (BGR or RGB; the channels are not mixed) are accepted.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "camera/camera_model.hpp"

namespace vp::preprocess {

// Sub-pixel resolution of the map: OpenCV's INTER_BITS (1/32 px per axis).
constexpr int kRemapFractionBits = 5;
constexpr int kRemapFractionSteps = 1 << kRemapFractionBits;

class FrameRemap {
 public:
  FrameRemap() = default;

  // Builds the map from the distorted input camera to the pinhole output camera (intrinsics
  // and size of `output`). Start-up only (allocates width x height x 6 bytes).
  bool init(const camera::CameraModel& input, const camera::Intrinsics& output,
            std::string* why = nullptr);
  bool initialised() const { return !sourceXY_.empty(); }

  cv::Size inputSize() const { return {input_.width_px, input_.height_px}; }
  cv::Size outputSize() const { return {output_.width_px, output_.height_px}; }

  // Remaps output rows [rowBegin, rowEnd) of dst from src. The caller guarantees src is
  // CV_8UC3 of inputSize(), dst CV_8UC3 of outputSize(), and that they do not overlap.
  void applyRows(const cv::Mat& src, cv::Mat& dst, int rowBegin, int rowEnd) const;

  // All rows, with the checks: false (and nothing written) on a wrong size, type or overlap.
  bool apply(const cv::Mat& src, cv::Mat& dst) const;

 private:
  camera::Intrinsics input_{};
  camera::Intrinsics output_{};
  std::vector<std::int16_t> sourceXY_;     // per output pixel: integer source x, y
  std::vector<std::uint16_t> sourceFrac_;  // per output pixel: (fy << 5) | fx, 1/32 px
};

}  // namespace vp::preprocess
