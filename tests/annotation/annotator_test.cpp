#include "annotation/annotator.hpp"

#include <cstdio>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "../perception/test_scene.hpp"
#include "alloc_counter.hpp"

namespace vp::annotation {
namespace {

namespace testworld = perception::testworld;

// One lifted car (a perfect detection of a ground-truth vehicle) in a tilted view.
struct LiftedCar {
  testworld::Scene scene{testworld::plane(0.05, -0.03), camera::LensModel::BrownConrady};
  perception::FrameLiftSummary summary;
  perception::VehicleObservation observation;

  explicit LiftedCar(double heading_rad) {
    const lifting::DronePose pose = testworld::hoveringPose(20.0, -75.0);
    const auto cameraPose = scene.lifter.cameraPose(pose);
    EXPECT_TRUE(cameraPose);
    testworld::TruthVehicle truth;
    truth.footprint.centreEnu = *scene.terrain.groundPointEnu(3.0, 12.0);
    truth.footprint.headingEnu_rad = heading_rad;
    truth.footprint.length_m = 4.6;
    truth.footprint.width_m = 1.85;
    detection::Detection d;
    EXPECT_TRUE(testworld::perfectDetection(scene, *cameraPose, truth, &d));
    summary = scene.detectionLifter.liftFrame(scene.lifter, 5, telemetry::PoseStatus::Ok, pose,
                                              std::span(&d, 1), std::span(&observation, 1));
    EXPECT_EQ(observation.liftStatus, perception::LiftStatus::Ok);
    EXPECT_TRUE(observation.hasKeypoints);
  }
};

cv::Rect boxBounds(const geometry::RotatedBox& box) {
  const auto c = geometry::corners(box);
  double x0 = c[0].x(), x1 = c[0].x(), y0 = c[0].y(), y1 = c[0].y();
  for (const auto& p : c) {
    x0 = std::min(x0, p.x());
    x1 = std::max(x1, p.x());
    y0 = std::min(y0, p.y());
    y1 = std::max(y1, p.y());
  }
  return {static_cast<int>(x0), static_cast<int>(y0), static_cast<int>(x1 - x0) + 1,
          static_cast<int>(y1 - y0) + 1};
}

// Does the pixel show this colour? Anti-aliased 1 px lines blend it with the background, so
// a full channel counts when >= 180 and an empty one when <= 60 (other values within 40).
bool shows(const cv::Vec3b& p, Bgr colour) {
  const std::array<int, 3> want = {colour.b, colour.g, colour.r};
  for (std::size_t c = 0; c < 3; ++c) {
    const int v = p[static_cast<int>(c)];
    const int w = want[c];
    if ((w == 0 && v > 60) || (w == 255 && v < 180) ||
        (w != 0 && w != 255 && std::abs(v - w) > 40)) {
      return false;
    }
  }
  return true;
}

// Is there a pixel of this colour within `radius` of p?
bool colourNear(const cv::Mat& image, const Eigen::Vector2d& p, Bgr colour, int radius) {
  for (int dy = -radius; dy <= radius; ++dy) {
    for (int dx = -radius; dx <= radius; ++dx) {
      const int x = static_cast<int>(std::lround(p.x())) + dx;
      const int y = static_cast<int>(std::lround(p.y())) + dy;
      if (x >= 0 && y >= 0 && x < image.cols && y < image.rows &&
          shows(image.at<cv::Vec3b>(y, x), colour)) {
        return true;
      }
    }
  }
  return false;
}

int countColour(const cv::Mat& image, Bgr colour) {
  int n = 0;
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      n += shows(image.at<cv::Vec3b>(y, x), colour) ? 1 : 0;
    }
  }
  return n;
}

