#include "preprocess/area_resizer.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>

namespace vp::preprocess {

namespace {

constexpr int kChannels = 3;
// OpenCV ignores coverage slivers thinner than this (source px) in computeResizeAreaTab.
constexpr double kSliver_px = 1e-3;

bool fail(std::string* why, const std::string& message) {
  if (why != nullptr) {
    *why = "area resize: " + message;
  }
  return false;
}

std::uint8_t saturateRound(float value) {
  const long rounded = std::lrint(value);  // half to even, as cvRound
  return static_cast<std::uint8_t>(std::clamp(rounded, 0L, 255L));
}

// OpenCV's computeResizeAreaTab: the source cells (with their coverage share) of every
// output cell along one axis. `channels` multiplies the indices (interleaved pixels).
template <class Term>
void coverageTerms(int srcSize, int dstSize, int channels, double scale, std::vector<Term>* terms) {
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
      terms->push_back(
          {d * channels, (s1 - 1) * channels, static_cast<float>((s1 - fs1) / cellWidth)});
    }
    for (int s = s1; s < s2; ++s) {
      terms->push_back({d * channels, s * channels, static_cast<float>(1.0 / cellWidth)});
    }
    if (fs2 - s2 > kSliver_px) {
      terms->push_back(
          {d * channels, s2 * channels,
           static_cast<float>(std::min(std::min(fs2 - s2, 1.0), cellWidth) / cellWidth)});
    }
  }
}

}  // namespace

bool AreaResizer::init(cv::Size srcSize, cv::Size dstSize, int scratchSlots, std::string* why) {
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
  coverageTerms(srcSize.width, dstSize.width, kChannels, scaleX, &xTerms_);
  coverageTerms(srcSize.height, dstSize.height, 1, scaleY, &yTerms_);
  yTermStart_.assign(static_cast<std::size_t>(dstSize.height) + 1, 0);
  int row = 0;
  for (std::size_t k = 0; k < yTerms_.size(); ++k) {
    if (k == 0 || yTerms_[k].dst != yTerms_[k - 1].dst) {
      yTermStart_[static_cast<std::size_t>(row++)] = static_cast<int>(k);
    }
  }
  yTermStart_[static_cast<std::size_t>(dstSize.height)] = static_cast<int>(yTerms_.size());
  scratchStride_ = 2 * static_cast<std::size_t>(dstSize.width) * kChannels;
  scratch_.assign(scratchStride_ * static_cast<std::size_t>(scratchSlots), 0.0F);
  srcSize_ = srcSize;
  dstSize_ = dstSize;
  return true;
}

void AreaResizer::applyRows(const cv::Mat& src, cv::Mat& dst, int rowBegin, int rowEnd,
                            int slot) const {
  if (factorX_ > 0) {
    applyRowsInteger(src, dst, rowBegin, rowEnd);
  } else {
    applyRowsGeneral(src, dst, rowBegin, rowEnd, slot);
  }
}

void AreaResizer::applyRowsInteger(const cv::Mat& src, cv::Mat& dst, int rowBegin,
                                   int rowEnd) const {
  const int fx = factorX_;
  const int fy = factorY_;
  const int width = dstSize_.width;
  // OpenCV's SIMD path for 2 x 2 rounds half up; every other factor goes through
  // sum * (1 / area) in float and cvRound (half to even).
  const bool halfUp = fx == 2 && fy == 2;
  const float inverseArea = 1.0F / static_cast<float>(fx * fy);
  for (int dy = rowBegin; dy < rowEnd; ++dy) {
    std::uint8_t* out = dst.ptr<std::uint8_t>(dy);
    const std::uint8_t* top = src.ptr<std::uint8_t>(dy * fy);
    for (int dx = 0; dx < width; ++dx) {
      int sum0 = 0;
      int sum1 = 0;
      int sum2 = 0;
      const std::uint8_t* block = top + static_cast<std::size_t>(dx) * fx * kChannels;
      for (int r = 0; r < fy; ++r) {
        const std::uint8_t* p = block + static_cast<std::size_t>(r) * src.step[0];
        for (int c = 0; c < fx; ++c, p += kChannels) {
          sum0 += p[0];
          sum1 += p[1];
          sum2 += p[2];
        }
      }
      std::uint8_t* o = out + static_cast<std::size_t>(dx) * kChannels;
      if (halfUp) {
        o[0] = static_cast<std::uint8_t>((sum0 + 2) >> 2);
        o[1] = static_cast<std::uint8_t>((sum1 + 2) >> 2);
        o[2] = static_cast<std::uint8_t>((sum2 + 2) >> 2);
      } else {
        o[0] = saturateRound(static_cast<float>(sum0) * inverseArea);
        o[1] = saturateRound(static_cast<float>(sum1) * inverseArea);
        o[2] = saturateRound(static_cast<float>(sum2) * inverseArea);
      }
    }
  }
}

void AreaResizer::applyRowsGeneral(const cv::Mat& src, cv::Mat& dst, int rowBegin, int rowEnd,
                                   int slot) const {
  const std::size_t rowValues = static_cast<std::size_t>(dstSize_.width) * kChannels;
  float* buf = scratch_.data() + scratchStride_ * static_cast<std::size_t>(slot);
  float* sum = buf + rowValues;
  for (int dy = rowBegin; dy < rowEnd; ++dy) {
    std::fill(sum, sum + rowValues, 0.0F);
    const int begin = yTermStart_[static_cast<std::size_t>(dy)];
    const int end = yTermStart_[static_cast<std::size_t>(dy) + 1];
    for (int k = begin; k < end; ++k) {
      const Term& yTerm = yTerms_[static_cast<std::size_t>(k)];
      const std::uint8_t* s = src.ptr<std::uint8_t>(yTerm.src);
      std::fill(buf, buf + rowValues, 0.0F);
      for (const Term& xTerm : xTerms_) {
        float* b = buf + xTerm.dst;
        const std::uint8_t* p = s + xTerm.src;
        b[0] = b[0] + static_cast<float>(p[0]) * xTerm.weight;
        b[1] = b[1] + static_cast<float>(p[1]) * xTerm.weight;
        b[2] = b[2] + static_cast<float>(p[2]) * xTerm.weight;
      }
      const float beta = yTerm.weight;
      for (std::size_t i = 0; i < rowValues; ++i) {
        sum[i] += beta * buf[i];
      }
    }
    std::uint8_t* out = dst.ptr<std::uint8_t>(dy);
    for (std::size_t i = 0; i < rowValues; ++i) {
      out[i] = saturateRound(sum[i]);
    }
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
