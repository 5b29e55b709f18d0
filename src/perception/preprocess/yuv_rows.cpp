#include "preprocess/yuv_rows.hpp"

#include <algorithm>

namespace vp::preprocess {

namespace {

// The coefficients scaled by 2^20 and rounded.
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

}  // namespace

void yuyvRowToBgr(const std::uint8_t* yuyv, int width_px, std::uint8_t* bgr) {
  for (int col = 0; col < width_px; col += 2, yuyv += 4, bgr += 6) {
    const Chroma c = chroma(yuyv[1], yuyv[3]);
    writePixel(yuyv[0], c, bgr);
    writePixel(yuyv[2], c, bgr + 3);
  }
}

void nv12RowToBgr(const std::uint8_t* y, const std::uint8_t* uv, int width_px, std::uint8_t* bgr) {
  for (int col = 0; col < width_px; col += 2, bgr += 6) {
    const Chroma c = chroma(uv[col], uv[col + 1]);
    writePixel(y[col], c, bgr);
    writePixel(y[col + 1], c, bgr + 3);
  }
}

}  // namespace vp::preprocess
