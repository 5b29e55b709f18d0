// preprocess/exposure: a gain for under-exposed frames, so that a frame the camera's automatic
// exposure has not caught up with (the first frames of a recording, a sudden cloud, a drone
// turning towards the sun) reaches the brightness the detector was trained on.
//
// Contract: estimateExposure() reads a regular subsample of an 8-bit BGR frame (every
// sampleStride_px-th pixel in both axes; pure black pixels, e.g. the blank corners of an
// undistorted frame, are skipped), takes the mean BT.601 luminance of the samples and, when it
// is below darkMeanLuma, returns the gain targetMeanLuma / mean clamped to [1, maxGain]; any
// other frame gets gain 1 and is left as it is (the normally exposed frames the detector was
// tuned on are never changed). estimateExposureYuv() does the same on the Y bytes of a YUYV or
// NV12 frame, limited range (Y 16..235) mapped to full range as the camera path's conversion
// does; no sample is skipped there (that path has no blank corners). Both are pure functions of the
// pixels: no allocation, no state. The gain is applied by the preprocessor as a white-balance gain
// equal on all channels (saturate(round(v * gain))).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

namespace vp::preprocess {

// config: perception.exposure_* (docs/configuration.md).
struct ExposureOptions {
  bool enabled = true;
  // Frames darker than this mean luminance (8-bit) get a gain. 40: the darkest frames of the
  // simulated and real training sets have means of 89 and 112, so none of them is changed.
  double darkMeanLuma = 40.0;     // [0, 255]
  double targetMeanLuma = 100.0;  // the gain brings the mean here, [darkMeanLuma, 255]
  double maxGain = 8.0;           // [1, 16]: more would mostly amplify noise and compression
  int sampleStride_px = 8;        // [1, 64]
};

// Checks ranges; false with a message naming the key (exposure_*) otherwise.
bool validate(const ExposureOptions& options, std::string* why);

struct ExposureGain {
  float gain = 1.0F;      // 1: the frame is left as it is
  float meanLuma = 0.0F;  // of the samples (8-bit); 0 when no sample was usable
  bool applied = false;   // gain > 1
};

ExposureGain estimateExposure(const cv::Mat& bgrFrame, const ExposureOptions& options);
// luma: the first Y byte of the frame; pixelStride 2 for YUYV (Y at even bytes), 1 for
// NV12's Y plane.
ExposureGain estimateExposureYuv(const std::uint8_t* luma, std::size_t strideBytes, int width_px,
                                 int height_px, int pixelStride, const ExposureOptions& options);

}  // namespace vp::preprocess
