#include "camera/undistorter.hpp"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace vp::camera {
namespace {

Intrinsics smallIntrinsics(double focal_px) {
  Intrinsics k;
  k.width_px = 640;
  k.height_px = 512;
  k.fx_px = focal_px;
  k.fy_px = focal_px * 1.004;
  k.cx_px = 321.7;
  k.cy_px = 254.2;
  return k;
}

CameraModel brownConradyCamera() {
  Distortion d;
  d.model = LensModel::BrownConrady;
  d.k1 = -0.28;
  d.k2 = 0.09;
  d.p1 = 4e-4;
  d.p2 = -6e-4;
  d.k3 = -0.01;
  CameraModel camera;
  EXPECT_TRUE(camera.init(smallIntrinsics(520.0), d));
  return camera;
}

CameraModel sphericalCamera() {
  Distortion d;
  d.model = LensModel::EquivalentSpherical;
  CameraModel camera;
  EXPECT_TRUE(camera.init(smallIntrinsics(350.0), d));
  return camera;
}

// A smooth texture on a plane parallel to the image plane, so that an ideal pinhole sees
// it as a function of the normalised coordinates. Smooth (period ~28 px at the smaller focal
// length) so bilinear interpolation itself contributes little error and the comparison tests the
// geometry.
double texture(const Eigen::Vector2d& normalised) {
  const double period = 0.08;
  return 128.0 + 100.0 * std::sin(2.0 * std::numbers::pi * normalised.x() / period) *
                     std::cos(2.0 * std::numbers::pi * normalised.y() / period);
}

// What an ideal pinhole camera with intrinsics k sees.
cv::Mat renderIdeal(const Intrinsics& k) {
  cv::Mat image(k.height_px, k.width_px, CV_8UC1);
  for (int v = 0; v < k.height_px; ++v) {
    for (int u = 0; u < k.width_px; ++u) {
      const Eigen::Vector2d xy((u - k.cx_px) / k.fx_px, (v - k.cy_px) / k.fy_px);
      image.at<uint8_t>(v, u) = cv::saturate_cast<uint8_t>(texture(xy));
    }
  }
  return image;
}

// What the distorting lens sees: each sensor pixel looks along its undistorted ray. The
// rays come from an oracle independent of CameraModel::undistort (OpenCV's iterative
// undistortPoints, or the seed's closed form), so the test does not grade itself.
cv::Mat renderDistorted(const CameraModel& camera) {
  const Intrinsics& k = camera.intrinsics();
  std::vector<cv::Point2d> pixels;
  pixels.reserve(static_cast<size_t>(k.width_px) * k.height_px);
  for (int v = 0; v < k.height_px; ++v) {
    for (int u = 0; u < k.width_px; ++u) {
      pixels.emplace_back(u, v);
    }
  }
  std::vector<cv::Point2d> normalised;
  const Distortion& d = camera.distortion();
  if (d.model == LensModel::BrownConrady) {
    const cv::Matx33d cameraMatrix(k.fx_px, 0.0, k.cx_px, 0.0, k.fy_px, k.cy_px, 0.0, 0.0, 1.0);
    cv::undistortPoints(
        pixels, normalised, cameraMatrix, cv::Vec<double, 5>(d.k1, d.k2, d.p1, d.p2, d.k3),
        cv::noArray(), cv::noArray(),
        cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-6));
  } else {
    for (const cv::Point2d& p : pixels) {
      const cv::Point2d xd((p.x - k.cx_px) / k.fx_px, (p.y - k.cy_px) / k.fy_px);
      const double rd = std::hypot(xd.x, xd.y);
      const double scale = rd > 0.0 ? std::tan(2.0 * std::asin(rd / 2.0)) / rd : 1.0;
      normalised.push_back(xd * scale);
    }
  }
  cv::Mat image(k.height_px, k.width_px, CV_8UC1);
  for (int v = 0; v < k.height_px; ++v) {
    for (int u = 0; u < k.width_px; ++u) {
      const cv::Point2d& xy = normalised[static_cast<size_t>(v) * k.width_px + u];
      image.at<uint8_t>(v, u) = cv::saturate_cast<uint8_t>(texture({xy.x, xy.y}));
    }
  }
  return image;
}

struct Comparison {
  double meanAbsDiff = 0.0;
  double maxAbsDiff = 0.0;
  int pixels = 0;
};

