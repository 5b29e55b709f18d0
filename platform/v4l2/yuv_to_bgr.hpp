// platform/v4l2/yuv_to_bgr: the camera's YUV layouts into the pipeline's BGR8 frames, in place.
//
// Contract: pure, allocation-free, single-threaded; writes into a caller-owned CV_8UC3 image
// of exactly the given size (never reallocates it) and returns false, writing nothing, when
// the image or the dimensions do not fit (odd width, odd height for NV12). Colour: the row
// conversion of src/perception/preprocess/yuv_rows.hpp (ITU-R BT.601 limited range, 20-bit
// fixed point, = cv::cvtColor; the preprocessor's direct camera path uses the same rows).
// Source strides are in bytes (V4L2 bytesperline), so padded rows are handled.
#pragma once

#include <cstddef>
#include <cstdint>

#include <opencv2/core.hpp>

namespace vp::platform::v4l2 {

// YUYV 4:2:2 (V4L2_PIX_FMT_YUYV, "YUY2"): Y0 U Y1 V per pixel pair.
bool yuyvToBgr(const std::uint8_t* yuyv, std::size_t strideBytes, int width_px, int height_px,
               cv::Mat& bgr);

// NV12 4:2:0 (V4L2_PIX_FMT_NV12): a Y plane, then an interleaved U V plane at half resolution.
bool nv12ToBgr(const std::uint8_t* yPlane, std::size_t yStrideBytes, const std::uint8_t* uvPlane,
               std::size_t uvStrideBytes, int width_px, int height_px, cv::Mat& bgr);

}  // namespace vp::platform::v4l2
