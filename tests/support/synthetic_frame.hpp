// tests/support/synthetic_frame: a grey road-like BGR frame with car-sized bright and dark
// rotated rectangles, for tests and benchmarks that need image structure of the right scale
// but no realism. Deterministic for a seed. Header-only (OpenCV core + imgproc).
#pragma once

#include <array>
#include <cstdint>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace vp::test {

inline cv::Mat syntheticCarFrame(int width_px, int height_px, std::uint64_t seed, int cars) {
  cv::Mat frame(height_px, width_px, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(frame, cv::RNG::NORMAL, 110, 12);
  for (int i = 0; i < cars; ++i) {
    const cv::RotatedRect car({static_cast<float>(rng.uniform(100, width_px - 92)),
                               static_cast<float>(rng.uniform(100, height_px - 98))},
                              {150.0F, 60.0F}, static_cast<float>(rng.uniform(0, 360)));
    cv::Point2f corners[4];
    car.points(corners);
    std::array<cv::Point, 4> polygon;
    for (int k = 0; k < 4; ++k) {
      polygon[k] = corners[k];
    }
    const int shade = rng.uniform(0, 2) == 0 ? 30 : 230;
    cv::fillConvexPoly(frame, polygon.data(), 4, cv::Scalar(shade, shade, shade + 10));
  }
  return frame;
}

}  // namespace vp::test
