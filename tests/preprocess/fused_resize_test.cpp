// The one-sweep resize (AreaResizer with gains) against the straightforward reference: the
// white-balance tables applied to the whole frame, then cv::resize(INTER_AREA) (on x86-64; see
// referenceAreaResize for other CPUs). Every
// instruction-set variant of the kernels (scalar - what ARM builds run -, SSE2, AVX2 where the
// CPU has it) must give the same bytes, on random and simulated frames, odd sizes, integer and
// fractional factors, saturating gains, and any split of the rows over threads.
#include <algorithm>
#include <array>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "alloc_counter.hpp"
#include "pinhole_camera.hpp"

#include "preprocess/area_kernels.hpp"
#include "preprocess/area_resizer.hpp"
#include "preprocess/preprocessor.hpp"
#include "preprocess/white_balance.hpp"
#include "preprocess/yuv_rows.hpp"
#include "synthetic_frame.hpp"

namespace vp::preprocess {
namespace {

using kernels::Isa;

// Runs the test body once per instruction set this machine has; restores the best after.
class EveryIsa : public ::testing::Test {
 protected:
  void TearDown() override { kernels::limitIsa(Isa::Avx2); }
  static std::vector<Isa> available() {
    std::vector<Isa> isas;
    for (const Isa isa : {Isa::Scalar, Isa::Sse2, Isa::Avx2}) {
      if (kernels::limitIsa(isa) == isa) {
        isas.push_back(isa);
      }
    }
    kernels::limitIsa(Isa::Avx2);
    return isas;
  }
};

const char* name(Isa isa) {
  switch (isa) {
    case Isa::Scalar:
      return "scalar";
    case Isa::Sse2:
      return "sse2";
    case Isa::Avx2:
      return "avx2";
  }
  return "?";
}

cv::Mat randomImage(cv::Size size, std::uint64_t seed) {
  cv::Mat image(size, CV_8UC3);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  return image;
}

// The reference: per-channel tables (WhiteBalancer::setGains / applyRows), then OpenCV.
cv::Mat referenceBalanced(const cv::Mat& frame, const std::array<float, 3>& gains) {
  WhiteBalancer balancer;
  EXPECT_TRUE(balancer.init(WhiteBalanceOptions{}, frame.size()));
  WhiteBalanceGains g;
  g.gain = gains;
  balancer.setGains(g);
  cv::Mat balanced(frame.size(), CV_8UC3);
  balancer.applyRows(frame, balanced, 0, frame.rows);
  return balanced;
}

// The area resize the kernels must equal: cv::resize(INTER_AREA) on x86-64, where the training
// pipeline runs; on other CPUs the plain AreaResizer (one block, no gains), whose own tests pin
// its output to x86-64 OpenCV's by hash (area_resizer_test.cpp: arm64 OpenCV fuses the
// multiply-adds of its fractional path and is not that reference).
cv::Mat referenceAreaResize(const cv::Mat& src, cv::Size dst) {
  cv::Mat out;
#if defined(__x86_64__)
  cv::resize(src, out, dst, 0, 0, cv::INTER_AREA);
#else
  const kernels::Isa isa = kernels::activeIsa();
  kernels::limitIsa(Isa::Scalar);
  AreaResizer plain;
  EXPECT_TRUE(plain.init(src.size(), dst, 1));
  out.create(dst, CV_8UC3);
  EXPECT_TRUE(plain.apply(src, out));
  kernels::limitIsa(isa);
#endif
  return out;
}

double maxDifference(const cv::Mat& a, const cv::Mat& b) {
  return cv::norm(a, b, cv::NORM_INF);
}

// Resizes src to dst in `blocks` row blocks (one scratch slot each, as RowParallel does) and
// compares with the reference, with and without gains.
void expectLikeReference(const cv::Mat& src, cv::Size dst, int blocks,
                         const std::array<float, 3>* gains) {
  SCOPED_TRACE(std::to_string(src.cols) + "x" + std::to_string(src.rows) + " -> " +
               std::to_string(dst.width) + "x" + std::to_string(dst.height) + ", " +
               std::to_string(blocks) + " block(s), " + name(kernels::activeIsa()) +
               (gains != nullptr ? ", gains" : ""));
  AreaResizer resizer;
  std::string why;
  ASSERT_TRUE(resizer.init(src.size(), dst, blocks, &why)) << why;
  // The output sits in a larger image (the working image with its padding).
  cv::Mat canvas(dst.height + 3, dst.width + 5, CV_8UC3, cv::Scalar::all(128));
  cv::Mat ours = canvas(cv::Rect(0, 0, dst.width, dst.height));
  cv::Mat gained(src.size(), CV_8UC3, cv::Scalar::all(7));
  for (int b = 0; b < blocks; ++b) {
    const int begin = dst.height * b / blocks;
    const int end = dst.height * (b + 1) / blocks;
    resizer.applyRows(src, ours, begin, end, b, gains, gains != nullptr ? &gained : nullptr);
  }
  const cv::Mat input = gains != nullptr ? referenceBalanced(src, *gains) : src;
  const cv::Mat reference = referenceAreaResize(input, dst);
  EXPECT_EQ(maxDifference(ours, reference), 0.0);
  if (gains != nullptr) {
    // Every source row written once, as the tables make it.
    EXPECT_EQ(maxDifference(gained, input), 0.0);
  }
  // The padding beyond the output is untouched.
  EXPECT_EQ(canvas.at<cv::Vec3b>(dst.height + 2, dst.width + 4), cv::Vec3b(128, 128, 128));
  EXPECT_EQ(canvas.at<cv::Vec3b>(0, dst.width), cv::Vec3b(128, 128, 128));
}

TEST_F(EveryIsa, ResizeEqualsOpenCvOnEverySizeAndSplit) {
  const cv::Mat camera = test::syntheticCarFrame(2592, 2048, 11, 40);
  const cv::Mat noise = randomImage({2592, 2048}, 12);
  const double rung = kDefaultWorkingScale * kScaleStep;
  const cv::Size rungSize(static_cast<int>(std::nearbyint(2592 * rung)),
                          static_cast<int>(std::nearbyint(2048 * rung)));
  for (const Isa isa : available()) {
    ASSERT_EQ(kernels::limitIsa(isa), isa);
    for (const int blocks : {1, 3}) {
      expectLikeReference(camera, {648, 512}, blocks, nullptr);  // 4 x 4: the default
      expectLikeReference(noise, {648, 512}, blocks, nullptr);
      expectLikeReference(noise, rungSize, blocks, nullptr);       // a ladder rung: fractional
      expectLikeReference(camera, {1296, 1024}, blocks, nullptr);  // 2 x 2: half up
      expectLikeReference(noise, {81, 64}, blocks, nullptr);       // 32 x 32: 32-bit sums
    }
    // Odd sizes: integer 3 x 3, non-square factors, slivers, a single output pixel, 1 px wide.
    expectLikeReference(randomImage({99, 63}, 1), {33, 21}, 2, nullptr);
    expectLikeReference(randomImage({100, 63}, 2), {50, 21}, 2, nullptr);
    expectLikeReference(randomImage({101, 77}, 3), {37, 29}, 2, nullptr);
    expectLikeReference(randomImage({640, 480}, 4), {639, 479}, 3, nullptr);
    expectLikeReference(randomImage({13, 11}, 5), {1, 1}, 1, nullptr);
    expectLikeReference(randomImage({7, 40}, 6), {1, 9}, 2, nullptr);
    expectLikeReference(randomImage({2592, 2048}, 7), {778, 614}, 2, nullptr);  // scale 0.3
  }
}

TEST_F(EveryIsa, GainsInTheSweepEqualTheTablesThenTheResize) {
  const cv::Mat camera = test::syntheticCarFrame(2592, 2048, 21, 40);
  const cv::Mat noise = randomImage({2592, 2048}, 22);
  // Typical gains, saturating ones (bright pixels clip at 255 per pixel, before the mean),
  // gains below 1, and the clamp's extremes.
  const std::array<std::array<float, 3>, 4> gainSets{
      {{1.08F, 1.0F, 0.87F}, {2.7F, 1.35F, 3.9F}, {0.5F, 0.71F, 0.93F}, {4.0F, 0.25F, 1.0F}}};
  for (const Isa isa : available()) {
    ASSERT_EQ(kernels::limitIsa(isa), isa);
    for (const auto& gains : gainSets) {
      expectLikeReference(camera, {648, 512}, 2, &gains);
      expectLikeReference(noise, {708, 559}, 3, &gains);  // fractional, shared border rows
    }
    expectLikeReference(randomImage({101, 77}, 8), {37, 29}, 4, &gainSets[1]);
    expectLikeReference(randomImage({99, 63}, 9), {33, 21}, 2, &gainSets[1]);
    expectLikeReference(randomImage({640, 480}, 10), {639, 479}, 3, &gainSets[0]);
  }
}

// The whole preprocessor with white balance on: its corrected frame and tiles equal the
// reference's (estimate the gains, tables on the frame, OpenCV's resize), on 1 and 2 threads,
// at the default scale and a fractional rung.
TEST(FusedPreprocessor, WhiteBalancedFrameAndTilesEqualTheReference) {
  camera::Intrinsics k;
  k.width_px = 2592;
  k.height_px = 2048;
  k.fx_px = 2300.0;
  k.fy_px = 2300.0;
  k.cx_px = 1295.5;
  k.cy_px = 1023.5;
  camera::CameraModel camera;
  ASSERT_TRUE(camera.init(k, camera::Distortion{}));
  cv::Mat frame = test::syntheticCarFrame(2592, 2048, 31, 60);
  // A warm cast and some clipped highlights, so that the gains differ and saturate.
  frame.forEach<cv::Vec3b>([](cv::Vec3b& p, const int* position) {
    p[2] = cv::saturate_cast<std::uint8_t>(p[2] * 1.25 + (position[1] % 97 == 0 ? 120 : 0));
  });
  for (const double scale : {kDefaultWorkingScale, kDefaultWorkingScale * kScaleStep}) {
    for (const int threads : {1, 2}) {
      SCOPED_TRACE("scale " + std::to_string(scale) + ", threads " + std::to_string(threads));
      PreprocessOptions options;
      options.whiteBalance = true;
      options.workingScale = scale;
      options.threads = threads;
      Preprocessor pre;
      std::string why;
      ASSERT_TRUE(pre.init(options, camera, frame.size(), &why)) << why;
      ASSERT_EQ(pre.process(frame), PreprocessStatus::Ok) << pre.lastError();
      const PreprocessedFrame& out = pre.output();
      ASSERT_TRUE(out.whiteBalance.found);

      WhiteBalancer balancer;
      ASSERT_TRUE(balancer.init(options.whiteBalanceOptions, frame.size()));
      const WhiteBalanceGains gains = balancer.estimate(frame);
      EXPECT_EQ(gains.gain, out.whiteBalance.gain);
      const cv::Mat balanced = referenceBalanced(frame, gains.gain);
      EXPECT_EQ(maxDifference(out.frame, balanced), 0.0);
      const cv::Size working(out.geometry.workingWidth_px, out.geometry.workingHeight_px);
      const cv::Mat small = referenceAreaResize(balanced, working);
      const TileView& tile = out.tiles[0];
      const cv::Mat tileMat(tile.rect.height_px, tile.rect.width_px, CV_8UC3,
                            const_cast<std::uint8_t*>(tile.data), tile.strideBytes);
      const cv::Rect inTile(0, 0, std::min(working.width, tile.rect.width_px),
                            std::min(working.height, tile.rect.height_px));
      EXPECT_EQ(maxDifference(tileMat(inTile), small(inTile)), 0.0);
    }
  }
}

camera::CameraModel pinhole(int width, int height) {
  return test::pinholeCamera(width, height);
}

// A camera buffer: YUYV (2 bytes a pixel) or NV12 (Y plane, then UV rows), rows padded to
// `stride` bytes. Luma from a simulated scene (plus noise), chroma random: every U, V value.
struct CameraBuffer {
  std::vector<std::uint8_t> bytes;
  YuvFrame frame;
};

CameraBuffer cameraBuffer(YuvFrame::Layout layout, int width, int height, std::size_t stride,
                          std::uint64_t seed) {
  const cv::Mat scene = test::syntheticCarFrame(width, height, seed, 30);
  cv::RNG rng(seed);
  const bool nv12 = layout == YuvFrame::Layout::Nv12;
  CameraBuffer out;
  const auto rows = static_cast<std::size_t>(nv12 ? height + height / 2 : height);
  out.bytes.assign(stride * rows, 0xEE);  // padding bytes must not matter
  for (int y = 0; y < height; ++y) {
    std::uint8_t* row = out.bytes.data() + static_cast<std::size_t>(y) * stride;
    for (int x = 0; x < width; ++x) {
      const auto luma = static_cast<std::uint8_t>(
          std::clamp(scene.at<cv::Vec3b>(y, x)[1] + rng.uniform(-8, 9), 0, 255));
      if (nv12) {
        row[x] = luma;
      } else {
        row[2 * x] = luma;
        row[2 * x + 1] = static_cast<std::uint8_t>(rng.uniform(0, 256));
      }
    }
  }
  out.frame.layout = layout;
  out.frame.data = out.bytes.data();
  out.frame.strideBytes = stride;
  out.frame.width_px = width;
  out.frame.height_px = height;
  if (nv12) {
    std::uint8_t* uv = out.bytes.data() + stride * static_cast<std::size_t>(height);
    for (int y = 0; y < height / 2; ++y) {
      for (int x = 0; x < width; ++x) {
        uv[static_cast<std::size_t>(y) * stride + static_cast<std::size_t>(x)] =
            static_cast<std::uint8_t>(rng.uniform(0, 256));
      }
    }
    out.frame.uv = uv;
    out.frame.uvStrideBytes = stride;
  }
  return out;
}

// What the app does today: the capture converts the whole frame (the same rows), then BGR.
cv::Mat convertedFrame(const YuvFrame& f) {
  cv::Mat bgr(f.height_px, f.width_px, CV_8UC3);
  for (int y = 0; y < f.height_px; ++y) {
    const std::uint8_t* row = f.data + static_cast<std::size_t>(y) * f.strideBytes;
    if (f.layout == YuvFrame::Layout::Nv12) {
      nv12RowToBgr(row, f.uv + static_cast<std::size_t>(y / 2) * f.uvStrideBytes, f.width_px,
                   bgr.ptr<std::uint8_t>(y));
    } else {
      yuyvRowToBgr(row, f.width_px, bgr.ptr<std::uint8_t>(y));
    }
  }
  return bgr;
}

TEST(YuvRows, MatchOpenCvsConversionWithinOneLevel) {
  for (const auto layout : {YuvFrame::Layout::Yuyv, YuvFrame::Layout::Nv12}) {
    const bool nv12 = layout == YuvFrame::Layout::Nv12;
    const CameraBuffer buffer = cameraBuffer(layout, 320, 240, nv12 ? 320 : 640, 3);
    const cv::Mat ours = convertedFrame(buffer.frame);
    cv::Mat theirs;
    if (nv12) {
      const cv::Mat planes(360, 320, CV_8UC1, const_cast<std::uint8_t*>(buffer.bytes.data()));
      cv::cvtColor(planes, theirs, cv::COLOR_YUV2BGR_NV12);
    } else {
      const cv::Mat packed(240, 320, CV_8UC2, const_cast<std::uint8_t*>(buffer.bytes.data()));
      cv::cvtColor(packed, theirs, cv::COLOR_YUV2BGR_YUYV);
    }
    EXPECT_LE(maxDifference(ours, theirs), 1.0) << (nv12 ? "NV12" : "YUYV");
  }
}

TEST_F(EveryIsa, YuvRowsAreTheSameOnEveryInstructionSet) {
  // Odd tails (width not a multiple of 8) and every byte value.
  for (const auto layout : {YuvFrame::Layout::Yuyv, YuvFrame::Layout::Nv12}) {
    const bool nv12 = layout == YuvFrame::Layout::Nv12;
    for (const int width : {2592, 322, 6}) {
      CameraBuffer buffer = cameraBuffer(layout, width, 64, nv12 ? width : 2 * width, 4);
      cv::RNG rng(9);
      for (std::uint8_t& byte : buffer.bytes) {
        byte = static_cast<std::uint8_t>(rng.uniform(0, 256));
      }
      kernels::limitIsa(Isa::Scalar);
      const cv::Mat scalar = convertedFrame(buffer.frame);
      for (const Isa isa : available()) {
        ASSERT_EQ(kernels::limitIsa(isa), isa);
        EXPECT_EQ(maxDifference(convertedFrame(buffer.frame), scalar), 0.0)
            << name(isa) << (nv12 ? " NV12 " : " YUYV ") << width;
      }
    }
  }
}

// The direct camera path: tiles equal to converting the whole frame and then preprocessing
// it, for both layouts, padded strides, the default and a fractional scale, 1 and 2 threads,
// every instruction set; no full-size frame and no allocation per frame.
TEST_F(EveryIsa, CameraLayoutsGoStraightToTheWorkingImage) {
  const camera::CameraModel camera = pinhole(2592, 2048);
  const CameraBuffer yuyv = cameraBuffer(YuvFrame::Layout::Yuyv, 2592, 2048, 2592 * 2 + 64, 41);
  const CameraBuffer nv12 = cameraBuffer(YuvFrame::Layout::Nv12, 2592, 2048, 2592 + 32, 42);
  for (const Isa isa : available()) {
    ASSERT_EQ(kernels::limitIsa(isa), isa);
    for (const CameraBuffer* buffer : {&yuyv, &nv12}) {
      const cv::Mat converted = convertedFrame(buffer->frame);
      for (const double scale : {kDefaultWorkingScale, kDefaultWorkingScale * kScaleStep}) {
        for (const int threads : {1, 2}) {
          SCOPED_TRACE(std::string(name(isa)) + ", " + (buffer == &nv12 ? "NV12" : "YUYV") +
                       ", scale " + std::to_string(scale) + ", threads " + std::to_string(threads));
          PreprocessOptions options;
          options.workingScale = scale;
          options.threads = threads;
          Preprocessor direct;
          Preprocessor viaBgr;
          ASSERT_TRUE(direct.init(options, camera, {2592, 2048}));
          ASSERT_TRUE(viaBgr.init(options, camera, {2592, 2048}));
          ASSERT_EQ(direct.process(buffer->frame), PreprocessStatus::Ok) << direct.lastError();
          ASSERT_EQ(viaBgr.process(converted), PreprocessStatus::Ok);
          EXPECT_TRUE(direct.output().frame.empty());
          ASSERT_EQ(direct.output().tiles.size(), viaBgr.output().tiles.size());
          for (std::size_t t = 0; t < direct.output().tiles.size(); ++t) {
            const TileView& a = direct.output().tiles[t];
            const TileView& b = viaBgr.output().tiles[t];
            const cv::Mat tileA(a.rect.height_px, a.rect.width_px, CV_8UC3,
                                const_cast<std::uint8_t*>(a.data), a.strideBytes);
            const cv::Mat tileB(b.rect.height_px, b.rect.width_px, CV_8UC3,
                                const_cast<std::uint8_t*>(b.data), b.strideBytes);
            EXPECT_EQ(maxDifference(tileA, tileB), 0.0) << "tile " << t;
          }
          if (isa == available().back() && scale == kDefaultWorkingScale) {
            test::AllocationCounter counter;
            ASSERT_EQ(direct.process(buffer->frame), PreprocessStatus::Ok);
            counter.stop();
            EXPECT_EQ(counter.count(), 0U);
          }
        }
      }
    }
  }
}

TEST(FusedPreprocessor, CameraFramesItCannotTakeAreStatusesNamingWhy) {
  const camera::CameraModel camera = pinhole(2592, 2048);
  CameraBuffer buffer = cameraBuffer(YuvFrame::Layout::Nv12, 2592, 2048, 2592, 5);
  Preprocessor pre;
  EXPECT_EQ(pre.process(buffer.frame), PreprocessStatus::NotInitialised);
  ASSERT_TRUE(pre.init(PreprocessOptions{}, camera, {2592, 2048}));
  YuvFrame frame = buffer.frame;
  frame.data = nullptr;
  EXPECT_EQ(pre.process(frame), PreprocessStatus::EmptyFrame);
  frame = buffer.frame;
  frame.width_px = 1296;
  EXPECT_EQ(pre.process(frame), PreprocessStatus::WrongFrameSize);
  EXPECT_NE(std::string(pre.lastError()).find("NV12 frame is 1296x2048, expected 2592x2048"),
            std::string::npos)
      << pre.lastError();
  frame = buffer.frame;
  frame.uv = nullptr;
  EXPECT_EQ(pre.process(frame), PreprocessStatus::WrongFrameType);
  EXPECT_NE(std::string(pre.lastError()).find("no UV plane"), std::string::npos) << pre.lastError();
  frame = buffer.frame;
  frame.strideBytes = 2000;
  EXPECT_EQ(pre.process(frame), PreprocessStatus::WrongFrameType);
  ASSERT_EQ(pre.process(buffer.frame), PreprocessStatus::Ok);
  EXPECT_STREQ(pre.lastError(), "");

  PreprocessOptions balanced;
  balanced.whiteBalance = true;
  ASSERT_TRUE(pre.init(balanced, camera, {2592, 2048}));
  EXPECT_EQ(pre.process(buffer.frame), PreprocessStatus::WrongFrameType);
  EXPECT_NE(std::string(pre.lastError()).find("white balance need a BGR frame"), std::string::npos)
      << pre.lastError();

  const camera::CameraModel odd = pinhole(2591, 2048);
  ASSERT_TRUE(pre.init(PreprocessOptions{}, odd, {2591, 2048}));
  CameraBuffer oddBuffer = cameraBuffer(YuvFrame::Layout::Yuyv, 2590, 2048, 2591 * 2, 6);
  oddBuffer.frame.width_px = 2591;
  EXPECT_EQ(pre.process(oddBuffer.frame), PreprocessStatus::WrongFrameType);
  EXPECT_NE(std::string(pre.lastError()).find("width must be even"), std::string::npos)
      << pre.lastError();
}

}  // namespace
}  // namespace vp::preprocess