TEST(Annotator, InitRejectsABadStyleNamingTheField) {
  Annotator annotator;
  std::string why;
  AnnotationStyle style;
  style.lineThickness_px = 0;
  EXPECT_FALSE(annotator.init(style, &why));
  EXPECT_NE(why.find("lineThickness_px"), std::string::npos) << why;
  style = {};
  style.fontScale = 9.0;
  EXPECT_FALSE(annotator.init(style, &why));
  EXPECT_NE(why.find("fontScale"), std::string::npos) << why;
  cv::Mat image(100, 100, CV_8UC3, cv::Scalar::all(0));
  EXPECT_FALSE(annotator.drawFrame(image, {}, {}, nullptr, nullptr));  // not initialised
}

TEST(Annotator, DrawsBoxArrowLabelAndWireframeOnlyAroundTheVehicle) {
  LiftedCar car(0.7);
  Annotator annotator;
  std::string why;
  ASSERT_TRUE(annotator.init({}, &why)) << why;
  const camera::Intrinsics& in = car.scene.camera.intrinsics();
  cv::Mat image(in.height_px, in.width_px, CV_8UC3, cv::Scalar::all(0));
  const cv::Rect drawn = annotator.drawObservation(image, car.observation, 17, &car.scene.lifter,
                                                   &car.summary.cameraPose);
  ASSERT_FALSE(drawn.empty());

  const geometry::RotatedBox& box = car.observation.detection.box;
  std::printf("box %.1f x %.1f px at (%.1f, %.1f); drawn rect %d x %d at (%d, %d)\n", box.length,
              box.width, box.cx, box.cy, drawn.width, drawn.height, drawn.x, drawn.y);
  // The box's edges are drawn (green: lifted); a quarter along each, clear of the arrow tip.
  const auto corners = geometry::corners(box);
  for (std::size_t i = 0; i < 4; ++i) {
    const Eigen::Vector2d mid = 0.75 * corners[i] + 0.25 * corners[(i + 1) % 4];
    EXPECT_TRUE(colourNear(image, mid, kLiftedBoxColour, 1)) << "edge " << i;
  }
  // The arrow runs from the centre towards the front edge (yellow).
  const Eigen::Vector2d centre(box.cx, box.cy);
  const Eigen::Vector2d front = 0.5 * (corners[0] + corners[1]);
  EXPECT_TRUE(colourNear(image, 0.5 * (centre + front), kDirectionColour, 1));
  // The wireframe: red pixels at the projected roof keypoints.
  int redKeypoints = 0;
  for (int k : {10, 11, 12, 13}) {
    const auto p =
        car.scene.lifter.worldToPixel(car.summary.cameraPose, car.observation.keypointsEnu.col(k));
    ASSERT_TRUE(p);
    redKeypoints += colourNear(image, *p, kWireframeColour, 2) ? 1 : 0;
  }
  EXPECT_GE(redKeypoints, 3);
  // The label (white text) lies above the box.
  const cv::Rect bounds = boxBounds(box);
  const cv::Size label = annotator.textSize("sedan 88% #17");
  const cv::Rect labelBand(bounds.x - 2, bounds.y - label.height - 8, label.width + 8,
                           label.height + 8);
  EXPECT_GT(
      countColour(image(labelBand & cv::Rect(0, 0, image.cols, image.rows)), kLabelTextColour), 10);

  // Nothing outside the returned rectangle, and that rectangle stays within the box and its
  // label (plus the line width and anti-aliasing).
  cv::Mat changed;
  cv::cvtColor(image, changed, cv::COLOR_BGR2GRAY);
  cv::Mat outside = changed.clone();
  outside(drawn).setTo(0);
  EXPECT_EQ(cv::countNonZero(outside), 0);
  EXPECT_GT(cv::countNonZero(changed(drawn)), 200);
  const int margin = 6;
  const cv::Rect allowed(bounds.x - margin, bounds.y - label.height - margin,
                         std::max(bounds.width, label.width) + 2 * margin,
                         bounds.height + label.height + 2 * margin);
  EXPECT_EQ(drawn & allowed, drawn) << "drawn " << drawn << " allowed " << allowed;
}

