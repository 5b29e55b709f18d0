#include "platform/v4l2/yuv_to_bgr.hpp"

#include "preprocess/yuv_rows.hpp"

namespace vp::platform::v4l2 {
namespace {

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
    preprocess::yuyvRowToBgr(yuyv + static_cast<std::size_t>(row) * strideBytes, width_px,
                             bgr.ptr<std::uint8_t>(row));
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
  for (int row = 0; row < height_px; ++row) {
    preprocess::nv12RowToBgr(yPlane + static_cast<std::size_t>(row) * yStrideBytes,
                             uvPlane + static_cast<std::size_t>(row / 2) * uvStrideBytes, width_px,
                             bgr.ptr<std::uint8_t>(row));
  }
  return true;
}

}  // namespace vp::platform::v4l2
