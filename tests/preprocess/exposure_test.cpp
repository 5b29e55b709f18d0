// Exposure: the gain for under-exposed frames (preprocess/exposure.hpp) and its place in the
// Preprocessor: dark frames are brightened in the working image (and in the owned
// full-resolution frame when white balance or undistortion writes one; otherwise the crops get
// the gain through frameGain), normally exposed frames are not touched, nothing is allocated.
#include "preprocess/exposure.hpp"

#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "alloc_counter.hpp"
#include "pinhole_camera.hpp"
#include "preprocess/preprocessor.hpp"
#include "preprocess/white_balance.hpp"

namespace vp::preprocess {
namespace {

constexpr int kWidth_px = 2592;
constexpr int kHeight_px = 2048;

cv::Mat grey(int value, int width = 640, int height = 480) {
  return cv::Mat(height, width, CV_8UC3, cv::Scalar::all(value));
}

// A textured road-like frame whose mean luminance is about `mean`.
cv::Mat texturedFrame(double mean, std::uint64_t seed) {
  cv::Mat frame(kHeight_px, kWidth_px, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(frame, cv::RNG::UNIFORM, 0.4 * mean, 1.6 * mean);
  return frame;
}

camera::CameraModel pinhole() {
  return test::pinholeCamera(kWidth_px, kHeight_px);
}

TEST(Exposure, DarkFramesGetTheGainToTheTargetMean) {
  const ExposureOptions options;  // dark below 40, target 100, gain at most 8
  const ExposureGain dark = estimateExposure(grey(20), options);
  EXPECT_FLOAT_EQ(dark.meanLuma, 20.0F);
  EXPECT_FLOAT_EQ(dark.gain, 5.0F);
  EXPECT_TRUE(dark.applied);
  // Nearly black: the gain stops at maxGain.
  const ExposureGain black = estimateExposure(grey(3), options);
  EXPECT_FLOAT_EQ(black.gain, 8.0F);
  EXPECT_FLOAT_EQ(estimateExposure(grey(0), options).gain, 1.0F) << "no usable sample";
}

TEST(Exposure, NormallyExposedOrDisabledFramesKeepGainOne) {
  ExposureOptions options;
  for (const int value : {40, 90, 200}) {
    const ExposureGain normal = estimateExposure(grey(value), options);
    EXPECT_FLOAT_EQ(normal.gain, 1.0F) << value;
    EXPECT_FALSE(normal.applied) << value;
    EXPECT_NEAR(normal.meanLuma, value, 1e-3) << value;
  }
  options.enabled = false;
  EXPECT_FLOAT_EQ(estimateExposure(grey(10), options).gain, 1.0F);
  EXPECT_FALSE(estimateExposure(cv::Mat(), options).applied);
  EXPECT_FALSE(estimateExposure(cv::Mat(4, 4, CV_8UC1, cv::Scalar(5)), ExposureOptions{}).applied);
}

TEST(Exposure, BlackPixelsAreNotPartOfTheMean) {
  // The blank corners of an undistorted frame must not make a normal frame look dark.
  cv::Mat frame = grey(60);
  frame(cv::Rect(0, 0, 320, 480)).setTo(cv::Scalar::all(0));
  const ExposureGain gain = estimateExposure(frame, ExposureOptions{});
  EXPECT_NEAR(gain.meanLuma, 60.0F, 1e-3);
  EXPECT_FALSE(gain.applied);
}

TEST(Exposure, LuminanceIsBt601) {
  // Pure green 50 has luminance 0.587 * 50 = 29.4: dark.
  const cv::Mat green(64, 64, CV_8UC3, cv::Scalar(0, 50, 0));
  const ExposureGain gain = estimateExposure(green, ExposureOptions{});
  EXPECT_NEAR(gain.meanLuma, 29.35F, 1e-3);
  EXPECT_NEAR(gain.gain, 100.0F / 29.35F, 1e-3);
}

TEST(Exposure, YuvLumaGivesTheSameGain) {
  const int width = 64;
  const int height = 32;
  std::vector<std::uint8_t> yuyv(static_cast<std::size_t>(width) * 2 * height);
  for (std::size_t i = 0; i < yuyv.size(); ++i) {
    yuyv[i] = i % 2 == 0 ? 38 : 128;  // Y 38 (limited range: luminance 25.6), neutral chroma
  }
  const ExposureGain packed =
      estimateExposureYuv(yuyv.data(), 2 * width, width, height, 2, ExposureOptions{});
  EXPECT_NEAR(packed.meanLuma, 22.0F * 255.0F / 219.0F, 1e-3);
  EXPECT_NEAR(packed.gain, 100.0F / packed.meanLuma, 1e-4);
  const std::vector<std::uint8_t> plane(static_cast<std::size_t>(width) * height, 38);
  const ExposureGain planar =
      estimateExposureYuv(plane.data(), width, width, height, 1, ExposureOptions{});
  EXPECT_FLOAT_EQ(planar.gain, packed.gain);
  EXPECT_FALSE(estimateExposureYuv(nullptr, 0, width, height, 1, ExposureOptions{}).applied);
}

TEST(Exposure, BadOptionsNameTheKey) {
  std::string why;
  ExposureOptions options;
  EXPECT_TRUE(validate(options, &why)) << why;
  options.darkMeanLuma = 300.0;
  EXPECT_FALSE(validate(options, &why));
  EXPECT_NE(why.find("exposure_dark_mean"), std::string::npos) << why;
  options = ExposureOptions{};
  options.targetMeanLuma = 20.0;  // below the dark mean
  EXPECT_FALSE(validate(options, &why));
  EXPECT_NE(why.find("exposure_target_mean"), std::string::npos) << why;
  options = ExposureOptions{};
  options.maxGain = 0.5;
  EXPECT_FALSE(validate(options, &why));
  EXPECT_NE(why.find("exposure_max_gain"), std::string::npos) << why;
  options = ExposureOptions{};
  options.sampleStride_px = 0;
  EXPECT_FALSE(validate(options, &why));
  EXPECT_NE(why.find("exposure_sample_stride_px"), std::string::npos) << why;
  // The preprocessor refuses them at start-up with the same key.
  PreprocessOptions pre;
  pre.exposure.maxGain = 20.0;
  Preprocessor preprocessor;
  EXPECT_FALSE(preprocessor.init(pre, pinhole(), {kWidth_px, kHeight_px}, &why));
  EXPECT_NE(why.find("exposure_max_gain"), std::string::npos) << why;
}

// The working image of a copy of the tiles (views of the preprocessor's buffer).
cv::Mat firstTile(const Preprocessor& pre) {
  const TileView& tile = pre.output().tiles[0];
  const cv::Mat view(tile.rect.height_px, tile.rect.width_px, CV_8UC3,
                     const_cast<std::uint8_t*>(tile.data), tile.strideBytes);
  return view.clone();
}

TEST(Exposure, ADarkFrameIsPreprocessedAsIfItHadBeenExposedRight) {
  const cv::Mat dark = texturedFrame(20.0, 5);
  const cv::Mat copy = dark.clone();
  Preprocessor withGain;
  ASSERT_TRUE(withGain.init(PreprocessOptions{}, pinhole(), dark.size()));
  ASSERT_EQ(withGain.process(dark), PreprocessStatus::Ok);
  const ExposureGain& exposure = withGain.output().exposure;
  ASSERT_TRUE(exposure.applied);
  EXPECT_NEAR(exposure.meanLuma, 19.5F, 0.5F);  // uniform in [8, 32)
  EXPECT_NEAR(exposure.gain, 100.0F / 19.5F, 0.15F);
  EXPECT_EQ(cv::norm(dark, copy, cv::NORM_INF), 0.0) << "the caller's frame was written";
  // No full-size copy: the crops get the gain (frameGain) instead.
  EXPECT_EQ(withGain.output().frame.data, dark.data);
  EXPECT_FLOAT_EQ(withGain.output().frameGain, exposure.gain);

  // The same frame gained beforehand through the same tables, preprocessed without exposure:
  // the tiles are identical.
  WhiteBalancer tables;
  WhiteBalanceGains gains;
  gains.gain = {exposure.gain, exposure.gain, exposure.gain};
  tables.setGains(gains);
  cv::Mat gained(dark.size(), CV_8UC3);
  tables.applyRows(dark, gained, 0, dark.rows);
  PreprocessOptions off;
  off.exposure.enabled = false;
  Preprocessor without;
  ASSERT_TRUE(without.init(off, pinhole(), dark.size()));
  ASSERT_EQ(without.process(gained), PreprocessStatus::Ok);
  EXPECT_EQ(cv::norm(firstTile(withGain), firstTile(without), cv::NORM_INF), 0.0);
  EXPECT_NEAR(cv::mean(firstTile(withGain))[1], 100.0, 3.0);

  // With white balance there is an owned frame: the gain goes into it, multiplied into the
  // balance's gains, and nothing is left for the crops.
  PreprocessOptions balanced;
  balanced.whiteBalance = true;
  Preprocessor withBalance;
  ASSERT_TRUE(withBalance.init(balanced, pinhole(), dark.size()));
  ASSERT_EQ(withBalance.process(dark), PreprocessStatus::Ok);
  ASSERT_TRUE(withBalance.output().exposure.applied);
  EXPECT_FLOAT_EQ(withBalance.output().frameGain, 1.0F);
  EXPECT_NE(withBalance.output().frame.data, dark.data);
  EXPECT_GT(cv::mean(withBalance.output().frame)[1], 4.0 * cv::mean(dark)[1]);
}

TEST(Exposure, ANormallyExposedFrameIsNotTouched) {
  const cv::Mat frame = texturedFrame(110.0, 6);
  Preprocessor on;
  ASSERT_TRUE(on.init(PreprocessOptions{}, pinhole(), frame.size()));
  ASSERT_EQ(on.process(frame), PreprocessStatus::Ok);
  EXPECT_FALSE(on.output().exposure.applied);
  EXPECT_FLOAT_EQ(on.output().frameGain, 1.0F);
  EXPECT_EQ(on.output().frame.data, frame.data) << "copied although nothing changed";
  PreprocessOptions offOptions;
  offOptions.exposure.enabled = false;
  Preprocessor off;
  ASSERT_TRUE(off.init(offOptions, pinhole(), frame.size()));
  ASSERT_EQ(off.process(frame), PreprocessStatus::Ok);
  EXPECT_EQ(cv::norm(firstTile(on), firstTile(off), cv::NORM_INF), 0.0);
}

TEST(Exposure, TheCameraPathBrightensTheWorkingImage) {
  // A dark YUYV frame (Y 38: luminance 25.6, neutral chroma) straight to the working image.
  std::vector<std::uint8_t> yuyv(static_cast<std::size_t>(kWidth_px) * 2 * kHeight_px);
  for (std::size_t i = 0; i < yuyv.size(); ++i) {
    yuyv[i] = i % 2 == 0 ? 38 : 128;
  }
  YuvFrame frame;
  frame.layout = YuvFrame::Layout::Yuyv;
  frame.data = yuyv.data();
  frame.strideBytes = 2 * static_cast<std::size_t>(kWidth_px);
  frame.width_px = kWidth_px;
  frame.height_px = kHeight_px;
  Preprocessor pre;
  ASSERT_TRUE(pre.init(PreprocessOptions{}, pinhole(), {kWidth_px, kHeight_px}));
  ASSERT_EQ(pre.process(frame), PreprocessStatus::Ok);
  EXPECT_TRUE(pre.output().exposure.applied);
  EXPECT_NEAR(pre.output().exposure.gain, 100.0F / 25.6F, 0.01F);
  const cv::Mat tile = firstTile(pre);
  const cv::Rect content(0, 0, pre.output().geometry.workingWidth_px,
                         pre.output().geometry.workingHeight_px);
  EXPECT_NEAR(cv::mean(tile(content & cv::Rect(0, 0, tile.cols, tile.rows)))[1], 100.0, 6.0);
}

TEST(Exposure, NoHeapAllocationOnDarkOrNormalFrames) {
  const cv::Mat dark = texturedFrame(15.0, 7);
  const cv::Mat normal = texturedFrame(120.0, 8);
  for (const bool undistort : {false, true}) {
    PreprocessOptions options;
    options.undistort = undistort;
    camera::Intrinsics k = pinhole().intrinsics();
    camera::Distortion d;
    d.model = undistort ? camera::LensModel::BrownConrady : camera::LensModel::Pinhole;
    d.k1 = undistort ? -0.1 : 0.0;
    camera::CameraModel camera;
    ASSERT_TRUE(camera.init(k, d));
    Preprocessor pre;
    ASSERT_TRUE(pre.init(options, camera, dark.size()));
    ASSERT_EQ(pre.process(dark), PreprocessStatus::Ok);  // warm-up
    test::AllocationCounter counter;
    for (int i = 0; i < 2; ++i) {
      ASSERT_EQ(pre.process(dark), PreprocessStatus::Ok);
      ASSERT_TRUE(pre.output().exposure.applied);
      ASSERT_EQ(pre.process(normal), PreprocessStatus::Ok);
      ASSERT_FALSE(pre.output().exposure.applied);
    }
    counter.stop();
    EXPECT_EQ(counter.count(), 0U) << (undistort ? "undistorting" : "raw");
  }
}

}  // namespace
}  // namespace vp::preprocess
