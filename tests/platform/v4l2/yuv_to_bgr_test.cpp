// YUYV and NV12 -> BGR against OpenCV's cvtColor, in place and without allocation.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "alloc_counter.hpp"
#include "platform/v4l2/yuv_to_bgr.hpp"

namespace vp::platform::v4l2 {
namespace {

cv::Mat randomBytes(int rows, int cols, int seed) {
  cv::Mat bytes(rows, cols, CV_8UC1);
  cv::RNG rng(static_cast<std::uint64_t>(seed));
  rng.fill(bytes, cv::RNG::UNIFORM, 0, 256);
  return bytes;
}

double maxDifference(const cv::Mat& a, const cv::Mat& b) {
  double worst = 0.0;
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  cv::minMaxLoc(diff.reshape(1), nullptr, &worst);
  return worst;
}

TEST(YuvToBgr, YuyvMatchesCvtColorOnEveryValue) {
  // Random bytes cover every Y, U, V combination region, including out-of-range studio values.
  const int width = 320;
  const int height = 240;
  const cv::Mat yuyv = randomBytes(height, width * 2, 1);
  cv::Mat expected;
  cv::cvtColor(yuyv.reshape(2), expected, cv::COLOR_YUV2BGR_YUYV);
  cv::Mat bgr(height, width, CV_8UC3);
  const uchar* before = bgr.data;
  ASSERT_TRUE(yuyvToBgr(yuyv.data, yuyv.step, width, height, bgr));
  EXPECT_EQ(bgr.data, before);
  const double worst = maxDifference(bgr, expected);
  EXPECT_LE(worst, 1.0);
  std::printf("YUYV vs cvtColor: max difference %.0f\n", worst);
}

TEST(YuvToBgr, Nv12MatchesCvtColorOnEveryValue) {
  const int width = 320;
  const int height = 240;
  const cv::Mat nv12 = randomBytes(height * 3 / 2, width, 2);
  cv::Mat expected;
  cv::cvtColor(nv12, expected, cv::COLOR_YUV2BGR_NV12);
  cv::Mat bgr(height, width, CV_8UC3);
  ASSERT_TRUE(nv12ToBgr(nv12.data, nv12.step, nv12.ptr(height), nv12.step, width, height, bgr));
  const double worst = maxDifference(bgr, expected);
  EXPECT_LE(worst, 1.0);
  std::printf("NV12 vs cvtColor: max difference %.0f\n", worst);
}

TEST(YuvToBgr, PaddedLinesAreSkipped) {
  const int width = 64;
  const int height = 32;
  const std::size_t stride = width * 2 + 24;  // bytesperline larger than the pixels
  const cv::Mat padded = randomBytes(height, static_cast<int>(stride), 3);
  cv::Mat expected;
  cv::cvtColor(padded.colRange(0, width * 2).clone().reshape(2), expected, cv::COLOR_YUV2BGR_YUYV);
  cv::Mat bgr(height, width, CV_8UC3);
  ASSERT_TRUE(yuyvToBgr(padded.data, stride, width, height, bgr));
  EXPECT_LE(maxDifference(bgr, expected), 1.0);
}

TEST(YuvToBgr, RefusesWhatDoesNotFit) {
  std::vector<std::uint8_t> src(64 * 48 * 2, 128);
  cv::Mat wrongSize(47, 64, CV_8UC3);
  cv::Mat wrongType(48, 64, CV_8UC1);
  cv::Mat odd(48, 63, CV_8UC3);
  EXPECT_FALSE(yuyvToBgr(src.data(), 128, 64, 48, wrongSize));
  EXPECT_FALSE(yuyvToBgr(src.data(), 128, 64, 48, wrongType));
  EXPECT_FALSE(yuyvToBgr(src.data(), 126, 63, 48, odd));
  EXPECT_FALSE(yuyvToBgr(src.data(), 100, 64, 48, wrongSize));  // stride shorter than a line
  cv::Mat oddRows(47, 64, CV_8UC3);
  EXPECT_FALSE(nv12ToBgr(src.data(), 64, src.data() + 64 * 47, 64, 64, 47, oddRows));
  EXPECT_EQ(wrongSize.cols, 64);  // never reallocated
}

TEST(YuvToBgr, FullSizeConversionAllocatesNothing) {
  const int width = 2592;
  const int height = 2048;
  const cv::Mat yuyv = randomBytes(height, width * 2, 4);
  const cv::Mat nv12 = randomBytes(height * 3 / 2, width, 5);
  cv::Mat bgr(height, width, CV_8UC3);
  test::AllocationCounter counter;
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_TRUE(yuyvToBgr(yuyv.data, yuyv.step, width, height, bgr));
  const auto t1 = std::chrono::steady_clock::now();
  ASSERT_TRUE(nv12ToBgr(nv12.data, nv12.step, nv12.ptr(height), nv12.step, width, height, bgr));
  const auto t2 = std::chrono::steady_clock::now();
  counter.stop();
  EXPECT_EQ(counter.count(), 0u);
  std::printf("2592x2048: YUYV %.1f ms, NV12 %.1f ms (one thread)\n",
              std::chrono::duration<double, std::milli>(t1 - t0).count(),
              std::chrono::duration<double, std::milli>(t2 - t1).count());
}

}  // namespace
}  // namespace vp::platform::v4l2
