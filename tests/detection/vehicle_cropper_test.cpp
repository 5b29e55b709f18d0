// Second stage: the crop map is Python's crops.crop_affine, the crop is cv2.warpAffine's
// (bit for bit), and the crop network's outputs are applied as the training targets define
// them (crops.refine_target inverted).
#include "detection/vehicle_cropper.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "detection/ground_sample_distance.hpp"
#include "geometry/rotated_box.hpp"

namespace vp::detection {
namespace {

// One crop per vehicle, no verifier: the second stage's plain rules, which these tests take
// apart one by one (the shipped defaults add the mirrored crop, the large-vehicle ends and the
// verifier).
SecondStageOptions singleCrop() {
  SecondStageOptions options;
  options.mirrorAverage = false;
  options.mirrorRefine = false;
  options.largeVehicleEnds = false;
  options.turnAverage = false;
  options.turnTypeAverage = false;
  options.minVehicleProbability = 0.0F;
  return options;
}

// Made with /usr/bin/python3 in tools/: print(crops.crop_affine(center, angle, gsd).tolist()).
TEST(VehicleCropper, CropMapEqualsPythonCropAffine) {
  struct Case {
    double u, v, angle, gsd;
    double m[2][3];
  };
  const Case cases[] = {
      {1234.5,
       987.25,
       2.1,
       0.03,
       {{-1.0096922091997151, -1.7264187332977474, 1323.0312201694835},
        {1.7264187332977474, -1.0096922091997151, 928.9728770845503}}},
      {10.0,
       2040.75,
       5.9,
       0.0475,
       {{1.1715517019924664, 0.4722652608381928, -56.74693947433968},
        {-0.4722652608381928, 1.1715517019924664, 2035.6511348929912}}},
      {2591.0, 0.0, 0.0, 0.06, {{1.0, -0.0, 2543.5}, {0.0, 1.0, -23.5}}},
  };
  for (const Case& c : cases) {
    const CropMap map = cropAffine(c.u, c.v, c.angle, c.gsd);
    for (int r = 0; r < 2; ++r) {
      for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(map(r, k), c.m[r][k], 1e-9 * std::max(1.0, std::abs(c.m[r][k])))
            << "angle " << c.angle << " element " << r << "," << k;
      }
    }
  }
  // Crop centre -> box centre; crop +x -> the driving direction.
  const CropMap map = cropAffine(500.0, 300.0, 1.0, 0.03);
  const Eigen::Vector2d centre =
      map * Eigen::Vector3d((kCropWidth_px - 1) / 2.0, (kCropHeight_px - 1) / 2.0, 1.0);
  EXPECT_NEAR(centre.x(), 500.0, 1e-9);
  EXPECT_NEAR(centre.y(), 300.0, 1e-9);
  const Eigen::Vector2d forward = map.leftCols<2>() * Eigen::Vector2d(1.0, 0.0);
  EXPECT_NEAR(std::atan2(forward.y(), forward.x()), 1.0, 1e-12);
  EXPECT_NEAR(forward.norm(), 2.0, 1e-12);  // 6 cm crop px = 2 frame px at 3 cm/px
}

TEST(VehicleCropper, CropIsBitIdenticalToOpenCvWarpAffine) {
  cv::Mat frame(400, 600, CV_8UC3);
  cv::RNG rng(21);
  rng.fill(frame, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(frame, frame, {5, 5}, 1.5);  // some structure besides noise
  struct Pose {
    double u, v, angle, gsd;
  };
  const Pose poses[] = {
      {300.0, 200.0, 0.0, 0.06},      // identity scale, integer position
      {301.37, 188.91, 0.73, 0.031},  // fractional, rotated, 2x zoom out
      {5.2, 7.9, 2.6, 0.045},         // near the top-left corner: replicate border
      {598.6, 395.3, 4.1, 0.02},      // bottom-right corner, large footprint
      {250.0, 150.0, 5.5, 0.12},      // crop finer than the frame (upsampling)
      {-40.0, 420.0, 1.2, 0.05},      // centre outside the frame
  };
  cv::Mat ours(kCropHeight_px, kCropWidth_px, CV_8UC3);
  for (const Pose& p : poses) {
    SCOPED_TRACE(std::to_string(p.u) + ", " + std::to_string(p.v));
    const CropMap map = cropAffine(p.u, p.v, p.angle, p.gsd);
    ASSERT_TRUE(cutCrop(frame, map, ours));
    cv::Mat m(2, 3, CV_64F);
    for (int r = 0; r < 2; ++r) {
      for (int k = 0; k < 3; ++k) {
        m.at<double>(r, k) = map(r, k);
      }
    }
    cv::Mat reference;
    cv::warpAffine(frame, reference, m, {kCropWidth_px, kCropHeight_px},
                   cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REPLICATE);
    EXPECT_EQ(cv::norm(ours, reference, cv::NORM_INF), 0.0);
  }
  cv::Mat grey(10, 10, CV_8UC1);
  EXPECT_FALSE(cutCrop(grey, cropAffine(5, 5, 0, 0.06), ours));
}

// Round trip against the training targets: for a true box, a crop pose and a GSD, Python's
// crops.refine_target gave (flip, refine); the raw outputs are (refine - REFINE_OFFSET) /
// REFINE_SCALE and flip_logit = +-3. Applying them to the crop pose must give the true box.
// Made with /usr/bin/python3 in tools/: f, r = crops.refine_target(box, gsd, centre, angle).
TEST(VehicleCropper, AppliedOutputsInvertThePythonTrainingTargets) {
  struct Case {
    double box[5];  // true cx, cy, length, width, angle (frame px, rad)
    double gsd;
    double cropU, cropV, cropAngle;
    int flip;
    std::array<float, 5> raw;
  };
  const Case cases[] = {
      {{1500.3, 820.7, 151.0, 61.5, 0.4},
       0.03,
       1497.0,
       823.5,
       0.47,
       0,
       {0.10044562816619873F, -0.2394549548625946F, -0.3500000014901161F, 0.03000020980834961F,
        0.04500002861022945F}},
      {{200.0, 300.0, 120.0, 50.0, 6.1},
       0.04,
       203.5,
       296.25,
       2.9,
       1,
       {0.34364309906959534F, -0.2242976427078247F, 0.2920367382466793F, 0.3000001907348633F,
        0.19999999999999996F}},
      {{640.0, 480.0, 90.0, 40.0, 3.3},
       0.05,
       641.0,
       479.0,
       3.3,
       0,
       {0.0829734057188034F, -0.1145225465297699F, 0.0F, 0.0F, 0.19999999999999996F}},
  };
  const std::array<float, 7> logits{0.1F, 2.0F, -1.0F, 0.5F, 0.0F, -0.3F, 1.0F};
  const std::array<float, 3> gamma{0.25F, -1.5F, 0.125F};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.box[4]);
    Detection d;
    d.box = {c.cropU, c.cropV, 100.0, 40.0, c.cropAngle};
    CropNetOutputs outputs;
    outputs.typeLogits = logits;
    outputs.shape = gamma;
    outputs.flipLogit = c.flip != 0 ? 3.0F : -3.0F;
    outputs.refine = c.raw;
    ASSERT_EQ(applyCropOutputs(outputs, c.gsd, singleCrop(), &d), SecondStageStatus::Ok);
    EXPECT_NEAR(d.box.cx, c.box[0], 1e-4);
    EXPECT_NEAR(d.box.cy, c.box[1], 1e-4);
    EXPECT_NEAR(d.box.length, c.box[2], 1e-4);
    EXPECT_NEAR(d.box.width, c.box[3], 1e-4);
    EXPECT_NEAR(geometry::absAngleDifference(d.box.angle, c.box[4]), 0.0, 1e-6);
    EXPECT_NEAR(d.flipProbability, c.flip != 0 ? 0.952574 : 0.047426, 1e-6);
  }
}

