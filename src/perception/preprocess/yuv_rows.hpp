// preprocess/yuv_rows: one row of the camera's YUV layouts into BGR8, the conversion shared by
// the V4L2 capture (platform/v4l2/yuv_to_bgr: whole frames) and the preprocessor's direct
// camera path (rows converted inside the resize sweep, no full-size BGR frame).
//
// Contract: ITU-R BT.601 limited range ("studio swing", Y 16..235), the convention of UVC/V4L2
// cameras that report no colorimetry and of OpenCV's COLOR_YUV2BGR_*, in 20-bit fixed point so
// that the result matches cv::cvtColor (the tests compare them): R = 1.164 (Y - 16) + 1.596
// (V - 128), G = 1.164 (Y - 16) - 0.813 (V - 128) - 0.391 (U - 128), B = 1.164 (Y - 16) +
// 2.018 (U - 128), saturated to 0..255; one U, V pair serves two neighbouring pixels (and,
// in NV12, two rows). width_px is even. Pure, allocation-free.
#pragma once

#include <cstdint>

namespace vp::preprocess {

// YUYV 4:2:2 (V4L2_PIX_FMT_YUYV, "YUY2"): Y0 U Y1 V per pixel pair; 2 x width_px bytes in.
void yuyvRowToBgr(const std::uint8_t* yuyv, int width_px, std::uint8_t* bgr);

// NV12 4:2:0 (V4L2_PIX_FMT_NV12): one row of the Y plane and the UV row (U V interleaved, one
// pair per two pixels) that serves it.
void nv12RowToBgr(const std::uint8_t* y, const std::uint8_t* uv, int width_px, std::uint8_t* bgr);

}  // namespace vp::preprocess
