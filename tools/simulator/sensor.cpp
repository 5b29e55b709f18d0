#include "sensor.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include <opencv2/imgproc.hpp>

namespace vp::sim {

namespace {

// Approximately standard normal from a hash: the sum of four uniform bytes (Irwin-Hall,
// variance 4 (256^2 - 1) / 12), a tenth of the cost of Box-Muller's log and cos; sensor noise
// needs neither exact tails nor more than 1021 levels.
float gaussianFromHash(std::uint32_t key, std::uint32_t index) {
  const std::uint32_t h = hashCombine(key, index);
  const auto sum =
      static_cast<float>((h & 0xFFU) + ((h >> 8U) & 0xFFU) + ((h >> 16U) & 0xFFU) + (h >> 24U));
  constexpr float kInvSigma = 1.0F / 147.80054F;
  return (sum - 510.0F) * kInvSigma;
}

// Tone curve (gamma 1/2.2, contrast about mid grey, soft shoulder, 8-bit scale) tabulated
// over sqrt(linear) in [0, kToneRange]: pow and tanh per channel were a tenth of a frame.
// Steps of sqrt are fine near black, where the gamma curve is steep.
constexpr int kToneSteps = 8192;
constexpr float kToneRange = 2.0F;

std::vector<float> toneTable(double contrast) {
  std::vector<float> t(kToneSteps + 1);
  for (int i = 0; i <= kToneSteps; ++i) {
    const double r = kToneRange * i / kToneSteps;
    double g = std::pow(r * r, 1.0 / 2.2);
    g = 0.5 + contrast * (g - 0.5);
    // Soft shoulder instead of a hard clip, as camera tone curves do.
    if (g > 0.85) {
      g = 0.85 + 0.15 * std::tanh((g - 0.85) / 0.15);
    }
    t[static_cast<std::size_t>(i)] = static_cast<float>(std::clamp(g, 0.0, 1.0) * 255.0);
  }
  return t;
}

}  // namespace

SensorSpec drawSensor(Rng& rng) {
  SensorSpec s;
  s.vignetting = rng.uniform(0.05, 0.35);
  // Colour temperature cast: warm (more red) or cool (more blue), plus a small green shift.
  const double temperature = rng.normal(0.0, 0.07);
  s.whiteBalance =
      Eigen::Vector3d(1.0 + temperature, 1.0 + rng.normal(0.0, 0.02), 1.0 - temperature);
  s.exposureTargetGrey = rng.uniform(0.13, 0.26);
  s.exposureDrift = rng.uniform(0.002, 0.012);
  s.exposureStepChance = rng.uniform(0.0, 0.03);
  s.fullWellScale = rng.uniform(1500.0, 8000.0);
  s.readNoise = rng.uniform(0.001, 0.005);
  s.blurSigma_px = rng.uniform(0.35, 0.9);
  s.exposureTimeS = rng.uniform(0.0005, 0.004);
  s.contrast = rng.uniform(0.9, 1.15);
  s.saturation = rng.uniform(0.8, 1.15);
  return s;
}

bool makeCanvas(const camera::CameraModel& camera, int supersampling, Canvas* canvas,
                std::string* why) {
  const auto& k = camera.intrinsics();
  double minU = 1e18, maxU = -1e18, minV = 1e18, maxV = -1e18;
  const auto visit = [&](double u, double v) {
    const auto ideal = camera.undistortPixel({u, v});
    if (!ideal) {
      return false;
    }
    minU = std::min(minU, ideal->x());
    maxU = std::max(maxU, ideal->x());
    minV = std::min(minV, ideal->y());
    maxV = std::max(maxV, ideal->y());
    return true;
  };
  const double w = k.width_px - 1;
  const double h = k.height_px - 1;
  for (int i = 0; i <= 64; ++i) {
    const double t = i / 64.0;
    if (!visit(t * w - 0.5, -0.5) || !visit(t * w - 0.5, h + 0.5) || !visit(-0.5, t * h - 0.5) ||
        !visit(w + 0.5, t * h - 0.5)) {
      if (why != nullptr) {
        *why = "lens model: the image border lies outside the valid field";
      }
      return false;
    }
  }
  canvas->supersampling = supersampling;
  canvas->offsetX = static_cast<int>(std::ceil(-minU)) + 3;
  canvas->offsetY = static_cast<int>(std::ceil(-minV)) + 3;
  canvas->width = static_cast<int>(std::ceil(maxU)) + canvas->offsetX + 4;
  canvas->height = static_cast<int>(std::ceil(maxV)) + canvas->offsetY + 4;
  return true;
}

void Sensor::init(const camera::CameraModel& camera, const Canvas& canvas, const SensorSpec& spec) {
  canvas_ = canvas;
  spec_ = spec;
  const auto& k = camera.intrinsics();
  width_ = k.width_px;
  height_ = k.height_px;
  mapX_.create(height_, width_, CV_32FC1);
  mapY_.create(height_, width_, CV_32FC1);
  vignette_.create(height_, width_, CV_32FC1);
  const double halfDiag = std::hypot(0.5 * width_, 0.5 * height_);
  for (int v = 0; v < height_; ++v) {
    for (int u = 0; u < width_; ++u) {
      const auto ideal = camera.undistortPixel({static_cast<double>(u), static_cast<double>(v)});
      const Eigen::Vector2d p = ideal ? *ideal : Eigen::Vector2d(u, v);
      mapX_.at<float>(v, u) = static_cast<float>(p.x() + canvas.offsetX);
      mapY_.at<float>(v, u) = static_cast<float>(p.y() + canvas.offsetY);
      const double r = std::hypot(u - k.cx_px, v - k.cy_px) / halfDiag;
      // cos^4-like falloff scaled so the corner loses `vignetting`.
      const double c = 1.0 / (1.0 + r * r * (std::pow(1.0 - spec.vignetting, -0.5) - 1.0));
      vignette_.at<float>(v, u) = static_cast<float>(c * c);
    }
  }
  tone_ = toneTable(spec.contrast);
  inImage_.assign(static_cast<std::size_t>(canvas.width) * static_cast<std::size_t>(canvas.height),
                  0);
  for (int y = 0; y < canvas.height; ++y) {
    for (int x = 0; x < canvas.width; ++x) {
      const Eigen::Vector2d d = camera.distortPixel(
          {static_cast<double>(x - canvas.offsetX), static_cast<double>(y - canvas.offsetY)});
      inImage_[static_cast<std::size_t>(y) * static_cast<std::size_t>(canvas.width) +
               static_cast<std::size_t>(x)] = camera.inImage(d) ? 1 : 0;
    }
  }
}

std::vector<std::uint8_t> Sensor::neededCanvas(int margin_px) const {
  // Dilation of inImage_ by a square of margin_px (separable: rows, then columns).
  const int w = canvas_.width;
  const int h = canvas_.height;
  std::vector<std::uint8_t> rows(inImage_.size(), 0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (inImage_[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) +
                   static_cast<std::size_t>(x)] != 0) {
        for (int i = std::max(0, x - margin_px); i <= std::min(w - 1, x + margin_px); ++i) {
          rows[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) +
               static_cast<std::size_t>(i)] = 1;
        }
      }
    }
  }
  std::vector<std::uint8_t> out(inImage_.size(), 0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (rows[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) +
               static_cast<std::size_t>(x)] != 0) {
        for (int j = std::max(0, y - margin_px); j <= std::min(h - 1, y + margin_px); ++j) {
          out[static_cast<std::size_t>(j) * static_cast<std::size_t>(w) +
              static_cast<std::size_t>(x)] = 1;
        }
      }
    }
  }
  return out;
}

