// FrameRemap: the undistorted frame agrees with the CameraModel (a texture seen through the
// lens comes out as the ideal pinhole sees it) and with camera::Undistorter (cv::remap).
#include "preprocess/frame_remap.hpp"

#include <cmath>
#include <cstdio>
#include <numbers>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "camera/undistorter.hpp"

namespace vp::preprocess {
namespace {

camera::Intrinsics intrinsics(double focal_px) {
  camera::Intrinsics k;
  k.width_px = 640;
  k.height_px = 512;
  k.fx_px = focal_px;
  k.fy_px = focal_px * 1.003;
  k.cx_px = 318.4;
  k.cy_px = 259.1;
  return k;
}

camera::CameraModel brownConrady() {
  camera::Distortion d;
  d.model = camera::LensModel::BrownConrady;
  d.k1 = -0.25;
  d.k2 = 0.07;
  d.p1 = 3e-4;
  d.p2 = -5e-4;
  d.k3 = -0.008;
  camera::CameraModel camera;
  EXPECT_TRUE(camera.init(intrinsics(540.0), d));
  return camera;
}

camera::CameraModel spherical() {
  camera::Distortion d;
  d.model = camera::LensModel::EquivalentSpherical;
  camera::CameraModel camera;
  EXPECT_TRUE(camera.init(intrinsics(380.0), d));
  return camera;
}

// Smooth texture as a function of ideal normalised coordinates (period 0.07 ~ 26 px), so
// bilinear interpolation adds little error and the comparison tests the geometry.
double texture(double x, double y, int channel) {
  const double period = 0.07;
  const double phase = 0.7 * channel;
  return 128.0 + 100.0 * std::sin(2.0 * std::numbers::pi * x / period + phase) *
                     std::cos(2.0 * std::numbers::pi * y / period);
}

// What the distorted camera records: each pixel shows the texture at its ideal ray.
cv::Mat renderDistorted(const camera::CameraModel& camera) {
  const camera::Intrinsics& k = camera.intrinsics();
  cv::Mat image(k.height_px, k.width_px, CV_8UC3, cv::Scalar::all(0));
  for (int v = 0; v < k.height_px; ++v) {
    for (int u = 0; u < k.width_px; ++u) {
      const auto ideal = camera.undistortToNormalized(Eigen::Vector2d(u, v));
      if (!ideal) {
        continue;
      }
      for (int c = 0; c < 3; ++c) {
        image.at<cv::Vec3b>(v, u)[c] =
            cv::saturate_cast<std::uint8_t>(texture(ideal->x(), ideal->y(), c));
      }
    }
  }
  return image;
}

void expectMatchesIdealPinhole(const camera::CameraModel& camera) {
  const camera::Intrinsics& k = camera.intrinsics();
  FrameRemap remap;
  std::string why;
  ASSERT_TRUE(remap.init(camera, k, &why)) << why;
  const cv::Mat distorted = renderDistorted(camera);
  cv::Mat undistorted(k.height_px, k.width_px, CV_8UC3, cv::Scalar::all(0));
  ASSERT_TRUE(remap.apply(distorted, undistorted));
  // Compare with the ideal pinhole view where the source lies well inside the frame.
  double sumError = 0.0;
  double maxError = 0.0;
  int count = 0;
  for (int v = 0; v < k.height_px; v += 3) {
    for (int u = 0; u < k.width_px; u += 3) {
      const Eigen::Vector2d ideal((u - k.cx_px) / k.fx_px, (v - k.cy_px) / k.fy_px);
      const Eigen::Vector2d source = camera.distortPixel(Eigen::Vector2d(u, v));
      if (!camera.inImage(source, -3.0)) {
        continue;
      }
      for (int c = 0; c < 3; ++c) {
        const double error =
            std::abs(undistorted.at<cv::Vec3b>(v, u)[c] - texture(ideal.x(), ideal.y(), c));
        sumError += error;
        maxError = std::max(maxError, error);
        ++count;
      }
    }
  }
  ASSERT_GT(count, 10000);
  std::printf("  %s: mean |error| %.3f, max %.1f levels over %d samples\n",
              camera::toString(camera.distortion().model), sumError / count, maxError, count);
  // A 0.1 px geometric error would already cost ~2.4 levels on this texture's slopes.
  EXPECT_LT(sumError / count, 1.0) << "mean |error|";
  EXPECT_LT(maxError, 8.0);
}

TEST(FrameRemap, BrownConradyFrameMatchesCameraModel) {
  expectMatchesIdealPinhole(brownConrady());
}

TEST(FrameRemap, EquivalentSphericalFrameMatchesCameraModel) {
  expectMatchesIdealPinhole(spherical());
}

TEST(FrameRemap, SameResultAsUndistorter) {
  cv::Mat frame(512, 640, CV_8UC3);
  cv::RNG rng(11);
  rng.fill(frame, cv::RNG::UNIFORM, 0, 256);
  for (const camera::CameraModel& camera : {spherical(), brownConrady()}) {
    SCOPED_TRACE(camera::toString(camera.distortion().model));
    FrameRemap remap;
    ASSERT_TRUE(remap.init(camera, camera.intrinsics()));
    camera::Undistorter undistorter;
    ASSERT_TRUE(undistorter.init(camera));
    cv::Mat ours(512, 640, CV_8UC3);
    cv::Mat theirs(512, 640, CV_8UC3);
    ASSERT_TRUE(remap.apply(frame, ours));
    ASSERT_TRUE(undistorter.apply(frame, theirs));
    cv::Mat diff;
    cv::absdiff(ours, theirs, diff);
    const double differing = cv::countNonZero(diff.reshape(1)) / (3.0 * 512 * 640);
    double maxDiff = 0.0;
    cv::minMaxLoc(diff.reshape(1), nullptr, &maxDiff);
    std::printf("  %s: %.4f %% of values differ from Undistorter, max %.0f\n",
                camera::toString(camera.distortion().model), 100.0 * differing, maxDiff);
    if (camera.distortion().model == camera::LensModel::EquivalentSpherical) {
      // The same map (both evaluate CameraModel) and cv::remap's arithmetic: identical.
      EXPECT_EQ(maxDiff, 0.0);
    } else {
      // OpenCV builds its Brown-Conrady map itself (initUndistortRectifyMap): identical on
      // OpenCV 4.6; a 1/32 px rounding flip here and there would still be the same frame.
      EXPECT_LE(maxDiff, 1.0);
      EXPECT_LT(differing, 0.001);
    }
  }
}

TEST(FrameRemap, RowRangesComposeToTheWholeFrame) {
  const camera::CameraModel camera = brownConrady();
  FrameRemap remap;
  ASSERT_TRUE(remap.init(camera, camera.intrinsics()));
  cv::Mat frame(512, 640, CV_8UC3);
  cv::RNG rng(5);
  rng.fill(frame, cv::RNG::UNIFORM, 0, 256);
  cv::Mat whole(512, 640, CV_8UC3);
  cv::Mat parts(512, 640, CV_8UC3, cv::Scalar::all(7));
  ASSERT_TRUE(remap.apply(frame, whole));
  remap.applyRows(frame, parts, 0, 200);
  remap.applyRows(frame, parts, 200, 512);
  EXPECT_EQ(cv::norm(whole, parts, cv::NORM_INF), 0.0);
}

TEST(FrameRemap, RefusesMismatchedBuffers) {
  const camera::CameraModel camera = spherical();
  FrameRemap remap;
  ASSERT_TRUE(remap.init(camera, camera.intrinsics()));
  cv::Mat frame(512, 640, CV_8UC3, cv::Scalar::all(9));
  cv::Mat small(100, 100, CV_8UC3);
  cv::Mat grey(512, 640, CV_8UC1);
  cv::Mat out(512, 640, CV_8UC3, cv::Scalar::all(1));
  EXPECT_FALSE(remap.apply(small, out));
  EXPECT_FALSE(remap.apply(grey, out));
  EXPECT_FALSE(remap.apply(frame, frame));  // in place
  EXPECT_EQ(out.at<cv::Vec3b>(0, 0), cv::Vec3b(1, 1, 1));
  FrameRemap empty;
  EXPECT_FALSE(empty.apply(frame, out));
  std::string why;
  camera::Intrinsics bad = camera.intrinsics();
  bad.fx_px = -1.0;
  EXPECT_FALSE(remap.init(camera, bad, &why));
  EXPECT_NE(why.find("fx_px"), std::string::npos) << why;
}

}  // namespace
}  // namespace vp::preprocess