// Compares the undistorted frame with the ideal one where the source pixel lies well
// inside the distorted frame (the rest is legitimately black).
Comparison compareInterior(const CameraModel& camera, const Intrinsics& out,
                           const cv::Mat& undistorted, const cv::Mat& ideal) {
  Comparison c;
  double sum = 0.0;
  for (int v = 0; v < out.height_px; ++v) {
    for (int u = 0; u < out.width_px; ++u) {
      const Eigen::Vector2d xy((u - out.cx_px) / out.fx_px, (v - out.cy_px) / out.fy_px);
      const Eigen::Vector2d source =
          camera.distortPixel({camera.intrinsics().cx_px + camera.intrinsics().fx_px * xy.x(),
                               camera.intrinsics().cy_px + camera.intrinsics().fy_px * xy.y()});
      if (!camera.inImage(source, 2.0)) {
        continue;
      }
      const double diff = std::abs(undistorted.at<uint8_t>(v, u) - ideal.at<uint8_t>(v, u));
      sum += diff;
      c.maxAbsDiff = std::max(c.maxAbsDiff, diff);
      ++c.pixels;
    }
  }
  c.meanAbsDiff = sum / std::max(1, c.pixels);
  return c;
}

void expectUndistortsToIdeal(const CameraModel& camera, const Intrinsics& out, const char* label) {
  Undistorter undistorter;
  std::string why;
  ASSERT_TRUE(undistorter.init(camera, out, &why)) << why;
  EXPECT_EQ(undistorter.outputSize(), cv::Size(out.width_px, out.height_px));

  const cv::Mat distorted = renderDistorted(camera);
  const cv::Mat ideal = renderIdeal(out);
  cv::Mat undistorted(undistorter.outputSize(), distorted.type());
  ASSERT_TRUE(undistorter.apply(distorted, undistorted));

  // The distortion is large: without correction the images disagree badly.
  const Comparison before = compareInterior(camera, out, distorted, ideal);
  const Comparison after = compareInterior(camera, out, undistorted, ideal);
  std::printf("[ %s ] mean |diff| %.2f -> %.2f grey levels (max %.0f) over %d px\n", label,
              before.meanAbsDiff, after.meanAbsDiff, after.maxAbsDiff, after.pixels);
  EXPECT_GT(after.pixels, out.width_px * out.height_px / 3);
  EXPECT_LT(after.meanAbsDiff, 1.0);
  EXPECT_LT(after.maxAbsDiff, 8.0);  // bilinear + 1/32 px map quantisation at peak slopes
  EXPECT_GT(before.meanAbsDiff, 10.0 * after.meanAbsDiff);
}

TEST(Undistorter, BrownConradyFrameMatchesIdealPinhole) {
  const CameraModel camera = brownConradyCamera();
  expectUndistortsToIdeal(camera, camera.intrinsics(), "brown_conrady");
}

TEST(Undistorter, EquivalentSphericalFrameMatchesIdealPinhole) {
  const CameraModel camera = sphericalCamera();
  expectUndistortsToIdeal(camera, camera.intrinsics(), "equivalent_spherical");
}

TEST(Undistorter, ChosenOutputIntrinsics) {
  // A narrower, smaller output camera (zoom on the centre) for both models.
  for (const CameraModel& camera : {brownConradyCamera(), sphericalCamera()}) {
    Intrinsics out;
    out.width_px = 400;
    out.height_px = 300;
    out.fx_px = out.fy_px = 1.3 * camera.intrinsics().fx_px;
    out.cx_px = 199.5;
    out.cy_px = 149.5;
    expectUndistortsToIdeal(camera, out, toString(camera.distortion().model));
  }
}

TEST(Undistorter, PinholeIsAnExactCopy) {
  Distortion d;
  CameraModel camera;
  ASSERT_TRUE(camera.init(smallIntrinsics(500.0), d));
  Undistorter undistorter;
  ASSERT_TRUE(undistorter.init(camera));
  cv::Mat src(512, 640, CV_8UC3);
  cv::randu(src, cv::Scalar::all(0), cv::Scalar::all(255));
  cv::Mat dst(512, 640, CV_8UC3);
  ASSERT_TRUE(undistorter.apply(src, dst));
  EXPECT_EQ(cv::norm(src, dst, cv::NORM_INF), 0.0);
}

TEST(Undistorter, BlanksOutputBeyondTheFoldOver) {
  // k1 = -0.3 folds at an ideal radius of 1.054 while the image corner is at ~1.37: past
  // the fold the polynomial maps output pixels back into the frame as a mirrored ghost.
  Distortion d;
  d.model = LensModel::BrownConrady;
  d.k1 = -0.3;
  CameraModel camera;
  ASSERT_TRUE(camera.init(smallIntrinsics(300.0), d));
  Undistorter undistorter;
  ASSERT_TRUE(undistorter.init(camera));
  const cv::Mat src(512, 640, CV_8UC1, cv::Scalar(200));
  cv::Mat dst(512, 640, CV_8UC1, cv::Scalar(7));
  ASSERT_TRUE(undistorter.apply(src, dst));
  const Intrinsics& k = camera.intrinsics();
  int beyond = 0;
  int inside = 0;
  for (int v = 0; v < k.height_px; ++v) {
    for (int u = 0; u < k.width_px; ++u) {
      const double r = std::hypot((u - k.cx_px) / k.fx_px, (v - k.cy_px) / k.fy_px);
      if (r > camera.maxIdealRadius() + 0.01) {
        EXPECT_EQ(dst.at<uint8_t>(v, u), 0) << u << "," << v;
        ++beyond;
      } else if (r < 0.8) {
        EXPECT_EQ(dst.at<uint8_t>(v, u), 200) << u << "," << v;
        ++inside;
      }
    }
  }
  EXPECT_GT(beyond, 1000);
  EXPECT_GT(inside, 1000);
}

