// preprocess/area_resizer: downscales a frame to the working resolution with the area filter
// (each output pixel = mean of the source area it covers), with no heap allocation per frame.
//
// Contract: the result equals cv::resize(src, dst, dstSize, 0, 0, cv::INTER_AREA) - the
// filter the Python training and evaluation code (tools/detector/evaluate.py, Predictor)
// uses - bit for bit: for integer factors the integer block sum times 1/area rounded half to
// even; otherwise OpenCV's coverage weights (computeResizeAreaTab) accumulated in float in the
// same order. init() builds the weight tables; applyRows() fills output rows
// [rowBegin, rowEnd) and needs one scratch slot (two float rows) per concurrent caller:
// slot < scratchSlots. Downscaling only (dst no larger than src in either axis); 8-bit,
// 3 channels. dst may be a sub-view (ROI) of a larger image.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace vp::preprocess {

class AreaResizer {
 public:
  AreaResizer() = default;

  // Start-up: tables for src -> dst sizes and scratchSlots concurrent row ranges.
  bool init(cv::Size srcSize, cv::Size dstSize, int scratchSlots, std::string* why = nullptr);
  bool initialised() const { return srcSize_.width > 0; }

  cv::Size srcSize() const { return srcSize_; }
  cv::Size dstSize() const { return dstSize_; }
  bool integerFactor() const { return factorX_ > 0; }

  // The caller guarantees sizes and types (CV_8UC3) and slot < scratchSlots.
  void applyRows(const cv::Mat& src, cv::Mat& dst, int rowBegin, int rowEnd, int slot) const;

  // All rows on slot 0, with the checks: false (nothing written) on a wrong size or type.
  bool apply(const cv::Mat& src, cv::Mat& dst) const;

 private:
  // One term of a separable coverage sum: output index `dst` takes `weight` x source `src`.
  struct Term {
    int dst = 0;  // output column x channels (horizontal) or output row (vertical)
    int src = 0;  // source column x channels or source row
    float weight = 0.0F;
  };

  void applyRowsInteger(const cv::Mat& src, cv::Mat& dst, int rowBegin, int rowEnd) const;
  void applyRowsGeneral(const cv::Mat& src, cv::Mat& dst, int rowBegin, int rowEnd, int slot) const;

  cv::Size srcSize_{};
  cv::Size dstSize_{};
  int factorX_ = 0;  // > 0: exact integer factors (the fast block-mean path)
  int factorY_ = 0;
  std::vector<Term> xTerms_;
  std::vector<Term> yTerms_;
  std::vector<int> yTermStart_;         // per output row: first index into yTerms_ (+ 1 sentinel)
  mutable std::vector<float> scratch_;  // scratchSlots x (row buffer + sum buffer)
  std::size_t scratchStride_ = 0;
};

}  // namespace vp::preprocess