TEST(VehicleCropper, VerifierLogitBecomesTheVehicleProbability) {
  const std::array<float, 7> logits{0.1F, 2.0F, -1.0F, 0.5F, 0.0F, -0.3F, 1.0F};
  const std::array<float, 3> gamma{0.25F, -1.5F, 0.125F};
  const std::array<float, 5> refine{0.0F, 0.0F, 0.0F, 0.0F, 0.0F};
  CropNetOutputs outputs{logits, gamma, -1.0F, refine};
  Detection d;
  d.box = {100.0, 50.0, 150.0, 60.0, 0.5};
  // No verifier output: unknown, not "certainly a vehicle".
  ASSERT_EQ(applyCropOutputs(outputs, 0.03, singleCrop(), &d), SecondStageStatus::Ok);
  EXPECT_TRUE(std::isnan(d.vehicleProbability));
  outputs.hasVehicleLogit = true;
  for (const float logit : {-2.0F, 0.0F, 3.0F}) {
    outputs.vehicleLogit = logit;
    ASSERT_EQ(applyCropOutputs(outputs, 0.03, singleCrop(), &d), SecondStageStatus::Ok);
    EXPECT_NEAR(d.vehicleProbability, 1.0 / (1.0 + std::exp(-static_cast<double>(logit))), 1e-6);
  }
  outputs.vehicleLogit = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(applyCropOutputs(outputs, 0.03, singleCrop(), &d), SecondStageStatus::BadOutputs);
}

