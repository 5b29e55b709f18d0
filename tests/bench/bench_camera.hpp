// tests/bench/bench_camera: the camera the perception benchmarks share — a 2592 x 2048 frame
// (the product's camera) with a mild Brown-Conrady distortion, so the undistortion path costs
// what it does on the drone.
#pragma once

#include "camera/camera_model.hpp"

namespace vp::bench {

constexpr int kFrameWidth_px = 2592;
constexpr int kFrameHeight_px = 2048;

inline camera::CameraModel benchCamera() {
  camera::Intrinsics k;
  k.width_px = kFrameWidth_px;
  k.height_px = kFrameHeight_px;
  k.fx_px = 3000.0;
  k.fy_px = 3000.0;
  k.cx_px = 1295.5;
  k.cy_px = 1023.5;
  camera::Distortion d;
  d.model = camera::LensModel::BrownConrady;
  d.k1 = -0.1;
  d.k2 = 0.03;
  camera::CameraModel model;
  model.init(k, d);
  return model;
}

}  // namespace vp::bench