double Sensor::meanLevel(const cv::Mat& linear) const {
  double sum = 0.0;
  std::size_t n = 0;
  for (int y = 0; y < linear.rows; y += 4) {
    const auto* row = linear.ptr<cv::Vec3f>(y);
    for (int x = 0; x < linear.cols; x += 4) {
      if (canvasInImage(x, y)) {
        sum += 0.2126 * static_cast<double>(row[x][0]) + 0.7152 * static_cast<double>(row[x][1]) +
               0.0722 * static_cast<double>(row[x][2]);
        ++n;
      }
    }
  }
  return n > 0 ? sum / static_cast<double>(n) : 0.2;
}

void Sensor::outputIds(const Renderer& renderer, cv::Mat& ids) const {
  ids.create(height_, width_, CV_32SC1);
  const SampleBuffers& s = renderer.samples();
  const int ss = canvas_.supersampling;
  for (int v = 0; v < height_; ++v) {
    for (int u = 0; u < width_; ++u) {
      // Canvas coordinate -> nearest sample (samples at canvas x + (i + 0.5) / S - 0.5).
      const double sx = (static_cast<double>(mapX_.at<float>(v, u)) + 0.5) * ss - 0.5;
      const double sy = (static_cast<double>(mapY_.at<float>(v, u)) + 0.5) * ss - 0.5;
      const int ix = static_cast<int>(std::lround(sx));
      const int iy = static_cast<int>(std::lround(sy));
      int id = 0;
      if (ix >= 0 && iy >= 0 && ix < s.width && iy < s.height) {
        id = renderer.objectAt(static_cast<std::size_t>(iy) * static_cast<std::size_t>(s.width) +
                               static_cast<std::size_t>(ix));
      }
      ids.at<std::int32_t>(v, u) = id;
    }
  }
}