TEST(VehicleCropper, TypesShapeAndFlipOnly) {
  const std::array<float, 7> logits{0.1F, 2.0F, -1.0F, 0.5F, 0.0F, -0.3F, 1.0F};
  const std::array<float, 3> gamma{0.25F, -1.5F, 0.125F};
  const std::array<float, 5> refine{0.4F, 0.4F, 0.4F, 0.4F, 0.4F};
  Detection d;
  d.box = {100.0, 50.0, 150.0, 60.0, 0.5};
  CropNetOutputs outputs{logits, gamma, 0.2F, refine};
  SecondStageOptions options = singleCrop();
  options.applyRefine = false;  // = Predictor.run_crops' boxes_flip_corrected
  ASSERT_EQ(applyCropOutputs(outputs, 0.03, options, &d), SecondStageStatus::Ok);
  EXPECT_NEAR(d.box.angle, 0.5 + geometry::kPi, 1e-12);
  EXPECT_EQ(d.box.cx, 100.0);
  EXPECT_EQ(d.box.length, 150.0);
  double sum = 0.0;
  double denominator = 0.0;
  for (const float l : logits) {
    denominator += std::exp(static_cast<double>(l));
  }
  for (int t = 0; t < 7; ++t) {
    sum += static_cast<double>(d.typeProbabilities[t]);
    EXPECT_NEAR(d.typeProbabilities[t], std::exp(static_cast<double>(logits[t])) / denominator,
                1e-6);
  }
  EXPECT_NEAR(sum, 1.0, 1e-6);
  const TopTwoTypes top = topTwoTypes(d);
  EXPECT_EQ(top.first, shape::VehicleType::Compact);
  EXPECT_EQ(top.second, shape::VehicleType::Large);
  ASSERT_EQ(d.gamma.count, 3);
  EXPECT_EQ(d.gamma.gamma[1], -1.5F);

  // Flip logit <= 0 keeps the heading; a vehicle most likely Large has no ASM shape.
  std::array<float, 7> largeLogits{};
  largeLogits[6] = 5.0F;
  Detection large;
  large.box = {100.0, 50.0, 150.0, 60.0, 0.5};
  outputs = CropNetOutputs{largeLogits, gamma, -0.1F, refine};
  ASSERT_EQ(applyCropOutputs(outputs, 0.03, options, &large), SecondStageStatus::Ok);
  EXPECT_EQ(large.box.angle, 0.5);
  EXPECT_EQ(large.gamma.count, 0);
  options.shapeForLargeVehicles = true;
  ASSERT_EQ(applyCropOutputs(outputs, 0.03, options, &large), SecondStageStatus::Ok);
  EXPECT_EQ(large.gamma.count, 3);

  // Bad inputs are statuses and leave the detection alone.
  Detection untouched = large;
  EXPECT_EQ(applyCropOutputs(outputs, 0.0, options, &untouched), SecondStageStatus::BadGsd);
  const std::array<float, 4> shortRefine{};
  outputs.refine = shortRefine;
  EXPECT_EQ(applyCropOutputs(outputs, 0.03, options, &untouched), SecondStageStatus::BadOutputs);
  std::array<float, 5> nanRefine{};
  nanRefine[2] = std::nanf("");
  outputs.refine = nanRefine;
  EXPECT_EQ(applyCropOutputs(outputs, 0.03, options, &untouched), SecondStageStatus::BadOutputs);
  EXPECT_EQ(untouched.box.angle, large.box.angle);
}

