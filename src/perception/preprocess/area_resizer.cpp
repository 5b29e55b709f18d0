#include "preprocess/area_resizer.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "preprocess/area_kernels.hpp"
#include "preprocess/yuv_rows.hpp"

namespace vp::preprocess {

namespace {

constexpr int kChannels = 3;
// OpenCV ignores coverage slivers thinner than this (source px) in computeResizeAreaTab.
constexpr double kSliver_px = 1e-3;
// Values of slack after every scratch row: vector loads may run this far past the end.
constexpr std::size_t kPad = 64;

bool fail(std::string* why, const std::string& message) {
  if (why != nullptr) {
    *why = "area resize: " + message;
  }
  return false;
}

struct Term {
  int dst = 0;
  int src = 0;
  float weight = 0.0F;
};

// OpenCV's computeResizeAreaTab: the source cells (with their coverage share) of every
// output cell along one axis, output cells ascending and, within one, source cells ascending.
void coverageTerms(int srcSize, int dstSize, double scale, std::vector<Term>* terms) {
  terms->clear();
  for (int d = 0; d < dstSize; ++d) {
    const double fs1 = d * scale;
    const double fs2 = fs1 + scale;
    const double cellWidth = std::min(scale, srcSize - fs1);
    int s1 = static_cast<int>(std::ceil(fs1));
    int s2 = static_cast<int>(std::floor(fs2));
    s2 = std::min(s2, srcSize - 1);
    s1 = std::min(s1, s2);
    if (s1 - fs1 > kSliver_px) {
      terms->push_back({d, s1 - 1, static_cast<float>((s1 - fs1) / cellWidth)});
    }
    for (int s = s1; s < s2; ++s) {
      terms->push_back({d, s, static_cast<float>(1.0 / cellWidth)});
    }
    if (fs2 - s2 > kSliver_px) {
      terms->push_back(
          {d, s2, static_cast<float>(std::min(std::min(fs2 - s2, 1.0), cellWidth) / cellWidth)});
    }
  }
}

}  // namespace

bool AreaResizer::init(cv::Size srcSize, cv::Size dstSize, int scratchSlots, std::string* why) {
  srcSize_ = cv::Size();
  if (srcSize.width <= 0 || srcSize.height <= 0 || dstSize.width <= 0 || dstSize.height <= 0) {
    return fail(why, "sizes must be > 0, got " + std::to_string(srcSize.width) + "x" +
                         std::to_string(srcSize.height) + " -> " + std::to_string(dstSize.width) +
                         "x" + std::to_string(dstSize.height));
  }
  if (dstSize.width > srcSize.width || dstSize.height > srcSize.height) {
    return fail(why, "only downscaling is supported, got " + std::to_string(srcSize.width) + "x" +
                         std::to_string(srcSize.height) + " -> " + std::to_string(dstSize.width) +
                         "x" + std::to_string(dstSize.height));
  }
  if (scratchSlots < 1) {
    return fail(why, "scratchSlots must be >= 1");
  }
  // The same scale arithmetic as cv::resize, so that the integer-factor test agrees with it.
  const double scaleX = 1.0 / (static_cast<double>(dstSize.width) / srcSize.width);
  const double scaleY = 1.0 / (static_cast<double>(dstSize.height) / srcSize.height);
  const int integerX = static_cast<int>(std::lrint(scaleX));
  const int integerY = static_cast<int>(std::lrint(scaleY));
  const bool integer =
      std::abs(scaleX - integerX) < DBL_EPSILON && std::abs(scaleY - integerY) < DBL_EPSILON;
  factorX_ = integer ? integerX : 0;
  factorY_ = integer ? integerY : 0;
  std::vector<Term> xTerms;
  std::vector<Term> yTerms;
  coverageTerms(srcSize.width, dstSize.width, scaleX, &xTerms);
  coverageTerms(srcSize.height, dstSize.height, scaleY, &yTerms);

  // Horizontal taps: a fixed-length run per output pixel.
  xFirst_.assign(static_cast<std::size_t>(dstSize.width), 0);
  std::vector<int> tapCount(static_cast<std::size_t>(dstSize.width), 0);
  for (std::size_t k = 0; k < xTerms.size(); ++k) {
    const auto d = static_cast<std::size_t>(xTerms[k].dst);
    if (tapCount[d] == 0) {
      xFirst_[d] = xTerms[k].src;
    }
    ++tapCount[d];
  }
  xTaps_ = *std::max_element(tapCount.begin(), tapCount.end());
  xWeights_.assign(static_cast<std::size_t>(dstSize.width) * static_cast<std::size_t>(xTaps_),
                   0.0F);
  for (const Term& term : xTerms) {
    const auto d = static_cast<std::size_t>(term.dst);
    const auto tap = static_cast<std::size_t>(term.src - xFirst_[d]);
    xWeights_[d * static_cast<std::size_t>(xTaps_) + tap] = term.weight;
  }
  // After them, the same broadcast for two pixels a vector (area_kernels.hpp, pairWeights).
  const auto taps = static_cast<std::size_t>(xTaps_);
  const std::size_t plain = static_cast<std::size_t>(dstSize.width) * taps;
  const std::size_t pairs = static_cast<std::size_t>(dstSize.width) / 2;
  xWeights_.resize(plain + pairs * taps * 8, 0.0F);
  for (std::size_t p = 0; p < pairs; ++p) {
    for (std::size_t t = 0; t < taps; ++t) {
      for (std::size_t lane = 0; lane < 8; ++lane) {
        xWeights_[plain + (p * taps + t) * 8 + lane] = xWeights_[(2 * p + lane / 4) * taps + t];
      }
    }
  }
  // Runs of the last pixels may reach past the row: the float row carries zeros there.

  // Vertical terms and the source rows each output row owns.
  yRows_.clear();
  yWeights_.clear();
  yTermStart_.assign(static_cast<std::size_t>(dstSize.height) + 1, 0);
  ownedEnd_.assign(static_cast<std::size_t>(dstSize.height), 0);
  int row = -1;
  int ownedUpTo = 0;
  for (const Term& term : yTerms) {
    if (term.dst != row) {
      row = term.dst;
      yTermStart_[static_cast<std::size_t>(row)] = static_cast<int>(yRows_.size());
    }
    yRows_.push_back(term.src);
    yWeights_.push_back(term.weight);
    ownedUpTo = std::max(ownedUpTo, term.src + 1);
    ownedEnd_[static_cast<std::size_t>(row)] = ownedUpTo;
  }
  yTermStart_[static_cast<std::size_t>(dstSize.height)] = static_cast<int>(yRows_.size());
  ownedEnd_.back() = srcSize.height;

  integerFast_ = false;
  log2FactorX_ = -1;
  if (integer) {
    for (int k = 0; k < 16; ++k) {
      if ((1 << k) == integerX) {
        log2FactorX_ = k;
      }
    }
    // Column sums of fy rows and block sums of fx x fy pixels must fit 16 bits.
    integerFast_ = integerX * integerY * 255 <= 65535;
  }

  rowValues_ = static_cast<std::size_t>(srcSize.width) * kChannels;
  outValues_ = static_cast<std::size_t>(dstSize.width) * kChannels;
  const auto slots = static_cast<std::size_t>(scratchSlots);
  strideBytes_ = 2 * (rowValues_ + kPad);  // a gained row and a converted row
  scratchBytes_.assign(strideBytes_ * slots, 0);
  if (integer) {
    // 32-bit sums when 16 bits do not hold them.
    stride16_ = integerFast_ ? rowValues_ + static_cast<std::size_t>(3 * integerX) + kPad : 0;
    scratch16_.assign(stride16_ * slots, 0);
    strideF_ = integerFast_ ? 0 : rowValues_ + kPad;
    scratchF_.assign(strideF_ * slots, 0.0F);
    horizontalOffset_ = 0;
    sumOffset_ = 0;
  } else {
    stride16_ = 0;
    scratch16_.clear();
    // Float row with room for the last pixels' taps, horizontal sums, output sums.
    const std::size_t rowF = rowValues_ + static_cast<std::size_t>(3 * xTaps_) + kPad;
    horizontalOffset_ = rowF;
    sumOffset_ = rowF + outValues_ + kPad;
    strideF_ = sumOffset_ + outValues_ + kPad;
    scratchF_.assign(strideF_ * slots, 0.0F);
  }
  srcSize_ = srcSize;
  dstSize_ = dstSize;
  return true;
}

AreaResizer::Scratch AreaResizer::scratch(int slot) const {
  const auto s = static_cast<std::size_t>(slot);
  Scratch out{};
  out.gainedRow = scratchBytes_.data() + strideBytes_ * s;
  out.bgrRow = out.gainedRow + rowValues_ + kPad;
  out.sum16 = scratch16_.empty() ? nullptr : scratch16_.data() + stride16_ * s;
  float* f = scratchF_.empty() ? nullptr : scratchF_.data() + strideF_ * s;
  out.rowF = f;
  out.horizontal = f == nullptr ? nullptr : f + horizontalOffset_;
  out.sum = f == nullptr ? nullptr : f + sumOffset_;
  return out;
}

std::pair<int, int> AreaResizer::sourceRowsOwned(int rowBegin, int rowEnd) const {
  if (rowBegin >= rowEnd) {
    return {0, 0};
  }
  const int first = rowBegin == 0 ? 0 : ownedEnd_[static_cast<std::size_t>(rowBegin) - 1];
  return {first, ownedEnd_[static_cast<std::size_t>(rowEnd) - 1]};
}

// The source row in BGR8: the image's own row, or the camera row converted into scratch.
const std::uint8_t* AreaResizer::rawRow(const ResizeSource& src, int row,
                                        std::uint8_t* scratchRow) const {
  const std::uint8_t* in = src.data + static_cast<std::size_t>(row) * src.strideBytes;
  switch (src.layout) {
    case ResizeSource::Layout::Bgr:
      return in;
    case ResizeSource::Layout::Yuyv:
      yuyvRowToBgr(in, srcSize_.width, scratchRow);
      return scratchRow;
    case ResizeSource::Layout::Nv12:
      nv12RowToBgr(in, src.uv + static_cast<std::size_t>(row / 2) * src.uvStrideBytes,
                   srcSize_.width, scratchRow);
      return scratchRow;
  }
  return in;
}

// The source row as the mean sees it: rawRow, or its gained copy (in `gained` when this
// output row owns the row - written when it started -, else in the slot's scratch).
const std::uint8_t* AreaResizer::sourceRow(const ResizeSource& src, int row,
                                           const std::array<float, 3>* gains, cv::Mat* gained,
                                           int ownedBegin, int ownedEnd,
                                           const Scratch& scratch) const {
  if (gains != nullptr && gained != nullptr && row >= ownedBegin && row < ownedEnd) {
    return gained->ptr<std::uint8_t>(row);
  }
  const std::uint8_t* in = rawRow(src, row, scratch.bgrRow);
  if (gains == nullptr) {
    return in;
  }
  kernels::applyGains(in, scratch.gainedRow, rowValues_, *gains);
  return scratch.gainedRow;
}

void AreaResizer::writeOwnedRows(const ResizeSource& src, int ownedBegin, int ownedEnd,
                                 const std::array<float, 3>& gains, cv::Mat& gained,
                                 const Scratch& scratch) const {
  for (int r = ownedBegin; r < ownedEnd; ++r) {
    kernels::applyGains(rawRow(src, r, scratch.bgrRow), gained.ptr<std::uint8_t>(r), rowValues_,
                        gains);
  }
}

void AreaResizer::applyRows(const ResizeSource& src, cv::Mat& dst, int rowBegin, int rowEnd,
                            int slot, const std::array<float, 3>* gains, cv::Mat* gained) const {
  if (gains == nullptr) {
    gained = nullptr;
  }
  if (factorX_ > 0) {
    applyRowsInteger(src, dst, rowBegin, rowEnd, slot, gains, gained);
  } else {
    applyRowsGeneral(src, dst, rowBegin, rowEnd, slot, gains, gained);
  }
}

void AreaResizer::applyRowsInteger(const ResizeSource& src, cv::Mat& dst, int rowBegin, int rowEnd,
                                   int slot, const std::array<float, 3>* gains,
                                   cv::Mat* gained) const {
  const int fx = factorX_;
  const int fy = factorY_;
  const Scratch s = scratch(slot);
  // OpenCV's SIMD path for 2 x 2 rounds half up; every other factor goes through
  // sum * (1 / area) in float and cvRound (half to even).
  const kernels::BlockRounding rounding = kernels::blockRounding(fx, fy);
  for (int dy = rowBegin; dy < rowEnd; ++dy) {
    const auto [ownedBegin, ownedEnd] = sourceRowsOwned(dy, dy + 1);
    if (gained != nullptr) {
      writeOwnedRows(src, ownedBegin, ownedEnd, *gains, *gained, s);
    }
    std::uint8_t* out = dst.ptr<std::uint8_t>(dy);
    if (integerFast_) {
      // Rows in groups, but one at a time when each goes through the slot's scratch row.
      constexpr int kGroup = 8;
      std::array<const std::uint8_t*, kGroup> rows{};
      const bool throughScratch = src.layout != ResizeSource::Layout::Bgr || gains != nullptr;
      const int group = throughScratch && gained == nullptr ? 1 : kGroup;
      for (int r0 = 0; r0 < fy; r0 += group) {
        const int count = std::min(group, fy - r0);
        for (int r = 0; r < count; ++r) {
          rows[static_cast<std::size_t>(r)] =
              sourceRow(src, dy * fy + r0 + r, gains, gained, ownedBegin, ownedEnd, s);
        }
        kernels::accumulateColumns16(rows.data(), count, s.sum16, rowValues_, r0 == 0);
      }
      kernels::blockSums16(s.sum16, rowValues_, fx, log2FactorX_);
      kernels::roundBlocks16(s.sum16, rowValues_, s.gainedRow, out, outValues_, fx, rounding);
    } else {
      // Large factors: 32-bit column sums in the float scratch's bytes.
      auto* sum32 = reinterpret_cast<std::uint32_t*>(s.rowF);
      std::fill(sum32, sum32 + rowValues_, 0U);
      for (int r = 0; r < fy; ++r) {
        const std::uint8_t* row =
            sourceRow(src, dy * fy + r, gains, gained, ownedBegin, ownedEnd, s);
        for (std::size_t i = 0; i < rowValues_; ++i) {
          sum32[i] += row[i];
        }
      }
      kernels::roundBlocks32(sum32, out, outValues_, fx, rounding);
    }
  }
}

void AreaResizer::applyRowsGeneral(const ResizeSource& src, cv::Mat& dst, int rowBegin, int rowEnd,
                                   int slot, const std::array<float, 3>* gains,
                                   cv::Mat* gained) const {
  const Scratch s = scratch(slot);
  int cachedRow = -1;  // the source row whose horizontal sums s.horizontal holds
  for (int dy = rowBegin; dy < rowEnd; ++dy) {
    const auto [ownedBegin, ownedEnd] = sourceRowsOwned(dy, dy + 1);
    if (gained != nullptr) {
      writeOwnedRows(src, ownedBegin, ownedEnd, *gains, *gained, s);
    }
    const int begin = yTermStart_[static_cast<std::size_t>(dy)];
    const int end = yTermStart_[static_cast<std::size_t>(dy) + 1];
    for (int k = begin; k < end; ++k) {
      const int row = yRows_[static_cast<std::size_t>(k)];
      if (row != cachedRow) {
        const std::uint8_t* in = sourceRow(src, row, gains, gained, ownedBegin, ownedEnd, s);
        kernels::toFloat(in, s.rowF, rowValues_);
        kernels::horizontalTaps(s.rowF, s.horizontal, dstSize_.width, xFirst_.data(),
                                xWeights_.data(),
                                xWeights_.data() + static_cast<std::size_t>(dstSize_.width) *
                                                       static_cast<std::size_t>(xTaps_),
                                xTaps_);
        cachedRow = row;
      }
      kernels::accumulateWeighted(s.horizontal, s.sum, outValues_,
                                  yWeights_[static_cast<std::size_t>(k)], k == begin);
    }
    kernels::roundToBytes(s.sum, dst.ptr<std::uint8_t>(dy), outValues_);
  }
}

bool AreaResizer::apply(const cv::Mat& src, cv::Mat& dst) const {
  if (!initialised() || src.type() != CV_8UC3 || dst.type() != CV_8UC3 || src.size() != srcSize_ ||
      dst.size() != dstSize_) {
    return false;
  }
  applyRows(src, dst, 0, dstSize_.height, 0);
  return true;
}

}  // namespace vp::preprocess