void Sensor::develop(const cv::Mat& linear, const cv::Mat& ids,
                     const std::vector<MotionStreak>& streaks, double exposure,
                     std::uint32_t noiseKey, cv::Mat& bgr) const {
  cv::Mat img;
  cv::remap(linear, img, mapX_, mapY_, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  // Motion blur: pixels of a moving vehicle (and the background its streak passes over)
  // average the sharp image along the vehicle's motion during the exposure.
  if (!streaks.empty()) {
    const cv::Mat sharp = img.clone();
    // Pixel bounds of every streaking vehicle, in one pass over the ids.
    std::vector<std::array<int, 4>> bounds(streaks.size(), {width_, -1, height_, -1});
    std::vector<std::pair<int, std::size_t>> order;
    for (std::size_t i = 0; i < streaks.size(); ++i) {
      order.emplace_back(streaks[i].trackId, i);
    }
    std::sort(order.begin(), order.end());
    for (int v = 0; v < height_; ++v) {
      const auto* row = ids.ptr<std::int32_t>(v);
      for (int u = 0; u < width_; ++u) {
        if (row[u] <= 0) {
          continue;
        }
        auto it =
            std::lower_bound(order.begin(), order.end(), std::make_pair(row[u], std::size_t{0}));
        for (; it != order.end() && it->first == row[u]; ++it) {
          std::array<int, 4>& b = bounds[it->second];
          b[0] = std::min(b[0], u);
          b[1] = std::max(b[1], u);
          b[2] = std::min(b[2], v);
          b[3] = std::max(b[3], v);
        }
      }
    }
    for (std::size_t si = 0; si < streaks.size(); ++si) {
      const MotionStreak& m = streaks[si];
      const double len = m.motion_px.norm();
      if (len < 0.3) {
        continue;
      }
      const int taps = std::max(3, static_cast<int>(std::ceil(len * 2.0)) | 1);
      const int minX = bounds[si][0];
      const int maxX = bounds[si][1];
      const int minY = bounds[si][2];
      const int maxY = bounds[si][3];
      if (maxX < 0) {
        continue;
      }
      const int pad = static_cast<int>(std::ceil(len)) + 1;
      for (int v = std::max(0, minY - pad); v <= std::min(height_ - 1, maxY + pad); ++v) {
        for (int u = std::max(0, minX - pad); u <= std::min(width_ - 1, maxX + pad); ++u) {
          bool touches = false;
          for (int t = 0; t < taps && !touches; ++t) {
            const double f = (t + 0.5) / taps - 0.5;
            const int x = static_cast<int>(std::lround(u - f * m.motion_px.x()));
            const int y = static_cast<int>(std::lround(v - f * m.motion_px.y()));
            touches = x >= 0 && y >= 0 && x < width_ && y < height_ &&
                      ids.at<std::int32_t>(y, x) == m.trackId;
          }
          if (!touches) {
            continue;
          }
          cv::Vec3f sum(0, 0, 0);
          for (int t = 0; t < taps; ++t) {
            const double f = (t + 0.5) / taps - 0.5;
            const float x =
                static_cast<float>(std::clamp(u + f * m.motion_px.x(), 0.0, width_ - 1.0));
            const float y =
                static_cast<float>(std::clamp(v + f * m.motion_px.y(), 0.0, height_ - 1.0));
            sum += sharp.at<cv::Vec3f>(static_cast<int>(std::lround(y)),
                                       static_cast<int>(std::lround(x)));
          }
          img.at<cv::Vec3f>(v, u) = sum * (1.0F / static_cast<float>(taps));
        }
      }
    }
  }
  cv::GaussianBlur(img, img, cv::Size(0, 0), spec_.blurSigma_px, spec_.blurSigma_px,
                   cv::BORDER_REPLICATE);
  bgr.create(height_, width_, CV_8UC3);
  const auto gains = spec_.whiteBalance.cast<float>();
  const auto saturation = static_cast<float>(spec_.saturation);
  const auto shot = static_cast<float>(1.0 / spec_.fullWellScale);
  const auto read = static_cast<float>(spec_.readNoise);
  const std::vector<float>& tone = tone_;
  constexpr float kToneScale = kToneSteps / kToneRange;
  for (int v = 0; v < height_; ++v) {
    const auto* in = img.ptr<cv::Vec3f>(v);
    const auto* vig = vignette_.ptr<float>(v);
    auto* out = bgr.ptr<cv::Vec3b>(v);
    for (int u = 0; u < width_; ++u) {
      float c[3];
      const float k = static_cast<float>(exposure) * vig[u];
      for (int ch = 0; ch < 3; ++ch) {
        float s = std::max(0.0F, in[u][ch] * k * gains[ch]);
        const float sigma = std::sqrt(s * shot + read * read);
        const auto index = static_cast<std::uint32_t>((v * width_ + u) * 3 + ch);
        s += sigma * gaussianFromHash(noiseKey, index);
        c[ch] = std::max(0.0F, s);
      }
      // Saturation in linear light, then the tone curve.
      const float y = 0.2126F * c[0] + 0.7152F * c[1] + 0.0722F * c[2];
      std::uint8_t q[3];
      for (int ch = 0; ch < 3; ++ch) {
        const float lin = std::max(0.0F, y + saturation * (c[ch] - y));
        const float i = std::min(std::sqrt(lin) * kToneScale, static_cast<float>(kToneSteps));
        q[ch] = static_cast<std::uint8_t>(tone[static_cast<std::size_t>(i + 0.5F)] + 0.5F);
      }
      out[u] = cv::Vec3b(q[2], q[1], q[0]);
    }
  }
}

}  // namespace vp::sim
