#include "platform/v4l2/yuv_to_bgr.hpp"

#include <algorithm>

namespace vp::platform::v4l2 {
namespace {

// BT.601 limited range: R = 1.164 (Y - 16) + 1.596 (V - 128),
// G = 1.164 (Y - 16) - 0.813 (V - 128) - 0.391 (U - 128), B = 1.164 (Y - 16) + 2.018 (U - 128);
// coefficients scaled by 2^20 and rounded.
constexpr int kShift = 20;
constexpr int kRound = 1 << (kShift - 1);
constexpr int kCy = 1220542;   // 1.164
constexpr int kCvr = 1673527;  // 1.596
constexpr int kCvg = -852492;  // -0.813
constexpr int kCug = -409993;  // -0.391
constexpr int kCub = 2116026;  // 2.018

struct Chroma {
  int r, g, b;
};

inline Chroma chroma(int u, int v) {
  const int uu = u - 128;
  const int vv = v - 128;
  return {kRound + kCvr * vv, kRound + kCvg * vv + kCug * uu, kRound + kCub * uu};
}

inline std::uint8_t clampToByte(int value) {
  return static_cast<std::uint8_t>(std::clamp(value, 0, 255));
}

inline void writePixel(int luma, const Chroma& c, std::uint8_t* bgr) {
  const int y = std::max(0, luma - 16) * kCy;
  bgr[0] = clampToByte((y + c.b) >> kShift);
  bgr[1] = clampToByte((y + c.g) >> kShift);
  bgr[2] = clampToByte((y + c.r) >> kShift);
}

bool fits(const cv::Mat& bgr, int width_px, int height_px) {
  return width_px > 0 && height_px > 0 && width_px % 2 == 0 && bgr.type() == CV_8UC3 &&
         bgr.cols == width_px && bgr.rows == height_px;
}

}  // namespace

bool yuyvToBgr(const std::uint8_t* yuyv, std::size_t strideBytes, int width_px, int height_px,
               cv::Mat& bgr) {
  if (!fits(bgr, width_px, height_px) || strideBytes < static_cast<std::size_t>(width_px) * 2) {
    return false;
  }
  for (int row = 0; row < height_px; ++row) {
    const std::uint8_t* in = yuyv + static_cast<std::size_t>(row) * strideBytes;
    std::uint8_t* out = bgr.ptr<std::uint8_t>(row);
    for (int col = 0; col < width_px; col += 2, in += 4, out += 6) {
      const Chroma c = chroma(in[1], in[3]);
      writePixel(in[0], c, out);
      writePixel(in[2], c, out + 3);
    }
  }
  return true;
}

bool nv12ToBgr(const std::uint8_t* yPlane, std::size_t yStrideBytes, const std::uint8_t* uvPlane,
               std::size_t uvStrideBytes, int width_px, int height_px, cv::Mat& bgr) {
  if (!fits(bgr, width_px, height_px) || height_px % 2 != 0 ||
      yStrideBytes < static_cast<std::size_t>(width_px) ||
      uvStrideBytes < static_cast<std::size_t>(width_px)) {
    return false;
  }
  for (int row = 0; row < height_px; row += 2) {
    const std::uint8_t* y0 = yPlane + static_cast<std::size_t>(row) * yStrideBytes;
    const std::uint8_t* y1 = y0 + yStrideBytes;
    const std::uint8_t* uv = uvPlane + static_cast<std::size_t>(row / 2) * uvStrideBytes;
    std::uint8_t* out0 = bgr.ptr<std::uint8_t>(row);
    std::uint8_t* out1 = bgr.ptr<std::uint8_t>(row + 1);
    for (int col = 0; col < width_px; col += 2) {
      const Chroma c = chroma(uv[col], uv[col + 1]);
      writePixel(y0[col], c, out0 + 3 * col);
      writePixel(y0[col + 1], c, out0 + 3 * col + 3);
      writePixel(y1[col], c, out1 + 3 * col);
      writePixel(y1[col + 1], c, out1 + 3 * col + 3);
    }
  }
  return true;
}

}  // namespace vp::platform::v4l2
