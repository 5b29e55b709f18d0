// AreaResizer must reproduce cv::resize(INTER_AREA) - the filter of the Python pipeline, which
// trains on x86-64 - bit for bit, on the integer-factor fast paths (4x: the default working
// scale; 2x: OpenCV's half-up SIMD rounding) and on the general fractional-coverage path.
// On x86-64 the test compares with this machine's OpenCV and with the hash of x86-64 OpenCV's
// output; elsewhere with the hash alone: Debian's arm64 OpenCV fuses the multiply-adds of its
// fractional path and differs from x86-64 in the last bit, while AreaResizer (no contraction,
// -ffp-contract=off) gives the x86-64 bytes on every CPU.
#include "preprocess/area_resizer.hpp"

#include <cstdint>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

namespace vp::preprocess {
namespace {

cv::Mat randomImage(cv::Size size, std::uint64_t seed) {
  cv::Mat image(size, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  return image;
}

// FNV-1a over the pixels, row by row.
std::uint64_t pixelHash(const cv::Mat& image) {
  std::uint64_t hash = 14695981039346656037ULL;
  for (int r = 0; r < image.rows; ++r) {
    const std::uint8_t* p = image.ptr<std::uint8_t>(r);
    for (std::size_t i = 0; i < static_cast<std::size_t>(image.cols) * image.elemSize(); ++i) {
      hash = (hash ^ p[i]) * 1099511628211ULL;
    }
  }
  return hash;
}

// x86x64OpenCvHash: pixelHash of cv::resize(INTER_AREA) of the same input on x86-64.
void expectSameAsOpenCv(cv::Size src, cv::Size dst, bool expectInteger,
                        std::uint64_t x86x64OpenCvHash) {
  SCOPED_TRACE(std::to_string(src.width) + "x" + std::to_string(src.height) + " -> " +
               std::to_string(dst.width) + "x" + std::to_string(dst.height));
  const cv::Mat image = randomImage(src, 7U + static_cast<std::uint64_t>(src.width));
  AreaResizer resizer;
  std::string why;
  ASSERT_TRUE(resizer.init(src, dst, 1, &why)) << why;
  EXPECT_EQ(resizer.integerFactor(), expectInteger);
  cv::Mat ours(dst, CV_8UC3, cv::Scalar::all(0));
  ASSERT_TRUE(resizer.apply(image, ours));
  EXPECT_EQ(pixelHash(ours), x86x64OpenCvHash);
#if defined(__x86_64__)
  cv::Mat reference;
  cv::resize(image, reference, dst, 0, 0, cv::INTER_AREA);
  EXPECT_EQ(cv::norm(ours, reference, cv::NORM_INF), 0.0);
  EXPECT_EQ(pixelHash(reference), x86x64OpenCvHash);
#endif
}

TEST(AreaResizer, DefaultWorkingScaleMatchesOpenCvExactly) {
  expectSameAsOpenCv({2592, 2048}, {648, 512}, true,  // 4x: sum / 16, half to even
                     0xe7cb3431932bfd54ULL);
}

TEST(AreaResizer, HalfScaleMatchesOpenCvExactly) {
  expectSameAsOpenCv({400, 300}, {200, 150}, true,  // 2x: OpenCV rounds half up here
                     0x584a1753f34f3895ULL);
}

TEST(AreaResizer, FractionalScalesMatchOpenCvExactly) {
  expectSameAsOpenCv({2592, 2048}, {778, 614}, false, 0xd5f54f50f608f95aULL);  // scale 0.3
  expectSameAsOpenCv({101, 77}, {37, 29}, false, 0xc6bdacc9f4a4e9b9ULL);
  expectSameAsOpenCv({640, 480}, {639, 479}, false,
                     0xa81fdd887e17cf46ULL);  // slivers of coverage
}

TEST(AreaResizer, WritesIntoARegionOfALargerImage) {
  const cv::Mat image = randomImage({256, 128}, 3);
  AreaResizer resizer;
  ASSERT_TRUE(resizer.init({256, 128}, {64, 32}, 1));
  cv::Mat canvas(48, 96, CV_8UC3, cv::Scalar::all(128));
  cv::Mat roi = canvas(cv::Rect(0, 0, 64, 32));
  ASSERT_TRUE(resizer.apply(image, roi));
  cv::Mat reference;
  cv::resize(image, reference, {64, 32}, 0, 0, cv::INTER_AREA);
  EXPECT_EQ(cv::norm(roi, reference, cv::NORM_INF), 0.0);
  // The padding outside the region is untouched.
  EXPECT_EQ(canvas.at<cv::Vec3b>(40, 90), cv::Vec3b(128, 128, 128));
  EXPECT_EQ(canvas.at<cv::Vec3b>(10, 70), cv::Vec3b(128, 128, 128));
}

TEST(AreaResizer, RejectsBadSizes) {
  AreaResizer resizer;
  std::string why;
  EXPECT_FALSE(resizer.init({100, 100}, {200, 50}, 1, &why));
  EXPECT_NE(why.find("only downscaling"), std::string::npos) << why;
  EXPECT_FALSE(resizer.init({0, 100}, {20, 20}, 1, &why));
  ASSERT_TRUE(resizer.init({100, 100}, {50, 50}, 1, &why));
  cv::Mat src(100, 100, CV_8UC1);
  cv::Mat dst(50, 50, CV_8UC3);
  EXPECT_FALSE(resizer.apply(src, dst));  // wrong type
}

}  // namespace
}  // namespace vp::preprocess
