#include "preprocess/exposure.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace vp::preprocess {

namespace {

constexpr double kLimitedRangeScale = 255.0 / 219.0;

bool fail(std::string* why, const std::string& message) {
  if (why != nullptr) {
    *why = "exposure_" + message;
  }
  return false;
}

ExposureGain gainFor(double sum, long count, const ExposureOptions& options) {
  ExposureGain result;
  if (count == 0) {
    return result;
  }
  const double mean = sum / static_cast<double>(count);
  result.meanLuma = static_cast<float>(mean);
  if (!options.enabled || mean >= options.darkMeanLuma) {
    return result;
  }
  // A nearly black frame (mean < 1) takes the largest gain rather than a division by ~0.
  const double gain = mean > 0.0 ? options.targetMeanLuma / mean : options.maxGain;
  result.gain = static_cast<float>(std::clamp(gain, 1.0, options.maxGain));
  result.applied = result.gain > 1.0F;
  return result;
}

}  // namespace

bool validate(const ExposureOptions& options, std::string* why) {
  if (!(options.darkMeanLuma >= 0.0 && options.darkMeanLuma <= 255.0)) {
    return fail(why, "dark_mean: must be in [0, 255], got " + std::to_string(options.darkMeanLuma));
  }
  if (!(options.targetMeanLuma >= options.darkMeanLuma && options.targetMeanLuma <= 255.0)) {
    return fail(why, "target_mean: must be in [exposure_dark_mean, 255], got " +
                         std::to_string(options.targetMeanLuma));
  }
  if (!(options.maxGain >= 1.0 && options.maxGain <= 16.0)) {
    return fail(why, "max_gain: must be in [1, 16], got " + std::to_string(options.maxGain));
  }
  if (options.sampleStride_px < 1 || options.sampleStride_px > 64) {
    return fail(why, "sample_stride_px: must be in [1, 64], got " +
                         std::to_string(options.sampleStride_px));
  }
  return true;
}

ExposureGain estimateExposure(const cv::Mat& bgrFrame, const ExposureOptions& options) {
  if (bgrFrame.empty() || bgrFrame.type() != CV_8UC3 || options.sampleStride_px < 1) {
    return {};
  }
  const int stride = options.sampleStride_px;
  // BT.601 luma in thousandths, summed in integers: exact, so a frame at the dark threshold is
  // judged the same on every CPU (in floating point, FMA contraction on aarch64 put a grey 40
  // frame a rounding below 40).
  std::int64_t sum_milli = 0;
  long count = 0;
  for (int v = stride / 2; v < bgrFrame.rows; v += stride) {
    const std::uint8_t* row = bgrFrame.ptr<std::uint8_t>(v);
    for (int u = stride / 2; u < bgrFrame.cols; u += stride) {
      const std::uint8_t* p = row + 3 * static_cast<std::ptrdiff_t>(u);
      if ((p[0] | p[1] | p[2]) == 0) {
        continue;  // blank (e.g. outside the undistorted image)
      }
      sum_milli += 114 * p[0] + 587 * p[1] + 299 * p[2];
      ++count;
    }
  }
  return gainFor(static_cast<double>(sum_milli) / 1000.0, count, options);
}

ExposureGain estimateExposureYuv(const std::uint8_t* luma, std::size_t strideBytes, int width_px,
                                 int height_px, int pixelStride, const ExposureOptions& options) {
  if (luma == nullptr || width_px <= 0 || height_px <= 0 || pixelStride < 1 ||
      options.sampleStride_px < 1) {
    return {};
  }
  const int stride = options.sampleStride_px;
  std::int64_t sum = 0;  // integers, exact on every CPU (as the BGR estimate)
  long count = 0;
  for (int v = stride / 2; v < height_px; v += stride) {
    const std::uint8_t* row = luma + static_cast<std::size_t>(v) * strideBytes;
    for (int u = stride / 2; u < width_px; u += stride) {
      const int y = row[static_cast<std::ptrdiff_t>(u) * pixelStride];
      sum += std::max(0, y - 16);
      ++count;
    }
  }
  // Limited range (Y 16..235, as the camera path converts it: yuv_rows.hpp) to the full-range
  // luminance the BGR estimate sees, once on the sum.
  return gainFor(kLimitedRangeScale * static_cast<double>(sum), count, options);
}

}  // namespace vp::preprocess
