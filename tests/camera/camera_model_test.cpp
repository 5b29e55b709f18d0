#include "camera/camera_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>

namespace vp::camera {
namespace {

// A 5 MP machine-vision camera with a realistic mildly barrel-distorting lens.
Intrinsics sensorIntrinsics() {
  Intrinsics k;
  k.width_px = 2592;
  k.height_px = 2048;
  k.fx_px = 2900.0;
  k.fy_px = 2904.0;
  k.cx_px = 1299.3;
  k.cy_px = 1021.8;
  return k;
}

Distortion realisticBrownConrady() {
  Distortion d;
  d.model = LensModel::BrownConrady;
  d.k1 = -0.12;
  d.k2 = 0.08;
  d.p1 = 1e-4;
  d.p2 = -2e-4;
  d.k3 = -0.01;
  return d;
}

CameraModel brownConradyCamera() {
  CameraModel camera;
  EXPECT_TRUE(camera.init(sensorIntrinsics(), realisticBrownConrady()));
  return camera;
}

// Wide-angle spherical camera: the image corner is ~65 deg off-axis, with fx != fy so the
// per-axis normalisation is exercised.
CameraModel sphericalCamera() {
  Intrinsics k = sensorIntrinsics();
  k.fx_px = 1500.0;
  k.fy_px = 1512.0;
  Distortion d;
  d.model = LensModel::EquivalentSpherical;
  CameraModel camera;
  EXPECT_TRUE(camera.init(k, d));
  return camera;
}

cv::Matx33d cameraMatrix(const Intrinsics& k) {
  return {k.fx_px, 0.0, k.cx_px, 0.0, k.fy_px, k.cy_px, 0.0, 0.0, 1.0};
}

cv::Vec<double, 5> coefficients(const Distortion& d) {
  return {d.k1, d.k2, d.p1, d.p2, d.k3};
}

std::vector<Eigen::Vector2d> pixelGrid(const Intrinsics& k, int step_px) {
  std::vector<Eigen::Vector2d> pixels;
  for (int v = 0; v < k.height_px; v += step_px) {
    for (int u = 0; u < k.width_px; u += step_px) {
      pixels.emplace_back(u, v);
    }
  }
  // Include the far edges and corners exactly, where distortion is largest.
  for (int v = 0; v < k.height_px; v += step_px) {
    pixels.emplace_back(k.width_px - 1, v);
  }
  for (int u = 0; u < k.width_px; u += step_px) {
    pixels.emplace_back(u, k.height_px - 1);
  }
  pixels.emplace_back(k.width_px - 1, k.height_px - 1);
  return pixels;
}

TEST(LensModelNames, RoundTripAndRejectUnknown) {
  for (LensModel model :
       {LensModel::Pinhole, LensModel::BrownConrady, LensModel::EquivalentSpherical}) {
    const auto parsed = lensModelFromString(toString(model));
    ASSERT_TRUE(parsed.has_value()) << toString(model);
    EXPECT_EQ(*parsed, model);
  }
  EXPECT_STREQ(toString(LensModel::Pinhole), "pinhole");
  EXPECT_STREQ(toString(LensModel::BrownConrady), "brown_conrady");
  EXPECT_STREQ(toString(LensModel::EquivalentSpherical), "equivalent_spherical");
  EXPECT_FALSE(lensModelFromString("fisheye").has_value());
  EXPECT_FALSE(lensModelFromString("Pinhole").has_value());
  EXPECT_FALSE(lensModelFromString("").has_value());
}

TEST(CameraModelInit, RejectsInvalidValuesNamingTheField) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  struct Case {
    Intrinsics intrinsics;
    Distortion distortion;
    std::string expected;
  };
  std::vector<Case> cases;
  auto add = [&](auto mutate, const std::string& expected) {
    Case c{sensorIntrinsics(), realisticBrownConrady(), expected};
    mutate(c.intrinsics, c.distortion);
    cases.push_back(c);
  };
  add([](Intrinsics& k, Distortion&) { k.fx_px = -3.0; }, "fx_px must be > 0, got -3");
  add([](Intrinsics& k, Distortion&) { k.fy_px = 0.0; }, "fy_px must be > 0, got 0");
  add([&](Intrinsics& k, Distortion&) { k.fx_px = nan; }, "fx_px must be finite, got nan");
  add([](Intrinsics& k, Distortion&) { k.width_px = 0; }, "width_px must be > 0, got 0");
  add([](Intrinsics& k, Distortion&) { k.height_px = -5; }, "height_px must be > 0, got -5");
  add([&](Intrinsics& k, Distortion&) { k.cx_px = nan; }, "cx_px must be finite, got nan");
  add([&](Intrinsics& k, Distortion&) { k.cy_px = inf; }, "cy_px must be finite, got inf");
  add([&](Intrinsics&, Distortion& d) { d.k1 = inf; }, "k1 must be finite, got inf");
  add([&](Intrinsics&, Distortion& d) { d.p2 = nan; }, "p2 must be finite, got nan");
  add([&](Intrinsics&, Distortion& d) { d.k3 = -inf; }, "k3 must be finite, got -inf");

