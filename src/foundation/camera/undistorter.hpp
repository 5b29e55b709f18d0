// camera/undistorter: removes lens distortion from whole images at frame rate.
//
// Contract: init() builds the remap tables once (OpenCV's initUndistortRectifyMap for
// Brown-Conrady, our own table for the equivalent spherical model) for an output camera
// whose intrinsics the caller chooses (by default the input's). apply() remaps a frame
// into a destination image that the caller allocated once with outputSize() and the
// source's type; it performs no heap allocation when the destination already has that
// size and type. Output pixels whose source falls outside the frame are black.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "camera/camera_model.hpp"

namespace vp::camera {

class Undistorter {
 public:
  Undistorter() = default;

  // Builds the maps from the distorted input camera to the ideal pinhole output camera.
  bool init(const CameraModel& input, const Intrinsics& output, std::string* why = nullptr);
  bool init(const CameraModel& input, std::string* why = nullptr);  // output = input's

  cv::Size outputSize() const { return {output_.width_px, output_.height_px}; }
  const Intrinsics& outputIntrinsics() const { return output_; }

  // src: a frame of the input camera's size; dst: preallocated outputSize(), src.type().
  // Returns false (and does nothing) on a size or type mismatch.
  bool apply(const cv::Mat& src, cv::Mat& dst) const;

 private:
  Intrinsics input_{};
  Intrinsics output_{};
  cv::Mat mapX_;  // CV_16SC2 fixed-point maps: fastest remap path
  cv::Mat mapY_;  // CV_16UC1 interpolation table
};

}  // namespace vp::camera