// A vehicle most likely Large keeps the first stage's length and along-axis centre: the crop
// window shows only part of it. Across the axis (offset, angle, width) it is refined as any other.
TEST(VehicleCropper, LargeVehicleKeepsTheFirstStageLength) {
  std::array<float, 7> largeLogits{};
  largeLogits[6] = 5.0F;
  const std::array<float, 3> gamma{};
  // raw refine: du 0.5 m, dv 0.25 m, d_angle 0.02 rad, length 4.5 + 1 m, width 1.8 + 0.2 m
  const std::array<float, 5> raw{1.0F, 0.5F, 0.1F, 1.0F, 0.2F};
  const double gsd = 0.05;
  Detection large;
  large.box = {500.0, 300.0, 200.0, 50.0, 0.0};  // a 10 m x 2.5 m bus along +u
  CropNetOutputs outputs{largeLogits, gamma, -3.0F, raw};
  ASSERT_EQ(applyCropOutputs(outputs, gsd, singleCrop(), &large), SecondStageStatus::Ok);
  EXPECT_NEAR(large.box.cx, 500.0, 1e-9);        // du not applied
  EXPECT_NEAR(large.box.cy, 300.0 + 5.0, 1e-9);  // dv 0.25 m = 5 px
  EXPECT_NEAR(large.box.length, 200.0, 1e-9);
  EXPECT_NEAR(large.box.width, 2.0 / gsd, 1e-4);
  EXPECT_NEAR(large.box.angle, 0.02, 1e-6);

  SecondStageOptions options = singleCrop();
  options.refineLargeVehicleLength = true;  // the crop's length after all
  Detection refined;
  refined.box = {500.0, 300.0, 200.0, 50.0, 0.0};
  ASSERT_EQ(applyCropOutputs(outputs, gsd, options, &refined), SecondStageStatus::Ok);
  EXPECT_NEAR(refined.box.cx, 510.0, 1e-9);
  EXPECT_NEAR(refined.box.length, 5.5 / gsd, 1e-4);

  // A car is refined along its axis as before.
  std::array<float, 7> carLogits{};
  carLogits[3] = 5.0F;
  Detection car;
  car.box = {500.0, 300.0, 90.0, 36.0, 0.0};
  outputs.typeLogits = carLogits;
  ASSERT_EQ(applyCropOutputs(outputs, gsd, singleCrop(), &car), SecondStageStatus::Ok);
  EXPECT_NEAR(car.box.cx, 510.0, 1e-9);
  EXPECT_NEAR(car.box.length, 5.5 / gsd, 1e-4);

  // Without the size refinement the centre and axis are refined, length and width kept.
  SecondStageOptions noSize = singleCrop();
  noSize.refineSize = false;
  Detection kept;
  kept.box = {500.0, 300.0, 90.0, 36.0, 0.0};
  ASSERT_EQ(applyCropOutputs(outputs, gsd, noSize, &kept), SecondStageStatus::Ok);
  EXPECT_NEAR(kept.box.cx, 510.0, 1e-9);
  EXPECT_NEAR(kept.box.cy, 305.0, 1e-9);
  EXPECT_NEAR(kept.box.angle, 0.02, 1e-6);
  EXPECT_EQ(kept.box.length, 90.0);
  EXPECT_EQ(kept.box.width, 36.0);
}

