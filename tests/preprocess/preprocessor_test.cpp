// Preprocessor: the whole frame -> corrected frame + tiles chain at the camera's resolution,
// its statuses for bad frames, and zero heap allocation per frame after init().
#include "preprocess/preprocessor.hpp"

#include <cstring>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "alloc_counter.hpp"

namespace vp::preprocess {
namespace {

// Undistorted frames, as these tests were written for (the shipped default keeps them raw).
PreprocessOptions undistorting() {
  PreprocessOptions options;
  options.undistort = true;
  return options;
}

constexpr int kFrameWidth_px = 2592;  // the camera of seed 000
constexpr int kFrameHeight_px = 2048;

camera::CameraModel camera2592(camera::LensModel lens) {
  camera::Intrinsics k;
  k.width_px = kFrameWidth_px;
  k.height_px = kFrameHeight_px;
  k.fx_px = 2300.0;
  k.fy_px = 2300.0;
  k.cx_px = 1297.5;
  k.cy_px = 1021.0;
  camera::Distortion d;
  d.model = lens;
  if (lens == camera::LensModel::BrownConrady) {
    d.k1 = -0.12;
    d.k2 = 0.04;
    d.p1 = 2e-4;
    d.p2 = -1e-4;
  }
  camera::CameraModel camera;
  EXPECT_TRUE(camera.init(k, d));
  return camera;
}

cv::Mat texturedFrame(std::uint64_t seed) {
  cv::Mat frame(kFrameHeight_px, kFrameWidth_px, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(frame, cv::RNG::UNIFORM, 30, 220);
  return frame;
}

TEST(Preprocessor, DefaultScaleGivesOnePaddedTile) {
  const camera::CameraModel camera = camera2592(camera::LensModel::BrownConrady);
  Preprocessor pre;
  std::string why;
  ASSERT_TRUE(pre.init(undistorting(), camera, {kFrameWidth_px, kFrameHeight_px}, &why)) << why;
  EXPECT_TRUE(pre.undistorts());
  const cv::Mat frame = texturedFrame(1);
  ASSERT_EQ(pre.process(frame), PreprocessStatus::Ok) << pre.lastError();
  const PreprocessedFrame& out = pre.output();
  EXPECT_EQ(out.geometry.workingWidth_px, 648);
  EXPECT_EQ(out.geometry.workingHeight_px, 512);
  EXPECT_DOUBLE_EQ(out.geometry.scaleX, 0.25);
  EXPECT_DOUBLE_EQ(out.geometry.workingToFrameU(0.0), 1.5);  // pixel centres: 4 px block
  ASSERT_EQ(out.tiles.size(), 1U);
  const TileView& tile = out.tiles[0];
  EXPECT_EQ(tile.rect.x0_px, 0);
  EXPECT_EQ(tile.rect.width_px, 672);
  EXPECT_EQ(tile.rect.height_px, 512);
  EXPECT_FALSE(tile.rect.innerLeft || tile.rect.innerRight || tile.rect.innerTop ||
               tile.rect.innerBottom);

  // The corrected frame is the remap of the input, the tile its area downscale + grey pad.
  FrameRemap remap;
  ASSERT_TRUE(remap.init(camera, camera.intrinsics()));
  cv::Mat undistorted(frame.size(), CV_8UC3);
  ASSERT_TRUE(remap.apply(frame, undistorted));
  EXPECT_EQ(cv::norm(out.frame, undistorted, cv::NORM_INF), 0.0);
  cv::Mat small;
  cv::resize(undistorted, small, {648, 512}, 0, 0, cv::INTER_AREA);
  const cv::Mat tileMat(512, 672, CV_8UC3, const_cast<std::uint8_t*>(tile.data), tile.strideBytes);
  EXPECT_EQ(cv::norm(tileMat(cv::Rect(0, 0, 648, 512)), small, cv::NORM_INF), 0.0);
  EXPECT_EQ(tileMat.at<cv::Vec3b>(300, 660), cv::Vec3b(128, 128, 128));

  // Lifting uses the pinhole of the undistorted frame.
  EXPECT_EQ(pre.frameCamera().distortion().model, camera::LensModel::Pinhole);
  EXPECT_DOUBLE_EQ(pre.frameCamera().intrinsics().fx_px, 2300.0);
}

TEST(Preprocessor, WithoutCorrectionsTheFrameIsTheCallersFrame) {
  const camera::CameraModel camera = camera2592(camera::LensModel::Pinhole);
  PreprocessOptions options = undistorting();
  options.undistort = true;  // a pinhole needs none: no remap, no copy
  Preprocessor pre;
  ASSERT_TRUE(pre.init(options, camera, {kFrameWidth_px, kFrameHeight_px}));
  EXPECT_FALSE(pre.undistorts());
  const cv::Mat frame = texturedFrame(2);
  ASSERT_EQ(pre.process(frame), PreprocessStatus::Ok);
  EXPECT_EQ(pre.output().frame.data, frame.data);
  EXPECT_EQ(pre.frameCamera().distortion().model, camera::LensModel::Pinhole);
}

TEST(Preprocessor, WhiteBalanceNeverWritesTheCallersFrame) {
  const camera::CameraModel camera = camera2592(camera::LensModel::Pinhole);
  PreprocessOptions options = undistorting();
  options.whiteBalance = true;
  Preprocessor pre;
  ASSERT_TRUE(pre.init(options, camera, {kFrameWidth_px, kFrameHeight_px}));
  cv::Mat frame = texturedFrame(3);
  frame.forEach<cv::Vec3b>(
      [](cv::Vec3b& p, const int*) { p[2] = cv::saturate_cast<std::uint8_t>(p[2] * 1.2); });
  const cv::Mat copy = frame.clone();
  ASSERT_EQ(pre.process(frame), PreprocessStatus::Ok);
  EXPECT_EQ(cv::norm(frame, copy, cv::NORM_INF), 0.0);
  EXPECT_NE(pre.output().frame.data, frame.data);
  ASSERT_TRUE(pre.output().whiteBalance.found);
  // The red cast is reduced in the corrected frame.
  const cv::Scalar before = cv::mean(frame);
  const cv::Scalar after = cv::mean(pre.output().frame);
  EXPECT_LT(std::abs(after[2] / after[1] - 1.0), std::abs(before[2] / before[1] - 1.0));
}

TEST(Preprocessor, FinerWorkingScaleIsTiled) {
  const camera::CameraModel camera = camera2592(camera::LensModel::Pinhole);
  PreprocessOptions options = undistorting();
  options.workingScale = 0.5;
  options.tileOverlap_px = 96;
  Preprocessor pre;
  std::string why;
  ASSERT_TRUE(pre.init(options, camera, {kFrameWidth_px, kFrameHeight_px}, &why)) << why;
  ASSERT_EQ(pre.tileCount(), 9U);
  const cv::Mat frame = texturedFrame(4);
  ASSERT_EQ(pre.process(frame), PreprocessStatus::Ok);
  const PreprocessedFrame& out = pre.output();
  EXPECT_EQ(out.geometry.workingWidth_px, 1296);
  cv::Mat small;
  cv::resize(frame, small, {1296, 1024}, 0, 0, cv::INTER_AREA);
  for (const TileView& tile : out.tiles) {
    // Each tile shows the working image at its offset.
    const cv::Mat view(tile.rect.height_px, tile.rect.width_px, CV_8UC3,
                       const_cast<std::uint8_t*>(tile.data), tile.strideBytes);
    EXPECT_EQ(
        cv::norm(view, small(cv::Rect(tile.rect.x0_px, tile.rect.y0_px, 672, 512)), cv::NORM_INF),
        0.0)
        << "tile " << tile.index;
  }
  EXPECT_TRUE(out.tiles[4].rect.innerLeft && out.tiles[4].rect.innerRight &&
              out.tiles[4].rect.innerTop && out.tiles[4].rect.innerBottom);
}

TEST(Preprocessor, BadFramesAreStatusesNamingTheProblem) {
  const camera::CameraModel camera = camera2592(camera::LensModel::BrownConrady);
  Preprocessor pre;
  const cv::Mat frame = texturedFrame(5);
  EXPECT_EQ(pre.process(frame), PreprocessStatus::NotInitialised);
  ASSERT_TRUE(pre.init(undistorting(), camera, {kFrameWidth_px, kFrameHeight_px}));
  EXPECT_EQ(pre.process(cv::Mat()), PreprocessStatus::EmptyFrame);
  EXPECT_NE(std::strstr(pre.lastError(), "empty frame"), nullptr) << pre.lastError();
  const cv::Mat grey(kFrameHeight_px, kFrameWidth_px, CV_8UC1, cv::Scalar::all(0));
  EXPECT_EQ(pre.process(grey), PreprocessStatus::WrongFrameType);
  EXPECT_NE(std::strstr(pre.lastError(), "1 channel"), nullptr) << pre.lastError();
  const cv::Mat deep(kFrameHeight_px, kFrameWidth_px, CV_16UC3, cv::Scalar::all(0));
  EXPECT_EQ(pre.process(deep), PreprocessStatus::WrongFrameType);
  const cv::Mat small(1024, 1296, CV_8UC3, cv::Scalar::all(0));
  EXPECT_EQ(pre.process(small), PreprocessStatus::WrongFrameSize);
  EXPECT_NE(std::strstr(pre.lastError(), "1296x1024, expected 2592x2048"), nullptr)
      << pre.lastError();
  ASSERT_EQ(pre.process(frame), PreprocessStatus::Ok);
  EXPECT_STREQ(pre.lastError(), "");
  // Its own output fed back in would be remapped in place.
  EXPECT_EQ(pre.process(pre.output().frame), PreprocessStatus::FrameIsOutput);
}

TEST(Preprocessor, InitNamesBadOptions) {
  const camera::CameraModel camera = camera2592(camera::LensModel::BrownConrady);
  Preprocessor pre;
  std::string why;
  EXPECT_FALSE(pre.init(undistorting(), camera, {1296, 1024}, &why));
  EXPECT_NE(why.find("differs from the camera model's 2592x2048"), std::string::npos) << why;
  PreprocessOptions options = undistorting();
  options.workingScale = 1.5;
  EXPECT_FALSE(pre.init(options, camera, {kFrameWidth_px, kFrameHeight_px}, &why));
  EXPECT_NE(why.find("working_scale"), std::string::npos) << why;
  options = undistorting();
  options.tileOverlap_px = 400;
  EXPECT_FALSE(pre.init(options, camera, {kFrameWidth_px, kFrameHeight_px}, &why));
  EXPECT_NE(why.find("tile_overlap_px"), std::string::npos) << why;
  options = undistorting();
  options.workingScale = 1.0;
  options.networkWidth_px = 64;
  options.networkHeight_px = 64;
  options.tileOverlap_px = 16;
  EXPECT_FALSE(pre.init(options, camera, {kFrameWidth_px, kFrameHeight_px}, &why));
  EXPECT_NE(why.find("tiles, more than 64"), std::string::npos) << why;
  EXPECT_FALSE(pre.initialised());
}

TEST(Preprocessor, NoHeapAllocationPerFrame) {
  const camera::CameraModel camera = camera2592(camera::LensModel::BrownConrady);
  const cv::Mat frame = texturedFrame(6);
  for (const int threads : {1, 2}) {
    for (const double scale : {kDefaultWorkingScale, 0.3}) {
      PreprocessOptions options = undistorting();
      options.whiteBalance = true;
      options.threads = threads;
      options.workingScale = scale;
      Preprocessor pre;
      ASSERT_TRUE(pre.init(options, camera, {kFrameWidth_px, kFrameHeight_px}));
      ASSERT_EQ(pre.process(frame), PreprocessStatus::Ok);  // first frame: warm-up
      test::AllocationCounter counter;
      for (int i = 0; i < 2; ++i) {
        ASSERT_EQ(pre.process(frame), PreprocessStatus::Ok);
      }
      EXPECT_EQ(pre.process(cv::Mat()), PreprocessStatus::EmptyFrame);
      counter.stop();
      EXPECT_EQ(counter.count(), 0U) << "threads " << threads << " scale " << scale;
    }
  }
}

// The tiles of a preprocessor, copied (they are views of its working image).
std::vector<cv::Mat> tileImages(const Preprocessor& pre) {
  std::vector<cv::Mat> images;
  for (const TileView& tile : pre.output().tiles) {
    const cv::Mat view(tile.rect.height_px, tile.rect.width_px, CV_8UC3,
                       const_cast<std::uint8_t*>(tile.data), tile.strideBytes);
    images.push_back(view.clone());
  }
  return images;
}

TEST(Preprocessor, AdaptsTheWorkingScaleToTheGsdLikeAFixedScale) {
  const camera::CameraModel camera = camera2592(camera::LensModel::Pinhole);
  const cv::Mat frame = texturedFrame(7);
  PreprocessOptions adaptive;      // workingGsd_m 0.12, anchor 0.25, ladder [0.125, 1]
  adaptive.maxWorkingGsd_m = 0.0;  // always the height's rung (the next test: fewer tiles)
  Preprocessor pre;
  std::string why;
  ASSERT_TRUE(pre.init(adaptive, camera, {kFrameWidth_px, kFrameHeight_px}, &why)) << why;
  ASSERT_EQ(pre.workingScales().size(), 25U);
  EXPECT_EQ(pre.workingScale(), kDefaultWorkingScale);  // until the first GSD
  EXPECT_FALSE(pre.adaptToGsd(0.031));                  // ideal 0.258: within the hysteresis
  ASSERT_TRUE(pre.adaptToGsd(0.06));                    // twice as high: 0.5
  EXPECT_NEAR(pre.workingScale(), 0.5, 1e-9);
  ASSERT_EQ(pre.process(frame), PreprocessStatus::Ok);
  EXPECT_EQ(pre.output().geometry.workingWidth_px, 1296);
  const std::vector<cv::Mat> adapted = tileImages(pre);
  // Back down: the smaller rung's padded tile must not show what the larger one wrote.
  ASSERT_TRUE(pre.adaptToGsd(0.03));
  ASSERT_EQ(pre.process(frame), PreprocessStatus::Ok);
  const std::vector<cv::Mat> back = tileImages(pre);

  for (const auto& [scale, tiles] : {std::pair{0.5, adapted}, std::pair{0.25, back}}) {
    PreprocessOptions fixed;
    fixed.workingGsd_m = 0.0;
    fixed.workingScale = scale;
    Preprocessor reference;
    ASSERT_TRUE(reference.init(fixed, camera, {kFrameWidth_px, kFrameHeight_px}, &why)) << why;
    ASSERT_EQ(reference.workingScales().size(), 1U);
    ASSERT_EQ(reference.process(frame), PreprocessStatus::Ok);
    const std::vector<cv::Mat> expected = tileImages(reference);
    ASSERT_EQ(tiles.size(), expected.size()) << "scale " << scale;
    for (std::size_t i = 0; i < tiles.size(); ++i) {
      EXPECT_EQ(cv::norm(tiles[i], expected[i], cv::NORM_INF), 0.0)
          << "scale " << scale << " tile " << i;
    }
  }
}

TEST(Preprocessor, ACoarserRungWithFewerTilesIsTakenWithinTheGsdLimit) {
  const camera::CameraModel camera = camera2592(camera::LensModel::Pinhole);
  PreprocessOptions options;  // workingGsd_m 0.12, maxWorkingGsd_m 0.15: up to 1.25x coarser
  ASSERT_EQ(options.maxWorkingGsd_m, 0.15);
  PreprocessOptions off = options;
  off.maxWorkingGsd_m = 0.0;
  Preprocessor pre;
  Preprocessor height;  // always the height's rung
  std::string why;
  ASSERT_TRUE(pre.init(options, camera, {kFrameWidth_px, kFrameHeight_px}, &why)) << why;
  ASSERT_TRUE(height.init(off, camera, {kFrameWidth_px, kFrameHeight_px}, &why)) << why;
  // 6 cm/px: the height's rung is 0.5 (1296 x 1024 working px); 0.420 (two rungs down, 14.3 cm
  // working pixels) needs fewer tiles, 0.385 no fewer than that, 0.354 is beyond 0.15 m.
  ASSERT_TRUE(pre.adaptToGsd(0.06));
  ASSERT_TRUE(height.adaptToGsd(0.06));
  EXPECT_NEAR(height.workingScale(), 0.5, 1e-9);
  EXPECT_NEAR(pre.workingScale(), 0.5 / (kScaleStep * kScaleStep), 1e-9);
  EXPECT_LT(pre.tileCount(), height.tileCount());
  // 3.57 cm/px: the height's rung 0.297 (771 x 609: 2 x 2 tiles of 672 x 512); 0.25 (648 x 512,
  // one tile) gives 14.3 cm working pixels.
  ASSERT_TRUE(pre.adaptToGsd(0.0357));
  ASSERT_TRUE(height.adaptToGsd(0.0357));
  EXPECT_NEAR(height.workingScale(), 0.25 * kScaleStep * kScaleStep, 1e-9);
  EXPECT_EQ(height.tileCount(), 4U);
  EXPECT_EQ(pre.workingScale(), kDefaultWorkingScale);
  EXPECT_EQ(pre.tileCount(), 1U);
  // Hovering: the choice holds within the hysteresis.
  EXPECT_FALSE(pre.adaptToGsd(0.0345));
  EXPECT_FALSE(pre.adaptToGsd(0.0368));
  // A limit below working_gsd_m is refused, naming the option.
  options.maxWorkingGsd_m = 0.1;
  EXPECT_FALSE(pre.init(options, camera, {kFrameWidth_px, kFrameHeight_px}, &why));
  EXPECT_NE(why.find("max_working_gsd_m"), std::string::npos) << why;
}

TEST(Preprocessor, ChangingTheWorkingScaleAllocatesNothing) {
  const camera::CameraModel camera = camera2592(camera::LensModel::Pinhole);
  const cv::Mat frame = texturedFrame(8);
  Preprocessor pre;
  ASSERT_TRUE(pre.init(PreprocessOptions{}, camera, {kFrameWidth_px, kFrameHeight_px}));
  ASSERT_EQ(pre.process(frame), PreprocessStatus::Ok);
  test::AllocationCounter counter;
  int changes = 0;
  for (const double gsd_m : {0.06, 0.02, 0.045, 0.03}) {
    changes += pre.adaptToGsd(gsd_m) ? 1 : 0;
    ASSERT_EQ(pre.process(frame), PreprocessStatus::Ok);
  }
  counter.stop();
  EXPECT_EQ(changes, 4);
  EXPECT_EQ(counter.count(), 0U);
}

TEST(Preprocessor, FixedScaleIgnoresTheGsdAndLadderBoundsAreChecked) {
  const camera::CameraModel camera = camera2592(camera::LensModel::Pinhole);
  PreprocessOptions fixed;
  fixed.workingGsd_m = 0.0;
  Preprocessor pre;
  ASSERT_TRUE(pre.init(fixed, camera, {kFrameWidth_px, kFrameHeight_px}));
  EXPECT_FALSE(pre.adaptToGsd(0.06));
  EXPECT_EQ(pre.workingScale(), kDefaultWorkingScale);
  PreprocessOptions bad;
  bad.minWorkingScale = 0.3;  // above working_scale 0.25
  std::string why;
  EXPECT_FALSE(pre.init(bad, camera, {kFrameWidth_px, kFrameHeight_px}, &why));
  EXPECT_NE(why.find("min_working_scale"), std::string::npos) << why;
}

}  // namespace
}  // namespace vp::preprocess