TEST(Annotator, NotLiftedObservationsAreOrangeWithTheirStatusAndNoWireframe) {
  LiftedCar car(2.0);
  perception::VehicleObservation o = car.observation;
  o.liftStatus = perception::LiftStatus::StalePose;
  o.hasKeypoints = false;
  o.detection.directionKnown = false;
  Annotator annotator;
  ASSERT_TRUE(annotator.init({}));
  const camera::Intrinsics& in = car.scene.camera.intrinsics();
  cv::Mat image(in.height_px, in.width_px, CV_8UC3, cv::Scalar::all(0));
  ASSERT_TRUE(
      annotator.drawFrame(image, std::span(&o, 1), {}, &car.scene.lifter, &car.summary.cameraPose));
  const auto corners = geometry::corners(o.detection.box);
  EXPECT_TRUE(colourNear(image, 0.75 * corners[0] + 0.25 * corners[1], kNotLiftedBoxColour, 1));
  // Undecided direction: a grey axis line through the centre, no yellow arrow.
  EXPECT_TRUE(
      colourNear(image, {o.detection.box.cx, o.detection.box.cy}, kUnknownDirectionColour, 1));
  EXPECT_EQ(countColour(image, kWireframeColour), 0);
  EXPECT_EQ(countColour(image, kDirectionColour), 0);
  // The label is longer by the status.
  EXPECT_GT(annotator.textSize("sedan 88% [stale pose]").width,
            annotator.textSize("sedan 88%").width);
}

TEST(Annotator, DrawingAFrameDoesNotAllocate) {
  LiftedCar car(1.2);
  Annotator annotator;
  ASSERT_TRUE(annotator.init({}));
  const camera::Intrinsics& in = car.scene.camera.intrinsics();
  cv::Mat image(in.height_px, in.width_px, CV_8UC3, cv::Scalar::all(0));
  // 50 observations spread over the image, one of them not lifted; half with track ids.
  std::vector<perception::VehicleObservation> observations(50, car.observation);
  std::vector<int> ids(observations.size());
  for (std::size_t i = 0; i < observations.size(); ++i) {
    observations[i].detection.box.cx = 100.0 + 45.0 * static_cast<double>(i);
    observations[i].detection.box.cy = 200.0 + 30.0 * static_cast<double>(i);
    ids[i] = i % 2 == 0 ? static_cast<int>(i) : -1;
  }
  observations[3].liftStatus = perception::LiftStatus::OutsideDtm;
  vp::test::AllocationCounter counter;
  for (int frame = 0; frame < 3; ++frame) {
    ASSERT_TRUE(
        annotator.drawFrame(image, observations, ids, &car.scene.lifter, &car.summary.cameraPose));
  }
  counter.stop();
  std::printf("annotator: 3 frames x 50 vehicles, %zu allocations\n", counter.count());
  EXPECT_EQ(counter.count(), 0U);

  // For the record (docs/perception.md): what the OpenCV primitives themselves allocate.
  const auto count = [&](auto&& draw) {
    counter.start();
    draw();
    counter.stop();
    return counter.count();
  };
  const std::size_t line1 = count([&] {
    cv::line(image, {10, 10}, {300, 200}, cv::Scalar(1, 2, 3), 1, cv::LINE_AA);
  });
  const std::size_t line2 = count([&] {
    cv::line(image, {10, 10}, {300, 200}, cv::Scalar(1, 2, 3), 2, cv::LINE_AA);
  });
  const std::size_t line4 = count([&] {
    cv::line(image, {10, 10}, {300, 200}, cv::Scalar(1, 2, 3), 4, cv::LINE_8);
  });
  const std::size_t circle = count([&] {
    cv::circle(image, {100, 100}, 5, cv::Scalar(1, 2, 3), 2, cv::LINE_AA);
  });
  const std::size_t text = count([&] {
    cv::putText(image, "sedan 88%", {50, 50}, cv::FONT_HERSHEY_SIMPLEX, 0.5,
                cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  });
  std::printf(
      "OpenCV allocations per call: line 1 px AA %zu, line 2 px AA %zu, line 4 px %zu, circle 2 px "
      "AA %zu, putText %zu\n",
      line1, line2, line4, circle, text);
}

}  // namespace
}  // namespace vp::annotation
