// tests/support/pinhole_camera: an undistorted camera of a given image size with the principal
// point at the image centre, for tests that need a CameraModel but not its lens.
#pragma once

#include <gtest/gtest.h>

#include "camera/camera_model.hpp"

namespace vp::test {

inline camera::CameraModel pinholeCamera(int width_px, int height_px, double focal_px = 2300.0) {
  camera::Intrinsics k;
  k.width_px = width_px;
  k.height_px = height_px;
  k.fx_px = focal_px;
  k.fy_px = focal_px;
  k.cx_px = 0.5 * width_px - 0.5;
  k.cy_px = 0.5 * height_px - 0.5;
  camera::CameraModel camera;
  EXPECT_TRUE(camera.init(k, camera::Distortion{}));
  return camera;
}

}  // namespace vp::test
