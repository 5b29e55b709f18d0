#include "preprocess/frame_remap.hpp"

#include <algorithm>
#include <cmath>

namespace vp::preprocess {

namespace {

// Source position for output pixels that must stay black (beyond the valid field): far enough
// outside the frame that no bilinear neighbour is inside (the value camera::Undistorter uses).
constexpr float kOutsideSource_px = -100.0F;
// Largest frame side the 16-bit source coordinates can address.
constexpr int kMaxFrameSide_px = 32000;
// Bilinear weights are products of two 5-bit fractions: they sum to 32 * 32.
constexpr int kWeightBits = 2 * kRemapFractionBits;
constexpr int kWeightRound = 1 << (kWeightBits - 1);

bool fail(std::string* why, const std::string& message) {
  if (why != nullptr) {
    *why = "frame remap: " + message;
  }
  return false;
}

}  // namespace

bool FrameRemap::init(const camera::CameraModel& input, const camera::Intrinsics& output,
                      std::string* why) {
  const camera::Intrinsics& in = input.intrinsics();
  if (in.width_px <= 0 || in.height_px <= 0) {
    return fail(why, "the input camera model is not initialised");
  }
  if (in.width_px > kMaxFrameSide_px || in.height_px > kMaxFrameSide_px) {
    return fail(why, "input frame " + std::to_string(in.width_px) + "x" +
                         std::to_string(in.height_px) + " exceeds the map's 16-bit coordinates");
  }
  if (output.width_px <= 0 || output.height_px <= 0 || !(output.fx_px > 0.0) ||
      !(output.fy_px > 0.0) || !std::isfinite(output.fx_px) || !std::isfinite(output.fy_px) ||
      !std::isfinite(output.cx_px) || !std::isfinite(output.cy_px)) {
    return fail(why,
                "output intrinsics need a size > 0, finite fx_px, fy_px > 0 and a finite "
                "principal point");
  }
  const std::size_t pixels =
      static_cast<std::size_t>(output.width_px) * static_cast<std::size_t>(output.height_px);
  sourceXY_.assign(2 * pixels, 0);
  sourceFrac_.assign(pixels, 0);
  const double maxIdealRadius2 = input.maxIdealRadius() * input.maxIdealRadius();
  // Beyond this every bilinear neighbour is outside the frame: clamping there keeps wildly
  // diverging lens models inside the 16-bit coordinates without changing the (black) result.
  const auto farOutside_px = static_cast<float>(std::max(in.width_px, in.height_px) + 100);
  std::size_t i = 0;
  for (int v = 0; v < output.height_px; ++v) {
    for (int u = 0; u < output.width_px; ++u, ++i) {
      const Eigen::Vector2d ideal((u - output.cx_px) / output.fx_px,
                                  (v - output.cy_px) / output.fy_px);
      float x = kOutsideSource_px;
      float y = kOutsideSource_px;
      if (ideal.squaredNorm() <= maxIdealRadius2) {
        const Eigen::Vector2d distorted = input.distortNormalized(ideal);
        const auto sx = static_cast<float>(in.cx_px + in.fx_px * distorted.x());
        const auto sy = static_cast<float>(in.cy_px + in.fy_px * distorted.y());
        if (std::isfinite(sx) && std::isfinite(sy)) {
          x = std::clamp(sx, kOutsideSource_px, farOutside_px);
          y = std::clamp(sy, kOutsideSource_px, farOutside_px);
        }
      }
      // cv::convertMaps(CV_32FC1 -> CV_16SC2): round to 1/32 px, split integer and fraction.
      const auto ix = static_cast<int>(std::lrint(x * kRemapFractionSteps));
      const auto iy = static_cast<int>(std::lrint(y * kRemapFractionSteps));
      sourceXY_[2 * i] = static_cast<std::int16_t>(ix >> kRemapFractionBits);
      sourceXY_[2 * i + 1] = static_cast<std::int16_t>(iy >> kRemapFractionBits);
      sourceFrac_[i] =
          static_cast<std::uint16_t>(((iy & (kRemapFractionSteps - 1)) << kRemapFractionBits) |
                                     (ix & (kRemapFractionSteps - 1)));
    }
  }
  input_ = in;
  output_ = output;
  return true;
}

void FrameRemap::applyRows(const cv::Mat& src, cv::Mat& dst, int rowBegin, int rowEnd) const {
  const int width = output_.width_px;
  const int srcWidth = input_.width_px;
  const int srcHeight = input_.height_px;
  const std::size_t srcStep = src.step[0];
  const std::uint8_t* srcData = src.data;
  for (int v = rowBegin; v < rowEnd; ++v) {
    std::uint8_t* out = dst.ptr<std::uint8_t>(v);
    const std::size_t rowStart = static_cast<std::size_t>(v) * static_cast<std::size_t>(width);
    const std::int16_t* xy = sourceXY_.data() + 2 * rowStart;
    const std::uint16_t* frac = sourceFrac_.data() + rowStart;
    for (int u = 0; u < width; ++u, out += 3) {
      const int sx = xy[2 * u];
      const int sy = xy[2 * u + 1];
      const int fx = frac[u] & (kRemapFractionSteps - 1);
      const int fy = frac[u] >> kRemapFractionBits;
      const int w00 = (kRemapFractionSteps - fx) * (kRemapFractionSteps - fy);
      const int w01 = fx * (kRemapFractionSteps - fy);
      const int w10 = (kRemapFractionSteps - fx) * fy;
      const int w11 = fx * fy;
      if (static_cast<unsigned>(sx) < static_cast<unsigned>(srcWidth - 1) &&
          static_cast<unsigned>(sy) < static_cast<unsigned>(srcHeight - 1)) {
        const std::uint8_t* p0 =
            srcData + static_cast<std::size_t>(sy) * srcStep + static_cast<std::size_t>(sx) * 3;
        const std::uint8_t* p1 = p0 + srcStep;
        for (int c = 0; c < 3; ++c) {
          const int sum = p0[c] * w00 + p0[c + 3] * w01 + p1[c] * w10 + p1[c + 3] * w11;
          out[c] = static_cast<std::uint8_t>((sum + kWeightRound) >> kWeightBits);
        }
        continue;
      }
      // Border: neighbours outside the frame count as black (cv::BORDER_CONSTANT, value 0).
      if (sx >= srcWidth || sx + 1 < 0 || sy >= srcHeight || sy + 1 < 0) {
        out[0] = out[1] = out[2] = 0;
        continue;
      }
      const bool x0In = sx >= 0;
      const bool x1In = sx + 1 < srcWidth;
      const bool y0In = sy >= 0;
      const bool y1In = sy + 1 < srcHeight;
      for (int c = 0; c < 3; ++c) {
        auto at = [&](int x, int y) {
          return static_cast<int>(
              srcData[static_cast<std::size_t>(y) * srcStep + static_cast<std::size_t>(x) * 3 + c]);
        };
        const int sum = (x0In && y0In ? at(sx, sy) * w00 : 0) +
                        (x1In && y0In ? at(sx + 1, sy) * w01 : 0) +
                        (x0In && y1In ? at(sx, sy + 1) * w10 : 0) +
                        (x1In && y1In ? at(sx + 1, sy + 1) * w11 : 0);
        out[c] = static_cast<std::uint8_t>((sum + kWeightRound) >> kWeightBits);
      }
    }
  }
}

bool FrameRemap::apply(const cv::Mat& src, cv::Mat& dst) const {
  if (!initialised() || src.empty() || src.type() != CV_8UC3 || dst.type() != CV_8UC3) {
    return false;
  }
  if (src.size() != inputSize() || dst.size() != outputSize()) {
    return false;
  }
  if (src.datastart < dst.dataend && dst.datastart < src.dataend) {
    return false;  // remapping in place would read already written output
  }
  applyRows(src, dst, 0, output_.height_px);
  return true;
}

}  // namespace vp::preprocess
