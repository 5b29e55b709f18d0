// preprocess/area_resizer: downscales a frame to the working resolution with the area filter
// (each output pixel = mean of the source area it covers), with no heap allocation per frame.
//
// Contract: the result equals cv::resize(src, dst, dstSize, 0, 0, cv::INTER_AREA) - the
// filter the Python training and evaluation code (tools/detector/evaluate.py, Predictor)
// uses - bit for bit: for integer factors the integer block sum times 1/area rounded half to
// even (2 x 2: half up, as OpenCV's SIMD path); otherwise OpenCV's coverage weights
// (computeResizeAreaTab) accumulated in float in the same order (each source row's horizontal
// sums, then the rows' weighted sum). init() builds the weight tables; applyRows() fills output
// rows [rowBegin, rowEnd) in one sweep over the source rows they cover (no full-size
// intermediate) and needs one scratch slot per concurrent caller: slot < scratchSlots.
// Optional per-channel gains are applied to every source value on the way in, exactly as
// WhiteBalancer's tables (saturate(round(v * gain)), half to even), and the gained source
// rows can be written out to a full-size image in the same sweep. The inner loops use SSE2
// on x86-64 (AVX2 where the CPU has it, chosen at run time) and portable scalar code
// elsewhere; every variant gives the same bytes. Downscaling only (dst no larger than src in
// either axis); 8-bit, 3 channels. dst may be a sub-view (ROI) of a larger image.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

namespace vp::preprocess {

// What the resize reads: a BGR8 image, or a camera frame in YUYV or NV12 whose rows are
// converted to BGR8 (yuv_rows.hpp) one at a time inside the sweep. Views: nothing is owned.
struct ResizeSource {
  enum class Layout { Bgr, Yuyv, Nv12 };
  Layout layout = Layout::Bgr;
  const std::uint8_t* data = nullptr;  // BGR or YUYV rows, or NV12's Y plane
  std::size_t strideBytes = 0;         // bytes between rows
  const std::uint8_t* uv = nullptr;    // NV12: the interleaved UV plane (one row per two rows)
  std::size_t uvStrideBytes = 0;
  static ResizeSource bgr(const cv::Mat& image) {
    return {Layout::Bgr, image.data, image.step[0], nullptr, 0};
  }
};

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
  void applyRows(const cv::Mat& src, cv::Mat& dst, int rowBegin, int rowEnd, int slot) const {
    applyRows(ResizeSource::bgr(src), dst, rowBegin, rowEnd, slot, nullptr, nullptr);
  }
  // With gains (B, G, R; nullptr: none) every source value v enters as saturate(round(v *
  // gain)); with `gained` (a CV_8UC3 image of the source size, nullptr: none) the gained source
  // rows owned by [rowBegin, rowEnd) are written there (sourceRowsOwned: calls covering every
  // output row write every source row once).
  void applyRows(const cv::Mat& src, cv::Mat& dst, int rowBegin, int rowEnd, int slot,
                 const std::array<float, 3>* gains, cv::Mat* gained) const {
    applyRows(ResizeSource::bgr(src), dst, rowBegin, rowEnd, slot, gains, gained);
  }
  // From any source layout (of srcSize; YUV needs an even width, NV12 an even height).
  void applyRows(const ResizeSource& src, cv::Mat& dst, int rowBegin, int rowEnd, int slot,
                 const std::array<float, 3>* gains, cv::Mat* gained) const;
  // The source rows [first, second) an output-row range owns (for `gained`).
  std::pair<int, int> sourceRowsOwned(int rowBegin, int rowEnd) const;

  // All rows on slot 0, with the checks: false (nothing written) on a wrong size or type.
  bool apply(const cv::Mat& src, cv::Mat& dst) const;

 private:
  // One slot's scratch rows (float and 16-bit, padded for vector loads past the end).
  struct Scratch {
    std::uint8_t* gainedRow;  // one gained source row (when gains are on and not written out)
    std::uint8_t* bgrRow;     // one converted source row (YUV layouts)
    std::uint16_t* sum16;     // integer path: the block's column sums
    float* rowF;              // general path: one source row in float
    float* horizontal;        // general path: that row's horizontal sums (cached by row)
    float* sum;               // general path: the output row being accumulated
  };
  Scratch scratch(int slot) const;
  const std::uint8_t* rawRow(const ResizeSource& src, int row, std::uint8_t* scratchRow) const;
  const std::uint8_t* sourceRow(const ResizeSource& src, int row, const std::array<float, 3>* gains,
                                cv::Mat* gained, int ownedBegin, int ownedEnd,
                                const Scratch& scratch) const;
  void writeOwnedRows(const ResizeSource& src, int ownedBegin, int ownedEnd,
                      const std::array<float, 3>& gains, cv::Mat& gained,
                      const Scratch& scratch) const;
  void applyRowsInteger(const ResizeSource& src, cv::Mat& dst, int rowBegin, int rowEnd, int slot,
                        const std::array<float, 3>* gains, cv::Mat* gained) const;
  void applyRowsGeneral(const ResizeSource& src, cv::Mat& dst, int rowBegin, int rowEnd, int slot,
                        const std::array<float, 3>* gains, cv::Mat* gained) const;

  cv::Size srcSize_{};
  cv::Size dstSize_{};
  int factorX_ = 0;  // > 0: exact integer factors (the fast block-mean path)
  int factorY_ = 0;
  // Vertical terms (OpenCV's order), grouped per output row by yTermStart_.
  std::vector<int> yRows_;
  std::vector<float> yWeights_;
  std::vector<int> yTermStart_;  // per output row: first index into yRows_ (+ 1 sentinel)
  // The horizontal terms: one fixed-length run of xTaps_ weights per output pixel from
  // source pixel xFirst_[dx] on (zero weights pad the shorter runs: adding 0 changes no sum),
  // so that the inner loop has no branches and vectorises over the three channels.
  int xTaps_ = 0;
  std::vector<int> xFirst_;
  std::vector<float> xWeights_;
  std::vector<int> ownedEnd_;  // per output row: end of the source rows it owns (`gained`)
  bool integerFast_ = false;   // integer factors whose block sums fit 16 bits
  int log2FactorX_ = -1;       // factorX_ = 2^log2FactorX_ (-1: not a power of two)
  // Scratch, scratchSlots x per-slot stride (written by applyRows: mutable).
  mutable std::vector<std::uint8_t> scratchBytes_;
  mutable std::vector<std::uint16_t> scratch16_;
  mutable std::vector<float> scratchF_;
  std::size_t strideBytes_ = 0;
  std::size_t stride16_ = 0;
  std::size_t strideF_ = 0;
  std::size_t rowValues_ = 0;         // source row: width x 3
  std::size_t outValues_ = 0;         // output row: width x 3
  std::size_t horizontalOffset_ = 0;  // in a slot's float scratch
  std::size_t sumOffset_ = 0;
};

}  // namespace vp::preprocess
