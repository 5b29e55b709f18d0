// simulator/sensor: from the renderer's ideal linear-light canvas to the camera's image.
//
// Contract: init() precomputes, for every output pixel, where it comes from in the ideal
// canvas (inverse remap through the lens model: output pixel -> CameraModel::undistortPixel
// -> ideal pixel -> bilinear sample), so the image is distorted exactly as the recorded
// camera model describes. develop() then applies, in this order: motion blur of moving
// vehicles (a streak along each vehicle's image motion during the exposure), optical blur
// (Gaussian PSF), vignetting (cos^4-like radial falloff), exposure (auto exposure with a slow
// drift and occasional steps, per frame), white-balance cast (per-sequence channel gains),
// sensor noise (shot noise with variance proportional to the signal, plus read noise;
// counter-based hashing keyed per frame, so it is independent of threads), the tone curve
// (sRGB-like gamma with a per-sequence contrast and saturation), 8-bit quantisation, BGR.
// JPEG compression happens when the frame is written.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "camera/camera_model.hpp"
#include "renderer.hpp"
#include "sim_random.hpp"

namespace vp::sim {

struct SensorSpec {
  double vignetting = 0.2;                // brightness loss at the image corner
  Eigen::Vector3d whiteBalance{1, 1, 1};  // channel gains (R, G, B): the colour cast
  double exposureTargetGrey = 0.2;        // auto exposure: mean linear level it aims for
  double exposureDrift = 0.01;            // per-frame log-exposure random walk (sigma)
  double exposureStepChance = 0.02;       // chance per frame of an auto-exposure step
  double fullWellScale = 4000.0;          // shot noise: variance = signal / fullWellScale
  double readNoise = 0.003;               // sigma, linear units
  double blurSigma_px = 0.6;              // optics PSF
  double exposureTimeS = 0.002;           // for motion blur
  double contrast = 1.0;
  double saturation = 1.0;
};

SensorSpec drawSensor(Rng& rng);

// Canvas covering the ideal (pinhole) positions of all output pixels, with a small margin.
bool makeCanvas(const camera::CameraModel& camera, int supersampling, Canvas* canvas,
                std::string* why);

// A moving vehicle's image motion during the exposure.
struct MotionStreak {
  int trackId = 0;
  Eigen::Vector2d motion_px{0, 0};  // output pixels travelled during the exposure
};

class Sensor {
 public:
  void init(const camera::CameraModel& camera, const Canvas& canvas, const SensorSpec& spec);

  // linear: the renderer's canvas (CV_32FC3 RGB); ids: output object ids (CV_32SC1);
  // exposure: multiplier of this frame; noiseKey: drawn per frame from the Rng.
  void develop(const cv::Mat& linear, const cv::Mat& ids, const std::vector<MotionStreak>& streaks,
               double exposure, std::uint32_t noiseKey, cv::Mat& bgr) const;

  // Output object ids: the object of the sample nearest to each output pixel's ideal position.
  void outputIds(const Renderer& renderer, cv::Mat& ids) const;

  // True when canvas pixel (x, y) (1x grid) maps into the output image.
  bool canvasInImage(int x, int y) const {
    if (x < 0 || y < 0 || x >= canvas_.width || y >= canvas_.height) {
      return false;
    }
    return inImage_[static_cast<std::size_t>(y) * static_cast<std::size_t>(canvas_.width) +
                    static_cast<std::size_t>(x)] != 0;
  }
  const Canvas& canvas() const { return canvas_; }
  const SensorSpec& spec() const { return spec_; }
  // Canvas pixels within margin_px of one that maps into the image: the only ones develop()
  // reads (the canvas is the bounding box of the lens's ideal field, larger than needed).
  std::vector<std::uint8_t> neededCanvas(int margin_px) const;
  // Mean linear level of the canvas part that lands in the image (for auto exposure).
  double meanLevel(const cv::Mat& linear) const;

 private:
  Canvas canvas_{};
  SensorSpec spec_{};
  int width_ = 0;
  int height_ = 0;
  cv::Mat mapX_;  // CV_32FC1, canvas x of each output pixel
  cv::Mat mapY_;
  cv::Mat vignette_;  // CV_32FC1
  std::vector<std::uint8_t> inImage_;
  std::vector<float> tone_;  // 8-bit output (unrounded) over sqrt(linear), see toneTable()
};

}  // namespace vp::sim
