// WhiteBalancer (seed 001's near-white-point AWB): a grey scene under a colour cast comes
// back grey; a neutral scene keeps equal gains; flat or black input finds nothing.
#include "preprocess/white_balance.hpp"

#include <cstdio>

#include <gtest/gtest.h>

namespace vp::preprocess {
namespace {

// Grey levels uniform in [40, 200] per pixel, cast by per-channel factors (B, G, R order).
cv::Mat castGreyScene(cv::Size size, cv::Vec3f cast, std::uint64_t seed) {
  cv::Mat grey(size, CV_32FC1);
  cv::RNG rng(seed);
  rng.fill(grey, cv::RNG::UNIFORM, 40.0, 200.0);
  cv::Mat image(size, CV_8UC3);
  for (int v = 0; v < size.height; ++v) {
    for (int u = 0; u < size.width; ++u) {
      const float g = grey.at<float>(v, u);
      for (int c = 0; c < 3; ++c) {
        image.at<cv::Vec3b>(v, u)[c] = cv::saturate_cast<std::uint8_t>(g * cast[c]);
      }
    }
  }
  return image;
}

TEST(WhiteBalance, RestoresAColourCastGreyScene) {
  const cv::Vec3f cast(0.75F, 1.0F, 1.2F);  // bluish channel down, red up
  const cv::Mat frame = castGreyScene({640, 480}, cast, 42);
  WhiteBalancer balancer;
  std::string why;
  ASSERT_TRUE(balancer.init(WhiteBalanceOptions{}, frame.size(), &why)) << why;
  const WhiteBalanceGains gains = balancer.estimate(frame);
  ASSERT_TRUE(gains.found);
  EXPECT_EQ(gains.regionsUsed, 12);
  EXPECT_GT(gains.candidateCount, 1000);
  EXPECT_GE(gains.referenceCount, gains.candidateCount / 10);
  std::printf("  gains B %.4f G %.4f R %.4f (%d candidates, %d reference points)\n",
              static_cast<double>(gains.gain[0]), static_cast<double>(gains.gain[1]),
              static_cast<double>(gains.gain[2]), gains.candidateCount, gains.referenceCount);
  // Gains undo the cast: ratios to green = 1 / cast ratio (within 2 %).
  EXPECT_NEAR(gains.gain[0] / gains.gain[1], 1.0 / 0.75, 0.02 / 0.75);
  EXPECT_NEAR(gains.gain[2] / gains.gain[1], 1.0 / 1.2, 0.02 / 1.2);

  balancer.setGains(gains);
  cv::Mat balanced(frame.size(), CV_8UC3);
  balancer.applyRows(frame, balanced, 0, frame.rows);
  // Every mid-grey pixel is grey again: channels within 3 levels (rounding of the cast image).
  int checked = 0;
  int grey = 0;
  for (int v = 0; v < frame.rows; v += 2) {
    for (int u = 0; u < frame.cols; u += 2) {
      const cv::Vec3b p = balanced.at<cv::Vec3b>(v, u);
      if (p[1] < 60 || p[1] > 200) {
        continue;
      }
      ++checked;
      grey += (std::abs(p[0] - p[1]) <= 3 && std::abs(p[2] - p[1]) <= 3) ? 1 : 0;
    }
  }
  ASSERT_GT(checked, 10000);
  std::printf("  %.2f %% of mid-grey pixels grey again (channels within 3 levels)\n",
              100.0 * grey / checked);
  EXPECT_GT(static_cast<double>(grey) / checked, 0.99);
  // Before: the cast pixels were far from grey.
  const cv::Vec3b before = frame.at<cv::Vec3b>(100, 100);
  EXPECT_GT(std::abs(before[2] - before[0]), 10);
}

TEST(WhiteBalance, NeutralSceneKeepsEqualGains) {
  // Greys with colourful pixels (random RGB) in between: the near-white points are the greys.
  cv::Mat frame = castGreyScene({400, 300}, cv::Vec3f(1.0F, 1.0F, 1.0F), 5);
  cv::RNG rng(8);
  for (int v = 0; v < frame.rows; ++v) {
    for (int u = 0; u < frame.cols; ++u) {
      if (rng.uniform(0.0, 1.0) < 0.3) {
        frame.at<cv::Vec3b>(v, u) = cv::Vec3b(static_cast<std::uint8_t>(rng.uniform(0, 256)),
                                              static_cast<std::uint8_t>(rng.uniform(0, 256)),
                                              static_cast<std::uint8_t>(rng.uniform(0, 256)));
      }
    }
  }
  WhiteBalancer balancer;
  ASSERT_TRUE(balancer.init(WhiteBalanceOptions{}, frame.size()));
  const WhiteBalanceGains gains = balancer.estimate(frame);
  ASSERT_TRUE(gains.found);
  EXPECT_NEAR(gains.gain[0] / gains.gain[1], 1.0, 0.03);
  EXPECT_NEAR(gains.gain[2] / gains.gain[1], 1.0, 0.03);
  // Pure greys have no chroma variation at all: nothing to estimate, the gains stay 1.
  const cv::Mat greys = castGreyScene({400, 300}, cv::Vec3f(1.0F, 1.0F, 1.0F), 6);
  const WhiteBalanceGains none = balancer.estimate(greys);
  EXPECT_FALSE(none.found);
  EXPECT_EQ(none.gain[0], 1.0F);
  EXPECT_EQ(none.gain[2], 1.0F);
}

TEST(WhiteBalance, BlackPixelsAreSkipped) {
  const cv::Vec3f cast(0.8F, 1.0F, 1.1F);
  cv::Mat frame = castGreyScene({400, 300}, cast, 9);
  WhiteBalancer balancer;
  ASSERT_TRUE(balancer.init(WhiteBalanceOptions{}, frame.size()));
  const WhiteBalanceGains clean = balancer.estimate(frame);
  // Blank corners like those of an undistorted frame do not move the estimate much.
  frame(cv::Rect(0, 0, 60, 60)).setTo(cv::Scalar::all(0));
  frame(cv::Rect(340, 240, 60, 60)).setTo(cv::Scalar::all(0));
  const WhiteBalanceGains blanked = balancer.estimate(frame);
  ASSERT_TRUE(clean.found && blanked.found);
  EXPECT_NEAR(blanked.gain[0] / blanked.gain[1], clean.gain[0] / clean.gain[1], 0.03);
  EXPECT_NEAR(blanked.gain[2] / blanked.gain[1], clean.gain[2] / clean.gain[1], 0.03);
}

TEST(WhiteBalance, FlatOrWrongInputFindsNothing) {
  WhiteBalancer balancer;
  ASSERT_TRUE(balancer.init(WhiteBalanceOptions{}, {200, 100}));
  const cv::Mat flat(100, 200, CV_8UC3, cv::Scalar(90, 100, 120));
  WhiteBalanceGains gains = balancer.estimate(flat);
  EXPECT_FALSE(gains.found);
  EXPECT_EQ(gains.regionsUsed, 0);
  EXPECT_EQ(gains.gain[0], 1.0F);
  const cv::Mat wrongSize(50, 50, CV_8UC3, cv::Scalar::all(100));
  EXPECT_FALSE(balancer.estimate(wrongSize).found);
  const cv::Mat black(100, 200, CV_8UC3, cv::Scalar::all(0));
  EXPECT_FALSE(balancer.estimate(black).found);
}

TEST(WhiteBalance, GainsSaturateAndCanBeAppliedInPlace) {
  WhiteBalancer balancer;
  ASSERT_TRUE(balancer.init(WhiteBalanceOptions{}, {4, 1}));
  WhiteBalanceGains gains;
  gains.gain = {2.0F, 1.0F, 0.5F};
  balancer.setGains(gains);
  cv::Mat image(1, 4, CV_8UC3);
  image.at<cv::Vec3b>(0, 0) = {10, 10, 10};
  image.at<cv::Vec3b>(0, 1) = {200, 200, 200};
  image.at<cv::Vec3b>(0, 2) = {127, 0, 255};
  image.at<cv::Vec3b>(0, 3) = {0, 255, 3};
  balancer.applyRows(image, image, 0, 1);
  EXPECT_EQ(image.at<cv::Vec3b>(0, 0), cv::Vec3b(20, 10, 5));
  EXPECT_EQ(image.at<cv::Vec3b>(0, 1), cv::Vec3b(255, 200, 100));
  EXPECT_EQ(image.at<cv::Vec3b>(0, 2), cv::Vec3b(254, 0, 128));  // 127.5 -> 128 (half even)
  EXPECT_EQ(image.at<cv::Vec3b>(0, 3), cv::Vec3b(0, 255, 2));    // 1.5 -> 2
}

TEST(WhiteBalance, ValidatesOptions) {
  std::string why;
  WhiteBalanceOptions options;
  options.regionRows = 0;
  EXPECT_FALSE(validate(options, &why));
  EXPECT_NE(why.find("region_rows"), std::string::npos) << why;
  options = WhiteBalanceOptions{};
  options.whitePointShare = 0.0;
  EXPECT_FALSE(validate(options, &why));
  EXPECT_NE(why.find("white_point_share"), std::string::npos) << why;
  options = WhiteBalanceOptions{};
  options.maxGain = 0.5;
  EXPECT_FALSE(validate(options, &why));
  EXPECT_NE(why.find("max_gain"), std::string::npos) << why;
  options = WhiteBalanceOptions{};
  options.sampleStride_px = 0;
  WhiteBalancer balancer;
  EXPECT_FALSE(balancer.init(options, {10, 10}, &why));
  EXPECT_NE(why.find("sample_stride_px"), std::string::npos) << why;
}

}  // namespace
}  // namespace vp::preprocess
