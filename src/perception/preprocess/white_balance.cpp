#include "preprocess/white_balance.hpp"

#include <algorithm>
#include <cmath>

namespace vp::preprocess {

namespace {

constexpr int kLumaBins = 256;  // 1 luminance level per bin
constexpr float kSkipped = -1.0F;
// The seed's acceptance band around the region statistics (in units of Db, Dr) and the
// extra weight of Mr in the red-chroma condition.
constexpr float kBandWidth = 1.5F;
constexpr float kRedMeanWeight = 1.5F;

bool fail(std::string* why, const std::string& message) {
  if (why != nullptr) {
    *why = "white_balance." + message;
  }
  return false;
}

float sign(float value) {
  return value > 0.0F ? 1.0F : (value < 0.0F ? -1.0F : 0.0F);
}

}  // namespace

bool validate(const WhiteBalanceOptions& options, std::string* why) {
  if (options.regionRows < 1 || options.regionCols < 1 ||
      options.regionRows * options.regionCols > kMaxWhiteBalanceRegions) {
    return fail(why, "region_rows x region_cols: must be >= 1 each and at most " +
                         std::to_string(kMaxWhiteBalanceRegions) + " regions, got " +
                         std::to_string(options.regionRows) + " x " +
                         std::to_string(options.regionCols));
  }
  if (options.sampleStride_px < 1) {
    return fail(why,
                "sample_stride_px: must be >= 1, got " + std::to_string(options.sampleStride_px));
  }
  if (!(options.whitePointShare > 0.0 && options.whitePointShare <= 1.0)) {
    return fail(why, "white_point_share: must be in (0, 1], got " +
                         std::to_string(options.whitePointShare));
  }
  if (!(options.minRegionDeviation >= 0.0) || !std::isfinite(options.minRegionDeviation)) {
    return fail(why, "min_region_deviation: must be finite and >= 0");
  }
  if (!(options.maxGain >= 1.0) || !std::isfinite(options.maxGain)) {
    return fail(why, "max_gain: must be finite and >= 1, got " + std::to_string(options.maxGain));
  }
  return true;
}

bool WhiteBalancer::init(const WhiteBalanceOptions& options, cv::Size frameSize, std::string* why) {
  if (!validate(options, why)) {
    return false;
  }
  if (frameSize.width <= 0 || frameSize.height <= 0) {
    return fail(why, "frame size must be > 0");
  }
  options_ = options;
  frameSize_ = frameSize;
  samplesX_ = (frameSize.width + options.sampleStride_px - 1) / options.sampleStride_px;
  samplesY_ = (frameSize.height + options.sampleStride_px - 1) / options.sampleStride_px;
  const std::size_t samples =
      static_cast<std::size_t>(samplesX_) * static_cast<std::size_t>(samplesY_);
  regionCol_.resize(static_cast<std::size_t>(samplesX_));
  for (int sx = 0; sx < samplesX_; ++sx) {
    regionCol_[static_cast<std::size_t>(sx)] = sx * options.regionCols / samplesX_;
  }
  regionRowStart_.resize(static_cast<std::size_t>(samplesY_));
  for (int sy = 0; sy < samplesY_; ++sy) {
    regionRowStart_[static_cast<std::size_t>(sy)] =
        (sy * options.regionRows / samplesY_) * options.regionCols;
  }
  luma_.assign(samples, 0.0F);
  cb_.assign(samples, 0.0F);
  cr_.assign(samples, 0.0F);
  setGains(WhiteBalanceGains{});
  return true;
}

WhiteBalanceGains WhiteBalancer::estimate(const cv::Mat& bgrFrame) {
  WhiteBalanceGains result;
  if (!initialised() || bgrFrame.type() != CV_8UC3 || bgrFrame.size() != frameSize_) {
    return result;
  }
  const int regionCount = options_.regionRows * options_.regionCols;
  std::array<double, kMaxWhiteBalanceRegions> sumCb{};
  std::array<double, kMaxWhiteBalanceRegions> sumCr{};
  std::array<int, kMaxWhiteBalanceRegions> count{};
  const int stride = options_.sampleStride_px;
  // Region of a sample: tables built at init() (two integer divisions per sample otherwise).
  auto regionOf = [&](int sx, int sy) {
    return regionRowStart_[static_cast<std::size_t>(sy)] + regionCol_[static_cast<std::size_t>(sx)];
  };

  // 1. YCbCr of the samples, per-region chroma means, the largest luminance.
  float lumaMax = 0.0F;
  std::size_t i = 0;
  for (int sy = 0; sy < samplesY_; ++sy) {
    const std::uint8_t* row = bgrFrame.ptr<std::uint8_t>(sy * stride);
    for (int sx = 0; sx < samplesX_; ++sx, ++i) {
      const std::uint8_t* p = row + static_cast<std::size_t>(sx) * stride * 3;
      const float b = p[0];
      const float g = p[1];
      const float r = p[2];
      if (p[0] == 0 && p[1] == 0 && p[2] == 0) {
        luma_[i] = kSkipped;
        continue;
      }
      // BT.601 full range (JPEG's YCbCr), chroma centred on 0.
      const float y = 0.299F * r + 0.587F * g + 0.114F * b;
      const float cb = -0.168736F * r - 0.331264F * g + 0.5F * b;
      const float cr = 0.5F * r - 0.418688F * g - 0.081312F * b;
      luma_[i] = y;
      cb_[i] = cb;
      cr_[i] = cr;
      lumaMax = std::max(lumaMax, y);
      const int region = regionOf(sx, sy);
      sumCb[region] += static_cast<double>(cb);
      sumCr[region] += static_cast<double>(cr);
      ++count[region];
    }
  }
  std::array<double, kMaxWhiteBalanceRegions> meanCb{};
  std::array<double, kMaxWhiteBalanceRegions> meanCr{};
  for (int k = 0; k < regionCount; ++k) {
    if (count[k] > 0) {
      meanCb[k] = sumCb[k] / count[k];
      meanCr[k] = sumCr[k] / count[k];
    }
  }

  // 2. Per-region mean absolute chroma deviations.
  std::array<double, kMaxWhiteBalanceRegions> devCb{};
  std::array<double, kMaxWhiteBalanceRegions> devCr{};
  i = 0;
  for (int sy = 0; sy < samplesY_; ++sy) {
    for (int sx = 0; sx < samplesX_; ++sx, ++i) {
      if (luma_[i] < 0.0F) {
        continue;
      }
      const int region = regionOf(sx, sy);
      devCb[region] += std::abs(static_cast<double>(cb_[i]) - meanCb[region]);
      devCr[region] += std::abs(static_cast<double>(cr_[i]) - meanCr[region]);
    }
  }

  // 3. Average statistics of the regions with colour variation.
  double mb = 0.0;
  double mr = 0.0;
  double db = 0.0;
  double dr = 0.0;
  for (int k = 0; k < regionCount; ++k) {
    if (count[k] == 0) {
      continue;
    }
    const double regionDb = devCb[k] / count[k];
    const double regionDr = devCr[k] / count[k];
    if (regionDb < options_.minRegionDeviation && regionDr < options_.minRegionDeviation) {
      continue;
    }
    mb += meanCb[k];
    mr += meanCr[k];
    db += regionDb;
    dr += regionDr;
    ++result.regionsUsed;
  }
  if (result.regionsUsed == 0) {
    return result;
  }
  const auto mbF = static_cast<float>(mb / result.regionsUsed);
  const auto mrF = static_cast<float>(mr / result.regionsUsed);
  const auto dbF = static_cast<float>(db / result.regionsUsed);
  const auto drF = static_cast<float>(dr / result.regionsUsed);
  const float centreCb = mbF + dbF * sign(mbF);
  const float centreCr = kRedMeanWeight * mrF + drF * sign(mrF);

  // 4. Near-white candidates, binned by luminance with their channel sums.
  std::array<int, kLumaBins> binCount{};
  std::array<std::array<double, 3>, kLumaBins> binSum{};
  i = 0;
  for (int sy = 0; sy < samplesY_; ++sy) {
    const std::uint8_t* row = bgrFrame.ptr<std::uint8_t>(sy * stride);
    for (int sx = 0; sx < samplesX_; ++sx, ++i) {
      if (luma_[i] < 0.0F || !(std::abs(cb_[i] - centreCb) < kBandWidth * dbF) ||
          !(std::abs(cr_[i] - centreCr) < kBandWidth * drF)) {
        continue;
      }
      const int bin = std::clamp(static_cast<int>(luma_[i]), 0, kLumaBins - 1);
      const std::uint8_t* p = row + static_cast<std::size_t>(sx) * stride * 3;
      ++binCount[bin];
      binSum[bin][0] += p[0];
      binSum[bin][1] += p[1];
      binSum[bin][2] += p[2];
      ++result.candidateCount;
    }
  }
  if (result.candidateCount == 0) {
    return result;
  }

  // 5. The brightest share of the candidates are the reference white; gains Ymax / mean.
  const auto wanted = static_cast<int>(
      std::ceil(options_.whitePointShare * static_cast<double>(result.candidateCount)));
  std::array<double, 3> sum{};
  for (int bin = kLumaBins - 1; bin >= 0 && result.referenceCount < wanted; --bin) {
    result.referenceCount += binCount[bin];
    for (int c = 0; c < 3; ++c) {
      sum[c] += binSum[bin][c];
    }
  }
  const double maxGain = options_.maxGain;
  for (int c = 0; c < 3; ++c) {
    const double mean = sum[c] / result.referenceCount;
    const double gain = mean > 0.0 ? static_cast<double>(lumaMax) / mean : maxGain;
    result.gain[c] = static_cast<float>(std::clamp(gain, 1.0 / maxGain, maxGain));
  }
  result.found = true;
  return result;
}

std::array<std::uint8_t, 256> gainTable(float gain) {
  std::array<std::uint8_t, 256> table{};
  for (int v = 0; v < 256; ++v) {
    const long scaled = std::lrint(static_cast<float>(v) * gain);
    table[static_cast<std::size_t>(v)] = static_cast<std::uint8_t>(std::clamp(scaled, 0L, 255L));
  }
  return table;
}

void WhiteBalancer::setGains(const WhiteBalanceGains& gains) {
  for (std::size_t c = 0; c < 3; ++c) {
    table_[c] = gainTable(gains.gain[c]);
  }
}

void WhiteBalancer::applyRows(const cv::Mat& src, cv::Mat& dst, int rowBegin, int rowEnd) const {
  const int width = src.cols;
  const auto& t0 = table_[0];
  const auto& t1 = table_[1];
  const auto& t2 = table_[2];
  for (int v = rowBegin; v < rowEnd; ++v) {
    const std::uint8_t* in = src.ptr<std::uint8_t>(v);
    std::uint8_t* out = dst.ptr<std::uint8_t>(v);
    for (int u = 0; u < width; ++u, in += 3, out += 3) {
      out[0] = t0[in[0]];
      out[1] = t1[in[1]];
      out[2] = t2[in[2]];
    }
  }
}

}  // namespace vp::preprocess