// A textured background for the crop network (uniform noise, blurred like a photo).
cv::Mat blurredNoise(int rows, int cols, int seed) {
  cv::Mat frame(rows, cols, CV_8UC3);
  cv::RNG rng(static_cast<std::uint64_t>(seed));
  rng.fill(frame, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(frame, frame, cv::Size(9, 9), 2.0);
  return frame;
}

// mirrorAverage (+ mirrorRefine): the second run sees the crop mirrored across the vehicle's axis.
// A frame mirrored about the box's axis (a horizontal box on the middle row, 1 crop px = 1 frame
// px, so the crops are exact mirror images) gives the second run's outputs by itself: the averaged
// type is the normalised geometric mean of the two runs' probabilities, the averaged
// refinement the mean with the across-axis offset and angle turned back, the shape the mean;
// front/back comes from the crop as cut.
TEST(VehicleCropper, MirrorAverageCombinesTheCropAndItsMirrorImage) {
  cv::Mat frame = blurredNoise(240, 320, 7);
  cv::rectangle(frame, cv::Rect(130, 112, 60, 20), cv::Scalar(40, 60, 200), cv::FILLED);
  cv::rectangle(frame, cv::Rect(150, 104, 20, 10), cv::Scalar(220, 220, 220), cv::FILLED);
  cv::Mat mirrored;
  cv::flip(frame, mirrored, 0);
  constexpr double kGsd = kCropGsd_m;  // 1 crop px = 1 frame px
  auto box = [] {
    Detection d;
    d.box = {159.5, 119.5, 75.0, 30.0, 0.0};  // on the middle row (240 rows: 119.5)
    return d;
  };
  const std::string model = std::string(VP_SOURCE_DIR) + "/models/detector/crop_int8.onnx";
  SecondStageOptions single = singleCrop();
  single.applyFlip = false;
  SecondStageOptions averaged = single;
  averaged.mirrorAverage = true;
  averaged.mirrorRefine = true;
  VehicleCropper one;
  VehicleCropper both;
  ASSERT_TRUE(one.init(model, {}, single));
  ASSERT_TRUE(both.init(model, {}, averaged));

  Detection a = box(), b = box(), c = box();
  ASSERT_EQ(one.classify(frame, kGsd, &a), SecondStageStatus::Ok);
  ASSERT_EQ(one.classify(mirrored, kGsd, &b), SecondStageStatus::Ok);
  ASSERT_EQ(both.classify(frame, kGsd, &c), SecondStageStatus::Ok);
  // one's last crop is the mirrored frame's: mirrored back it is the crop both cut.
  cv::Mat flippedCrop;
  cv::flip(one.lastCrop(), flippedCrop, 0);
  ASSERT_EQ(cv::norm(flippedCrop, both.lastCrop(), cv::NORM_INF), 0.0) << "crops not mirrored";

  double total = 0.0;
  std::array<double, shape::kVehicleTypeCount> geometric{};
  for (int t = 0; t < shape::kVehicleTypeCount; ++t) {
    geometric[t] = std::sqrt(static_cast<double>(a.typeProbabilities[t]) *
                             static_cast<double>(b.typeProbabilities[t]));
    total += geometric[t];
  }
  for (int t = 0; t < shape::kVehicleTypeCount; ++t) {
    EXPECT_NEAR(c.typeProbabilities[t], geometric[t] / total, 1e-5) << "type " << t;
  }
  // Refinement: along-axis offset, length, width averaged; across-axis offset and angle
  // averaged with the mirrored run's turned back (about the frame's middle row).
  EXPECT_NEAR(c.box.cx, 0.5 * (a.box.cx + b.box.cx), 1e-4);
  EXPECT_NEAR(c.box.cy - 119.5, 0.5 * ((a.box.cy - 119.5) - (b.box.cy - 119.5)), 1e-4);
  EXPECT_NEAR(c.box.length, 0.5 * (a.box.length + b.box.length), 1e-4);
  EXPECT_NEAR(c.box.width, 0.5 * (a.box.width + b.box.width), 1e-4);
  EXPECT_NEAR(geometry::angleDifference(c.box.angle, 0.0),
              0.5 * (geometry::angleDifference(a.box.angle, 0.0) -
                     geometry::angleDifference(b.box.angle, 0.0)),
              1e-5);
  // Front/back: the crop as cut. Shape: the mean (the ASM's components are mirror-symmetric).
  EXPECT_EQ(c.flipProbability, a.flipProbability);
  ASSERT_EQ(c.gamma.count, a.gamma.count);
  for (int s = 0; s < a.gamma.count; ++s) {
    const auto k = static_cast<std::size_t>(s);
    EXPECT_NEAR(c.gamma.gamma[k], 0.5F * (a.gamma.gamma[k] + b.gamma.gamma[k]), 1e-5F);
  }
  // Without mirrorRefine the box is the single run's (type and shape still averaged).
  SecondStageOptions typeOnly = single;
  typeOnly.mirrorAverage = true;
  VehicleCropper typed;
  ASSERT_TRUE(typed.init(model, {}, typeOnly));
  Detection e = box();
  ASSERT_EQ(typed.classify(frame, kGsd, &e), SecondStageStatus::Ok);
  EXPECT_EQ(e.box.cx, a.box.cx);
  EXPECT_EQ(e.box.cy, a.box.cy);
  EXPECT_EQ(e.box.angle, a.box.angle);
  EXPECT_EQ(e.box.length, a.box.length);
  for (int t = 0; t < shape::kVehicleTypeCount; ++t) {
    EXPECT_EQ(e.typeProbabilities[t], c.typeProbabilities[t]) << "type " << t;
  }
  for (int s = 0; s < e.gamma.count; ++s) {
    EXPECT_EQ(e.gamma.gamma[static_cast<std::size_t>(s)],
              c.gamma.gamma[static_cast<std::size_t>(s)]);
  }
  // The two runs differ, or the test would show nothing.
  EXPECT_GT(std::abs(a.box.cy - 119.5) + std::abs(b.box.cy - 119.5), 1e-3);
  double gammaDifference = 0.0;
  for (int s = 0; s < a.gamma.count; ++s) {
    gammaDifference += static_cast<double>(std::abs(a.gamma.gamma[static_cast<std::size_t>(s)] -
                                                    b.gamma.gamma[static_cast<std::size_t>(s)]));
  }
  EXPECT_GT(gammaDifference, 1e-3);
}

// turnAverage: front/back from a crop at the refined box and the same crop turned by 180 deg.
// turnedFlipLogit() is half the difference of the flip logits classify() gives for a box and for
// the box turned by 180 deg (1 crop px = 1 frame px, box centre on a pixel: the crop cut at
// angle + pi is the turned crop); classify() with turnAverage takes its front/back from it, so a
// box and the same box turned by 180 deg end with the same heading. Type stays the crop's unless
// turnTypeAverage also averages the turned runs' type logits in.
TEST(VehicleCropper, TurnAverageMakesFrontBackIndependentOfTheBoxDirection) {
  cv::Mat frame = blurredNoise(240, 320, 13);
  cv::rectangle(frame, cv::Rect(130, 110, 60, 20), cv::Scalar(40, 60, 200), cv::FILLED);
  cv::rectangle(frame, cv::Rect(172, 112, 12, 16), cv::Scalar(30, 30, 30), cv::FILLED);
  constexpr double kGsd = kCropGsd_m;
  const std::string model = std::string(VP_SOURCE_DIR) + "/models/detector/crop_int8.onnx";
  SecondStageOptions single = singleCrop();
  single.applyRefine = false;
  SecondStageOptions turned = single;
  turned.turnAverage = true;
  VehicleCropper one;
  VehicleCropper both;
  ASSERT_TRUE(one.init(model, {}, single));
  ASSERT_TRUE(both.init(model, {}, turned));
  auto logit = [](float p) {
    const double q = static_cast<double>(p);
    return std::log(q / (1.0 - q));
  };
  auto box = [](double angle) {
    Detection d;
    d.box = {159.0, 120.0, 75.0, 30.0, angle};
    return d;
  };
  Detection a = box(0.0), b = box(geometry::kPi);
  ASSERT_EQ(one.classify(frame, kGsd, &a), SecondStageStatus::Ok);
  ASSERT_EQ(one.classify(frame, kGsd, &b), SecondStageStatus::Ok);
  float turnedLogit = 0.0F;
  ASSERT_EQ(both.turnedFlipLogit(frame, kGsd, box(0.0).box, &turnedLogit), SecondStageStatus::Ok);
  EXPECT_NEAR(turnedLogit, 0.5 * (logit(a.flipProbability) - logit(b.flipProbability)), 1e-2);
  EXPECT_GT(std::abs(logit(a.flipProbability) + logit(b.flipProbability)), 1e-2)
      << "the single runs are already antisymmetric: the test would show nothing";

  Detection c = box(0.0), d = box(geometry::kPi);
  ASSERT_EQ(both.classify(frame, kGsd, &c), SecondStageStatus::Ok);
  ASSERT_EQ(both.classify(frame, kGsd, &d), SecondStageStatus::Ok);
  EXPECT_NEAR(logit(c.flipProbability), static_cast<double>(turnedLogit), 1e-4);
  EXPECT_NEAR(logit(d.flipProbability), -logit(c.flipProbability), 1e-2);
  EXPECT_NEAR(std::abs(geometry::angleDifference(c.box.angle, d.box.angle)), 0.0, 1e-9);
  for (int t = 0; t < shape::kVehicleTypeCount; ++t) {
    EXPECT_EQ(c.typeProbabilities[t], a.typeProbabilities[t]) << "type " << t;
  }

  // turnTypeAverage with the weight w: the type logits are (1 - w) times the first look's plus w
  // times the mean of the two turned runs' (here a's crop and b's), i.e. probabilities
  // proportional to p_a^(1 - w/2) p_b^(w/2): w 1/2 gives p_a^(3/4) p_b^(1/4), 1 (p_a p_b)^(1/2),
  // 0 the first look alone. Front/back unchanged.
  for (const float weight : {0.5F, 1.0F, 0.0F}) {
    SecondStageOptions typed = turned;
    typed.turnTypeAverage = true;
    typed.turnTypeWeight = weight;
    VehicleCropper withType;
    ASSERT_TRUE(withType.init(model, {}, typed));
    Detection e = box(0.0);
    ASSERT_EQ(withType.classify(frame, kGsd, &e), SecondStageStatus::Ok);
    EXPECT_EQ(e.flipProbability, c.flipProbability);
    EXPECT_EQ(e.box.angle, c.box.angle);
    const double w = static_cast<double>(weight);
    std::array<double, shape::kVehicleTypeCount> expected{};
    double total = 0.0;
    double change = 0.0;
    for (int t = 0; t < shape::kVehicleTypeCount; ++t) {
      expected[t] = std::pow(static_cast<double>(a.typeProbabilities[t]), 1.0 - 0.5 * w) *
                    std::pow(static_cast<double>(b.typeProbabilities[t]), 0.5 * w);
      total += expected[t];
    }
    for (int t = 0; t < shape::kVehicleTypeCount; ++t) {
      EXPECT_NEAR(e.typeProbabilities[t], expected[t] / total, 1e-4)
          << "weight " << weight << " type " << t;
      change += std::abs(static_cast<double>(e.typeProbabilities[t] - a.typeProbabilities[t]));
    }
    if (weight > 0.0F) {
      EXPECT_GT(change, 1e-4)
          << "the turned runs agree with the first: the test would show nothing";
    }
  }
}

// largeVehicleEnds: a long vehicle's front/back from crops at its two ends. endsFlipLogit() is
// half the difference of the flip logits of a crop ahead of the centre looking ahead and one
// behind it looking back (each what classify() gives for a box there: flipProbability =
// sigmoid(flip_logit)); turning the box by 180 deg negates it; a car is classified as before.
TEST(VehicleCropper, LargeVehicleFrontBackFromCropsAtBothEnds) {
  cv::Mat frame = blurredNoise(400, 800, 11);
  // A 12 m x 2.5 m "bus" along +u with a dark front end (windscreen) and a light car beside it.
  cv::rectangle(frame, cv::Rect(160, 175, 480, 100), cv::Scalar(200, 200, 190), cv::FILLED);
  cv::rectangle(frame, cv::Rect(600, 180, 30, 90), cv::Scalar(30, 30, 40), cv::FILLED);
  cv::rectangle(frame, cv::Rect(200, 320, 180, 72), cv::Scalar(40, 60, 200), cv::FILLED);
  constexpr double kGsd = 0.025;  // 12 m = 480 px; the crop window 5.76 m = 230.4 px
  const std::string model = std::string(VP_SOURCE_DIR) + "/models/detector/crop_int8.onnx";
  SecondStageOptions plain = singleCrop();
  plain.applyRefine = false;
  plain.applyFlip = false;
  VehicleCropper cropper;
  ASSERT_TRUE(cropper.init(model, {}, plain));
  auto flipLogitAt = [&](double u, double v, double angle) {
    Detection d;
    d.box = {u, v, 100.0, 40.0, angle};
    EXPECT_EQ(cropper.classify(frame, kGsd, &d), SecondStageStatus::Ok);
    const double p = d.flipProbability;
    return std::log(p / (1.0 - p));
  };
  const geometry::RotatedBox bus{400.0, 225.0, 480.0, 100.0, 0.0};
  float ends = 0.0F;
  ASSERT_EQ(cropper.endsFlipLogit(frame, kGsd, bus, &ends), SecondStageStatus::Ok);
  const double offset = 240.0 - 115.2;  // L / 2 - half the window, in frame px
  const double ahead = flipLogitAt(400.0 + offset, 225.0, 0.0);
  const double behind = flipLogitAt(400.0 - offset, 225.0, geometry::kPi);
  EXPECT_NEAR(ends, 0.5 * (ahead - behind), 1e-3);
  EXPECT_GT(std::abs(ahead - behind), 1e-2);  // the two ends do differ
  geometry::RotatedBox turned = bus;
  turned.angle = geometry::kPi;
  float turnedEnds = 0.0F;
  ASSERT_EQ(cropper.endsFlipLogit(frame, kGsd, turned, &turnedEnds), SecondStageStatus::Ok);
  EXPECT_NEAR(turnedEnds, -ends, 1e-4);
  // A box no longer than the window: both crops at its centre, facing either way.
  const geometry::RotatedBox shortBox{400.0, 225.0, 200.0, 100.0, 0.0};
  ASSERT_EQ(cropper.endsFlipLogit(frame, kGsd, shortBox, &ends), SecondStageStatus::Ok);
  EXPECT_NEAR(ends,
              0.5 * (flipLogitAt(400.0, 225.0, 0.0) - flipLogitAt(400.0, 225.0, geometry::kPi)),
              1e-3);
  EXPECT_EQ(cropper.endsFlipLogit(frame, 0.0, bus, &ends), SecondStageStatus::BadGsd);

  // A vehicle the crop network does not take for Large is classified exactly as without.
  SecondStageOptions withEnds = plain;
  withEnds.applyFlip = true;
  withEnds.largeVehicleEnds = true;
  SecondStageOptions withoutEnds = withEnds;
  withoutEnds.largeVehicleEnds = false;
  VehicleCropper on;
  VehicleCropper off;
  ASSERT_TRUE(on.init(model, {}, withEnds));
  ASSERT_TRUE(off.init(model, {}, withoutEnds));
  Detection car;
  car.box = {290.0, 356.0, 180.0, 72.0, 0.0};
  Detection same = car;
  ASSERT_EQ(off.classify(frame, kGsd, &car), SecondStageStatus::Ok);
  ASSERT_NE(topTwoTypes(car).first, shape::VehicleType::Large);
  ASSERT_EQ(on.classify(frame, kGsd, &same), SecondStageStatus::Ok);
  EXPECT_EQ(same.box.angle, car.box.angle);
  EXPECT_EQ(same.flipProbability, car.flipProbability);
  EXPECT_EQ(same.typeProbabilities, car.typeProbabilities);
}

// The shipped crop network carries a second verifier for vehicles cut by the frame's border
// (vehicle_logit_edge): classify() with keepBox takes the vehicle probability from it, the one
// run and every other output unchanged.
TEST(VehicleCropper, AVehicleCutByTheBorderTakesTheBordersVerifier) {
  cv::Mat frame = blurredNoise(240, 320, 17);
  cv::rectangle(frame, cv::Rect(40, 40, 60, 24), cv::Scalar(200, 200, 205), cv::FILLED);
  cv::rectangle(frame, cv::Rect(200, 60, 64, 26), cv::Scalar(30, 30, 150), cv::FILLED);
  cv::rectangle(frame, cv::Rect(120, 160, 58, 22), cv::Scalar(70, 80, 70), cv::FILLED);
  const std::string model = std::string(VP_SOURCE_DIR) + "/models/detector/crop_int8.onnx";
  for (const bool mirror : {false, true}) {
    SecondStageOptions options = singleCrop();
    options.mirrorAverage = mirror;
    VehicleCropper cropper;
    std::string why;
    ASSERT_TRUE(cropper.init(model, {}, options, &why)) << why;
    ASSERT_TRUE(cropper.hasVerifier());
    ASSERT_TRUE(cropper.hasEdgeVerifier());
    int differ = 0;
    for (const geometry::RotatedBox& box : {geometry::RotatedBox{70.0, 52.0, 70.0, 28.0, 0.0},
                                            geometry::RotatedBox{232.0, 73.0, 72.0, 30.0, 0.1},
                                            geometry::RotatedBox{149.0, 171.0, 66.0, 26.0, -0.05},
                                            geometry::RotatedBox{160.0, 110.0, 70.0, 28.0, 0.7}}) {
      Detection inside;
      inside.box = box;
      Detection atBorder = inside;
      ASSERT_EQ(cropper.classify(frame, kCropGsd_m, &inside, false), SecondStageStatus::Ok);
      ASSERT_EQ(cropper.classify(frame, kCropGsd_m, &atBorder, true), SecondStageStatus::Ok);
      ASSERT_TRUE(std::isfinite(atBorder.vehicleProbability));
      differ += inside.vehicleProbability != atBorder.vehicleProbability ? 1 : 0;
      EXPECT_EQ(inside.typeProbabilities, atBorder.typeProbabilities);
      EXPECT_EQ(inside.flipProbability, atBorder.flipProbability);
      EXPECT_EQ(atBorder.box.cx, box.cx);  // kept, not refined
    }
    EXPECT_GT(differ, 0) << "mirror " << mirror;

    // frameEdgeOwnVerifier false: the border takes the inside verifier, value for value.
    options.frameEdgeOwnVerifier = false;
    VehicleCropper insideOnly;
    ASSERT_TRUE(insideOnly.init(model, {}, options, &why)) << why;
    Detection inside;
    inside.box = {232.0, 73.0, 72.0, 30.0, 0.1};
    Detection atBorder = inside;
    ASSERT_EQ(insideOnly.classify(frame, kCropGsd_m, &inside, false), SecondStageStatus::Ok);
    ASSERT_EQ(insideOnly.classify(frame, kCropGsd_m, &atBorder, true), SecondStageStatus::Ok);
    EXPECT_EQ(inside.vehicleProbability, atBorder.vehicleProbability) << "mirror " << mirror;
  }
}

TEST(GroundSampleDistance, MedianBoxIsANominalCar) {
  std::array<Detection, 5> detections{};
  const double lengths[] = {150.0, 160.0, 400.0, 140.0, 155.0};  // a bus among cars
  for (int i = 0; i < 5; ++i) {
    detections[i].box.length = lengths[i];
  }
  std::array<double, 5> scratch{};
  GsdOptions options;
  EXPECT_NEAR(medianLengthGsd(detections, options, scratch), 4.5 / 155.0, 1e-12);
  EXPECT_NEAR(medianLengthGsd(std::span(detections).first(4), options, scratch), 4.5 / 155.0,
              1e-12);  // even count: mean of 150 and 160
  EXPECT_EQ(medianLengthGsd({}, options, scratch), 0.0);
  detections[0].box.length = 1.0;
  detections[1].box.length = 1.0;
  detections[2].box.length = 1.0;
  EXPECT_EQ(medianLengthGsd(detections, options, scratch), options.maxGsd_m);  // clamped
  EXPECT_NEAR(nadirGsd(90.0, 3000.0), 0.03, 1e-15);
  EXPECT_EQ(nadirGsd(-1.0, 3000.0), 0.0);
  std::string why;
  options.minGsd_m = 0.0;
  EXPECT_FALSE(validate(options, &why));
  EXPECT_NE(why.find("min_gsd_m"), std::string::npos) << why;
}

TEST(GroundSampleDistance, WorkingScaleBringsAFrameToTheDetectorsResolution) {
  EXPECT_NEAR(workingScaleForGsd(0.068), 0.068 / 0.12, 1e-15);  // bev-intersection-de photos
  EXPECT_NEAR(workingScaleForGsd(0.03), 0.25, 1e-15);  // the 2592 px camera at ~90 m: the app's
  EXPECT_EQ(workingScaleForGsd(0.2), 1.0);             // coarser than the detector: as it is
  EXPECT_EQ(workingScaleForGsd(0.0), 0.0);
  EXPECT_EQ(workingScaleForGsd(std::nan("")), 0.0);
}

}  // namespace
}  // namespace vp::detection