  for (const Case& c : cases) {
    CameraModel camera;
    std::string why;
    EXPECT_FALSE(camera.init(c.intrinsics, c.distortion, &why));
    EXPECT_EQ(why, c.expected);
    EXPECT_FALSE(camera.init(c.intrinsics, c.distortion));  // why is optional
  }
}

TEST(CameraModelInit, FailedInitKeepsThePreviousModel) {
  CameraModel camera = brownConradyCamera();
  Intrinsics bad = sensorIntrinsics();
  bad.fx_px = -1.0;
  EXPECT_FALSE(camera.init(bad, realisticBrownConrady()));
  EXPECT_EQ(camera.intrinsics().fx_px, 2900.0);
  EXPECT_EQ(camera.distortion().model, LensModel::BrownConrady);
}

TEST(CameraModelInit, AcceptsPrincipalPointOutsideTheImage) {
  Intrinsics k = sensorIntrinsics();
  k.cx_px = -200.0;
  k.cy_px = 3000.0;
  CameraModel camera;
  EXPECT_TRUE(camera.init(k, realisticBrownConrady()));
}

TEST(BrownConrady, DistortionMatchesProjectPoints) {
  const CameraModel camera = brownConradyCamera();
  const Intrinsics& k = camera.intrinsics();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coord(-0.55, 0.55);
  std::vector<cv::Point3d> points;
  for (int i = 0; i < 2000; ++i) {
    const double z = 1.0 + 50.0 * (i % 7);
    points.emplace_back(coord(rng) * z, coord(rng) * z, z);
  }
  std::vector<cv::Point2d> expected;
  cv::projectPoints(points, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cameraMatrix(k),
                    coefficients(camera.distortion()), expected);

  double maxError_px = 0.0;
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d p(points[i].x, points[i].y, points[i].z);
    const auto projected = camera.projectToPixel(p);
    ASSERT_TRUE(projected.hasValue()) << i;
    const Eigen::Vector2d cvPixel(expected[i].x, expected[i].y);
    maxError_px = std::max(maxError_px, (*projected - cvPixel).norm());

    const Eigen::Vector2d distorted = camera.distortNormalized(p.head<2>() / p.z());
    const Eigen::Vector2d viaNormalized(k.cx_px + k.fx_px * distorted.x(),
                                        k.cy_px + k.fy_px * distorted.y());
    maxError_px = std::max(maxError_px, (viaNormalized - cvPixel).norm());

    const Eigen::Vector2d idealPixel(k.cx_px + k.fx_px * p.x() / p.z(),
                                     k.cy_px + k.fy_px * p.y() / p.z());
    maxError_px = std::max(maxError_px, (camera.distortPixel(idealPixel) - cvPixel).norm());
  }
  EXPECT_LT(maxError_px, 1e-6);
}