TEST(Undistorter, ApplyReusesTheDestinationBuffer) {
  const CameraModel camera = brownConradyCamera();
  Undistorter undistorter;
  ASSERT_TRUE(undistorter.init(camera));
  for (int type : {CV_8UC1, CV_8UC3, CV_16UC1, CV_32FC1}) {
    cv::Mat src(512, 640, type, cv::Scalar::all(100));
    cv::Mat dst(undistorter.outputSize(), type);
    const uint8_t* before = dst.data;
    ASSERT_TRUE(undistorter.apply(src, dst));
    ASSERT_TRUE(undistorter.apply(src, dst));
    EXPECT_EQ(dst.data, before) << type;
    EXPECT_EQ(dst.type(), type);
    EXPECT_EQ(dst.size(), undistorter.outputSize());
  }
  // Also into a view of a larger buffer (e.g. a slot of a preallocated frame pool).
  cv::Mat pool(600, 700, CV_8UC1, cv::Scalar(9));
  cv::Mat view = pool(cv::Rect(10, 20, 640, 512));
  const uint8_t* before = view.data;
  ASSERT_TRUE(undistorter.apply(cv::Mat(512, 640, CV_8UC1, cv::Scalar(50)), view));
  EXPECT_EQ(view.data, before);
  EXPECT_EQ(pool.at<uint8_t>(0, 0), 9);  // outside the view untouched
  EXPECT_EQ(pool.at<uint8_t>(20 + 256, 10 + 320), 50);
}

TEST(Undistorter, RejectsMismatchesWithoutTouchingDst) {
  const CameraModel camera = brownConradyCamera();
  Undistorter undistorter;
  cv::Mat dst(512, 640, CV_8UC1, cv::Scalar(7));
  const cv::Mat src(512, 640, CV_8UC1, cv::Scalar(100));
  EXPECT_FALSE(undistorter.apply(src, dst));  // not initialised
  ASSERT_TRUE(undistorter.init(camera));

  EXPECT_FALSE(undistorter.apply(cv::Mat(), dst));                                       // empty
  EXPECT_FALSE(undistorter.apply(cv::Mat(512, 641, CV_8UC1, cv::Scalar(1)), dst));       // src size
  EXPECT_FALSE(undistorter.apply(cv::Mat(256, 320, CV_8UC1, cv::Scalar(1)), dst));       // src size
  EXPECT_FALSE(undistorter.apply(cv::Mat(512, 640, CV_8UC3, cv::Scalar::all(1)), dst));  // type
  cv::Mat wrongSize(500, 640, CV_8UC1, cv::Scalar(7));
  EXPECT_FALSE(undistorter.apply(src, wrongSize));
  EXPECT_EQ(wrongSize.size(), cv::Size(640, 500));
  cv::Mat emptyDst;
  EXPECT_FALSE(undistorter.apply(src, emptyDst));
  EXPECT_TRUE(emptyDst.empty());
  cv::Mat inPlace = src.clone();
  EXPECT_FALSE(undistorter.apply(inPlace, inPlace));
  EXPECT_EQ(cv::countNonZero(dst != 7), 0);

  ASSERT_TRUE(undistorter.apply(src, dst));
  EXPECT_EQ(dst.at<uint8_t>(256, 320), 100);
}

TEST(Undistorter, InitValidatesOutput) {
  const CameraModel camera = brownConradyCamera();
  Undistorter undistorter;
  std::string why;
  Intrinsics out = camera.intrinsics();
  out.width_px = 0;
  EXPECT_FALSE(undistorter.init(camera, out, &why));
  EXPECT_NE(why.find("output size"), std::string::npos) << why;
  out = camera.intrinsics();
  out.fy_px = -1.0;
  EXPECT_FALSE(undistorter.init(camera, out, &why));
  EXPECT_NE(why.find("fy_px"), std::string::npos) << why;
  EXPECT_FALSE(undistorter.init(CameraModel{}, &why));
  EXPECT_NE(why.find("not initialised"), std::string::npos) << why;
}

}  // namespace
}  // namespace vp::camera