TEST(BrownConrady, UndistortionMatchesUndistortPoints) {
  const CameraModel camera = brownConradyCamera();
  const Intrinsics& k = camera.intrinsics();
  const std::vector<Eigen::Vector2d> grid = pixelGrid(k, 64);
  std::vector<cv::Point2d> distorted;
  distorted.reserve(grid.size());
  for (const auto& p : grid) {
    distorted.emplace_back(p.x(), p.y());
  }
  std::vector<cv::Point2d> expected;
  // Identity R and P = K: the result is in ideal pixels. The default criteria stop after
  // 5 fixed-point iterations, far too loose for a 1e-6 px comparison.
  cv::undistortPoints(
      distorted, expected, cameraMatrix(k), coefficients(camera.distortion()), cv::noArray(),
      cameraMatrix(k),
      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 1000, 1e-12));
  double maxError_px = 0.0;
  for (size_t i = 0; i < grid.size(); ++i) {
    const auto ideal = camera.undistortPixel(grid[i]);
    ASSERT_TRUE(ideal.hasValue()) << grid[i].transpose();
    maxError_px =
        std::max(maxError_px, (*ideal - Eigen::Vector2d(expected[i].x, expected[i].y)).norm());
  }
  EXPECT_LT(maxError_px, 1e-6);
}

// Acceptance: undistort then re-distort returns the point within 0.01 px for both lens
// models, everywhere in the image.
void expectDistortedRoundTrip(const CameraModel& camera, const char* label) {
  double maxError_px = 0.0;
  int count = 0;
  for (const Eigen::Vector2d& pixel : pixelGrid(camera.intrinsics(), 16)) {
    const auto ideal = camera.undistortPixel(pixel);
    ASSERT_TRUE(ideal.hasValue()) << label << " at " << pixel.transpose() << ": "
                                  << toString(ideal.error());
    maxError_px = std::max(maxError_px, (camera.distortPixel(*ideal) - pixel).norm());
    ++count;
  }
  std::printf("[ %s ] undistort->distort over %d pixels: max error %.3g px\n", label, count,
              maxError_px);
  EXPECT_LT(maxError_px, 0.01);
  EXPECT_LT(maxError_px, 1e-6);  // what the Newton tolerance actually delivers
}

TEST(RoundTrip, UndistortThenDistortBrownConrady) {
  expectDistortedRoundTrip(brownConradyCamera(), "brown_conrady");
}

TEST(RoundTrip, UndistortThenDistortEquivalentSpherical) {
  expectDistortedRoundTrip(sphericalCamera(), "equivalent_spherical");
}

void expectIdealRoundTrip(const CameraModel& camera, const char* label) {
  double maxError_px = 0.0;
  int count = 0;
  for (const Eigen::Vector2d& idealPixel : pixelGrid(camera.intrinsics(), 16)) {
    const Eigen::Vector2d distorted = camera.distortPixel(idealPixel);
    const auto back = camera.undistortPixel(distorted);
    ASSERT_TRUE(back.hasValue()) << label << " at " << idealPixel.transpose();
    maxError_px = std::max(maxError_px, (*back - idealPixel).norm());
    ++count;
  }
  std::printf("[ %s ] distort->undistort over %d pixels: max error %.3g px\n", label, count,
              maxError_px);
  EXPECT_LT(maxError_px, 1e-6);
}

TEST(RoundTrip, DistortThenUndistortBrownConrady) {
  expectIdealRoundTrip(brownConradyCamera(), "brown_conrady");
}

TEST(RoundTrip, DistortThenUndistortEquivalentSpherical) {
  expectIdealRoundTrip(sphericalCamera(), "equivalent_spherical");
}

TEST(RoundTrip, RayThenProject) {
  for (const CameraModel& camera : {brownConradyCamera(), sphericalCamera()}) {
    double maxError_px = 0.0;
    for (const Eigen::Vector2d& pixel : pixelGrid(camera.intrinsics(), 128)) {
      const auto ray = camera.pixelToRay(pixel);
      ASSERT_TRUE(ray.hasValue());
      EXPECT_NEAR(ray->norm(), 1.0, 1e-12);
      EXPECT_GT(ray->z(), 0.0);
      const auto back = camera.projectToPixel(*ray * 37.5);  // any depth along the ray
      ASSERT_TRUE(back.hasValue());
      maxError_px = std::max(maxError_px, (*back - pixel).norm());
    }
    EXPECT_LT(maxError_px, 1e-6) << toString(camera.distortion().model);
  }
}

TEST(RoundTrip, PrincipalPointIsTheOpticalAxis) {
  for (const CameraModel& camera : {brownConradyCamera(), sphericalCamera()}) {
    const Intrinsics& k = camera.intrinsics();
    const auto ray = camera.pixelToRay({k.cx_px, k.cy_px});
    ASSERT_TRUE(ray.hasValue());
    EXPECT_LT((*ray - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
  }
}

// The seed's formula in pixels, with the centre at the principal point and f = fx = fy.
TEST(EquivalentSpherical, MatchesSeedPixelFormula) {
  Intrinsics k = sensorIntrinsics();
  k.fx_px = 1500.0;
  k.fy_px = 1500.0;
  Distortion d;
  d.model = LensModel::EquivalentSpherical;
  CameraModel camera;
  ASSERT_TRUE(camera.init(k, d));
  const double f = k.fx_px;
  for (double l1 : {0.0, 1.0, 100.0, 500.0, 1000.0, 1500.0, 2000.0}) {
    for (double angle : {0.0, 0.7, 2.0, -2.5}) {
      const Eigen::Vector2d direction(std::cos(angle), std::sin(angle));
      const Eigen::Vector2d centre(k.cx_px, k.cy_px);
      const auto ideal = camera.undistortPixel(centre + l1 * direction);
      ASSERT_TRUE(ideal.hasValue()) << l1;
      const double l2 = f * std::tan(2.0 * std::asin(l1 / (2.0 * f)));
      EXPECT_NEAR((*ideal - centre).norm(), l2, 1e-9 * std::max(1.0, l2)) << l1;
      if (l1 > 0.0) {
        // Direction from the principal point is preserved.
        EXPECT_NEAR((*ideal - centre).normalized().dot(direction), 1.0, 1e-12);
      }
      // And the forward model inverts it.
      const Eigen::Vector2d redistorted = camera.distortPixel(centre + l2 * direction);
      EXPECT_NEAR((redistorted - centre).norm(), l1, 1e-9) << l1;
    }
  }
  // Spot values: L1 = f gives 2 asin(1/2) = 60 deg, so L2 = f tan(60 deg).
  const auto sixty_deg = camera.undistortPixel({k.cx_px + f, k.cy_px});
  ASSERT_TRUE(sixty_deg.hasValue());
  EXPECT_NEAR(sixty_deg->x() - k.cx_px, f * std::sqrt(3.0), 1e-9);
}

TEST(EquivalentSpherical, AnisotropicFocalUsesNormalisedRadius) {
  const CameraModel camera = sphericalCamera();
  const Intrinsics& k = camera.intrinsics();
  const Eigen::Vector2d pixel(k.cx_px + 900.0, k.cy_px - 700.0);
  const Eigen::Vector2d xd((pixel.x() - k.cx_px) / k.fx_px, (pixel.y() - k.cy_px) / k.fy_px);
  const double rd = xd.norm();
  const Eigen::Vector2d expected = xd * (std::tan(2.0 * std::asin(rd / 2.0)) / rd);
  const auto ideal = camera.undistortToNormalized(pixel);
  ASSERT_TRUE(ideal.hasValue());
  EXPECT_LT((*ideal - expected).norm(), 1e-12);
  // Field angle of the ray equals 2 asin(r_d / 2).
  const auto ray = camera.pixelToRay(pixel);
  ASSERT_TRUE(ray.hasValue());
  EXPECT_NEAR(std::acos(ray->z()), 2.0 * std::asin(rd / 2.0), 1e-12);
}

TEST(EquivalentSpherical, ValidFieldEndsShortOfNinetyDegrees) {
  const CameraModel camera = sphericalCamera();
  const Intrinsics& k = camera.intrinsics();
  EXPECT_LT(camera.maxDistortedRadius(), std::sqrt(2.0));
  EXPECT_GT(camera.maxDistortedRadius(), std::sqrt(2.0) - 1e-3);
  // Distorted radius sqrt(2) is exactly 90 deg off-axis, and beyond that nothing exists.
  for (double rd : {std::sqrt(2.0), 1.5, 3.0}) {
    const auto ideal = camera.undistortPixel({k.cx_px + rd * k.fx_px, k.cy_px});
    ASSERT_FALSE(ideal.hasValue()) << rd;
    EXPECT_EQ(ideal.error(), CameraError::OutsideValidField);
  }
  // 80 deg off-axis projects; 89.99 deg is beyond the margin.
  const double in = 80.0 * std::numbers::pi / 180.0;
  EXPECT_TRUE(camera.projectToPixel({std::sin(in), 0.0, std::cos(in)}).hasValue());
  const double out = 89.99 * std::numbers::pi / 180.0;
  const auto beyond = camera.projectToPixel({0.0, std::sin(out), std::cos(out)});
  ASSERT_FALSE(beyond.hasValue());
  EXPECT_EQ(beyond.error(), CameraError::OutsideValidField);
}

TEST(BrownConrady, ValidFieldStopsAtTheFoldOver) {
  // r (1 - 0.3 r^2) has its maximum at r = 1/sqrt(0.9), well inside 3x the corner radius.
  Intrinsics k = sensorIntrinsics();
  k.fx_px = k.fy_px = 1000.0;
  Distortion d;
  d.model = LensModel::BrownConrady;
  d.k1 = -0.3;
  CameraModel camera;
  ASSERT_TRUE(camera.init(k, d));
  const double foldRadius = 1.0 / std::sqrt(0.9);
  EXPECT_NEAR(camera.maxIdealRadius(), foldRadius, 1e-9);
  EXPECT_NEAR(camera.maxDistortedRadius(), foldRadius * (1.0 - 0.3 * foldRadius * foldRadius),
              1e-9);

  // A point past the fold would land back inside the image: refuse it.
  const auto projected = camera.projectToPixel({1.3, 0.0, 1.0});
  ASSERT_FALSE(projected.hasValue());
  EXPECT_EQ(projected.error(), CameraError::OutsideValidField);
  EXPECT_TRUE(camera.projectToPixel({1.0, 0.0, 1.0}).hasValue());

  // Distorted radius beyond the polynomial's maximum has no preimage at all.
  const auto ideal = camera.undistortPixel({k.cx_px + 0.75 * k.fx_px, k.cy_px});
  ASSERT_FALSE(ideal.hasValue());
  EXPECT_EQ(ideal.error(), CameraError::OutsideValidField);
  // Just inside, the solution is on the monotonic branch and round-trips.
  const Eigen::Vector2d inside(k.cx_px + 0.70 * k.fx_px, k.cy_px);
  const auto near = camera.undistortPixel(inside);
  ASSERT_TRUE(near.hasValue());
  EXPECT_LE((*near - Eigen::Vector2d(k.cx_px, k.cy_px)).norm() / k.fx_px, foldRadius);
  EXPECT_LT((camera.distortPixel(*near) - inside).norm(), 1e-6);
}

TEST(BrownConrady, MonotonicLensHasFieldBeyondTheImage) {
  const CameraModel camera = brownConradyCamera();
  const Intrinsics& k = camera.intrinsics();
  const double cornerRadius = std::hypot(k.cx_px / k.fx_px, k.cy_px / k.fy_px);
  EXPECT_GT(camera.maxIdealRadius(), 1.5 * cornerRadius);
  EXPECT_GT(camera.maxDistortedRadius(), 1.5 * cornerRadius);
}

TEST(BrownConrady, UndistortNeverReturnsAWrongPoint) {
  // A pathological lens whose tangential terms fold the plane: whatever comes back must
  // either be an error or a true preimage.
  Intrinsics k = sensorIntrinsics();
  Distortion d;
  d.model = LensModel::BrownConrady;
  d.k1 = 0.5;
  d.p1 = 0.4;
  d.p2 = -0.3;
  CameraModel camera;
  ASSERT_TRUE(camera.init(k, d));
  int noConvergence = 0;
  int outside = 0;
  int solved = 0;
  for (const Eigen::Vector2d& pixel : pixelGrid(k, 64)) {
    const auto ideal = camera.undistortPixel(pixel);
    if (!ideal) {
      EXPECT_NE(ideal.error(), CameraError::PointBehindCamera);
      (ideal.error() == CameraError::NoConvergence ? noConvergence : outside) += 1;
      continue;
    }
    ++solved;
    EXPECT_LT((camera.distortPixel(*ideal) - pixel).norm(), 1e-6) << pixel.transpose();
  }
  std::printf("[ pathological ] solved %d, no convergence %d, outside field %d\n", solved,
              noConvergence, outside);
  EXPECT_GT(solved, 0);
  EXPECT_GT(noConvergence, 0);
}

TEST(Projection, PointsBehindOrOnTheCameraPlane) {
  for (const CameraModel& camera : {brownConradyCamera(), sphericalCamera()}) {
    for (const Eigen::Vector3d& p : {Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(1.0, 2.0, 0.0),
                                     Eigen::Vector3d(0.1, 0.1, -5.0)}) {
      const auto pixel = camera.projectToPixel(p);
      ASSERT_FALSE(pixel.hasValue());
      EXPECT_EQ(pixel.error(), CameraError::PointBehindCamera);
    }
  }
}

TEST(Pinhole, IdentityDistortion) {
  Distortion d;
  d.model = LensModel::Pinhole;
  d.k1 = 0.3;  // ignored by the pinhole model
  CameraModel camera;
  ASSERT_TRUE(camera.init(sensorIntrinsics(), d));
  const Eigen::Vector2d xy(0.3, -0.2);
  EXPECT_EQ(camera.distortNormalized(xy), xy);
  const Eigen::Vector2d pixel(17.25, 2000.5);
  EXPECT_EQ(camera.distortPixel(pixel), pixel);
  const auto ideal = camera.undistortPixel(pixel);
  ASSERT_TRUE(ideal.hasValue());
  EXPECT_LT((*ideal - pixel).norm(), 1e-9);
  const auto projected = camera.projectToPixel({2.0, -1.0, 4.0});
  ASSERT_TRUE(projected.hasValue());
  const Intrinsics& k = camera.intrinsics();
  EXPECT_NEAR(projected->x(), k.cx_px + k.fx_px * 0.5, 1e-9);
  EXPECT_NEAR(projected->y(), k.cy_px - k.fy_px * 0.25, 1e-9);
  // The pinhole has no field limit in front of the camera.
  EXPECT_TRUE(camera.projectToPixel({1e6, 0.0, 1.0}).hasValue());
}

TEST(CameraModel, InImageUsesPixelEdges) {
  const CameraModel camera = brownConradyCamera();
  EXPECT_TRUE(camera.inImage({0.0, 0.0}));
  EXPECT_TRUE(camera.inImage({-0.5, -0.5}));
  EXPECT_FALSE(camera.inImage({-0.51, 10.0}));
  EXPECT_TRUE(camera.inImage({2591.4, 2047.4}));
  EXPECT_FALSE(camera.inImage({2591.5, 100.0}));
  EXPECT_FALSE(camera.inImage({100.0, 2047.5}));
  EXPECT_FALSE(camera.inImage({5.0, 5.0}, 10.0));
  EXPECT_TRUE(camera.inImage({15.0, 15.0}, 10.0));
  EXPECT_FALSE(camera.inImage({2585.0, 100.0}, 10.0));
}

TEST(CameraModel, ErrorNames) {
  EXPECT_STRNE(toString(CameraError::PointBehindCamera), toString(CameraError::OutsideValidField));
  EXPECT_STRNE(toString(CameraError::NoConvergence), toString(CameraError::OutsideValidField));
}

}  // namespace
}  // namespace vp::camera
