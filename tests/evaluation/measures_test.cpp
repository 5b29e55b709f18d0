// Seed 000's measures (src/evaluation/evaluation) on small hand-made cases with known answers.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "evaluation/matching.hpp"
#include "evaluation/measures.hpp"
#include "evaluation/seed_reference.hpp"
#include "evaluation/statistics.hpp"

namespace vp::evaluation {
namespace {

using geometry::kPi;
using geometry::RotatedBox;

TEST(Statistics, MedianMadRmsAndCumulativeShare) {
  const std::vector<double> odd{3, 1, 100, 4, 2};
  EXPECT_DOUBLE_EQ(median(odd), 3.0);
  const std::vector<double> even{4, 1, 3, 2};
  EXPECT_DOUBLE_EQ(median(even), 2.5);
  // |e - 3| = {0, 2, 97, 1, 1}: median 1 -> sigma_MAD = 1.4826 (Eq. 8).
  const RobustSummary r = robustSummary(odd);
  EXPECT_EQ(r.count, 5);
  EXPECT_DOUBLE_EQ(r.median, 3.0);
  EXPECT_DOUBLE_EQ(r.mad, 1.4826);
  // Signed errors are taken as absolute values first.
  const std::vector<double> signedErrors{-3, 1, -100, 4, 2};
  EXPECT_DOUBLE_EQ(robustSummary(signedErrors).median, 3.0);
  EXPECT_DOUBLE_EQ(rootMeanSquare(std::vector<double>{3, -4}), std::sqrt(12.5));
  const std::vector<double> thresholds{0, 2, 10};
  EXPECT_EQ(cumulativeShare(std::vector<double>{0, 1, 2, 5}, thresholds),
            (std::vector<double>{0.25, 0.75, 1.0}));
  EXPECT_DOUBLE_EQ(shareAbove(std::vector<double>{1, 91, 179, 5}, 90.0), 0.5);
  // Nothing measured is NaN, not 0.
  EXPECT_TRUE(std::isnan(robustSummary({}).median));
  EXPECT_TRUE(std::isnan(rootMeanSquare({})));
  EXPECT_TRUE(std::isnan(shareAbove({}, 1.0)));
}

TEST(Matching, IouOfKnownOverlaps) {
  // 4 x 2 boxes, the second shifted by 2 along the length: overlap 2 x 2 = 4, union 12.
  const RotatedBox a{10, 10, 4, 2, 0.0};
  const RotatedBox b{12, 10, 4, 2, 0.0};
  EXPECT_NEAR(geometry::rotatedIou(a, b), 1.0 / 3.0, 1e-12);
  // Reversed driving direction: the same rectangle, IoU 1 (the angle error is measured apart).
  EXPECT_NEAR(geometry::rotatedIou(a, RotatedBox{10, 10, 4, 2, kPi}), 1.0, 1e-12);
  // The enclosing axis-aligned box of a box standing at 90 degrees is 2 x 4.
  const AxisBox e = enclosingAxisBox(RotatedBox{0, 0, 4, 2, kPi / 2});
  EXPECT_NEAR(e.width, 2.0, 1e-12);
  EXPECT_NEAR(e.height, 4.0, 1e-12);
  // At 45 degrees: (4 + 2) / sqrt(2) both ways.
  const AxisBox d = enclosingAxisBox(RotatedBox{0, 0, 4, 2, kPi / 4});
  EXPECT_NEAR(d.width, 6.0 / std::sqrt(2.0), 1e-12);
  // Axis-aligned: 2 x 2 squares overlapping by 1 x 2 -> 2 / 6.
  EXPECT_NEAR(axisAlignedIou(AxisBox{0, 0, 2, 2}, AxisBox{1, 0, 2, 2}), 1.0 / 3.0, 1e-12);
  EXPECT_EQ(axisAlignedIou(AxisBox{0, 0, 2, 2}, AxisBox{5, 0, 2, 2}), 0.0);
  EXPECT_EQ(axisAlignedIou(AxisBox{0, 0, 0, 2}, AxisBox{0, 0, 0, 2}), 0.0);
}

TEST(Matching, GreedyByScoreOneToOneWithIgnoredReferences) {
  // References: r0 normal, r1 ignored, r2 normal (never matched).
  // p0 (0.5) and p1 (0.9) both overlap r0: p1 takes it (higher score), p0 becomes FP.
  // p2 overlaps only the ignored r1: neither TP nor FP. p3 overlaps nothing: FP.
  const std::vector<float> scores{0.5F, 0.9F, 0.7F, 0.6F};
  const std::vector<double> iou{0.8, 0.0, 0.0,   //
                                0.6, 0.0, 0.0,   //
                                0.0, 0.7, 0.0,   //
                                0.0, 0.0, 0.3};  // below the threshold
  const std::vector<std::uint8_t> ignore{0, 1, 0};
  const MatchResult m = greedyMatch(scores, iou, ignore, 0.5);
  ASSERT_EQ(m.pairs.size(), 1U);
  EXPECT_EQ(m.pairs[0], std::make_pair(1, 0));
  EXPECT_EQ(m.falsePositives, (std::vector<int>{3, 0}));  // in score order
  EXPECT_EQ(m.ignoredPredictions, (std::vector<int>{2}));
  EXPECT_EQ(m.falseNegatives, (std::vector<int>{2}));
  // Exactly at the threshold counts (>=).
  const MatchResult edge = greedyMatch(std::vector<float>{1.0F}, std::vector<double>{0.5},
                                       std::vector<std::uint8_t>{0}, 0.5);
  EXPECT_EQ(edge.pairs.size(), 1U);
}

ReferenceObject reference(const RotatedBox& box, int type, double gsd) {
  ReferenceObject r;
  r.box = box;
  r.type = type;
  r.gsd_m = gsd;
  return r;
}

PredictedObject prediction(const RotatedBox& box, float score, int topType, int secondType) {
  PredictedObject p;
  p.box = box;
  p.score = score;
  p.typeProbabilities.fill(0.0F);
  p.typeProbabilities[static_cast<std::size_t>(topType)] = 0.6F;
  p.typeProbabilities[static_cast<std::size_t>(secondType)] = 0.3F;
  p.typeProbabilities[6] += 0.1F;  // the rest on "large" (or on top of it)
  return p;
}

TEST(Evaluator, DetectionPoseAndTypeMeasures) {
  constexpr int kSedan = static_cast<int>(shape::VehicleType::Sedan);
  constexpr int kSuv = static_cast<int>(shape::VehicleType::Suv);
  constexpr int kVan = static_cast<int>(shape::VehicleType::Van);
  constexpr double kGsd = 0.05;  // m/px
  const std::vector<ReferenceObject> refs{
      reference({100, 100, 40, 16, 0.5}, kSedan, kGsd),
      reference({300, 100, 40, 16, 2.0}, kSuv, kGsd),
      reference({500, 100, 40, 16, 4.0}, kVan, kGsd),
      reference({700, 100, 40, 16, 1.0}, kSedan, kGsd),  // missed
  };
  const std::vector<PredictedObject> preds{
      // 3 px and 4 px off (5 px; IoU still > 0.5), same angle, right type.
      prediction({103, 104, 40, 16, 0.5}, 0.9F, kSedan, kSuv),
      // Reversed driving direction: 180 degrees; type right only as the second choice.
      prediction({300, 100, 40, 16, 2.0 + kPi}, 0.8F, kSedan, kSuv),
      // 10 degrees off; type wrong in both choices.
      prediction({500, 100, 40, 16, 4.0 + 10.0 * kPi / 180.0}, 0.7F, kSedan, kSuv),
      prediction({900, 500, 40, 16, 0.0}, 0.6F, kSedan, kSuv),  // false positive
  };
  Evaluator evaluator;
  evaluator.addImage(refs, preds);
  const EvaluationSummary s = evaluator.summary();
  EXPECT_EQ(s.truePositives, 3);
  EXPECT_EQ(s.falsePositives, 1);
  EXPECT_EQ(s.falseNegatives, 1);
  EXPECT_DOUBLE_EQ(s.precision, 0.75);
  EXPECT_DOUBLE_EQ(s.recall, 0.75);
  EXPECT_DOUBLE_EQ(s.f1, 0.75);
  // Position: 5, 0, 0 px -> median 0 px; in metres 0.25, 0, 0.
  EXPECT_DOUBLE_EQ(s.position_px.median, 0.0);
  EXPECT_EQ(s.position_m.count, 3);
  EXPECT_NEAR(s.position_m.median, 0.0, 1e-12);
  // Orientation: 0, 180, 10 deg: median 10; |e - 10| = {10, 170, 0} -> MAD 1.4826 * 10.
  EXPECT_NEAR(s.orientation_deg.median, 10.0, 1e-9);
  EXPECT_NEAR(s.orientation_deg.mad, 14.826, 1e-9);
  EXPECT_NEAR(s.flipShare, 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(s.shareBelow10_deg, 2.0 / 3.0, 1e-12);     // 10 deg itself is "<= 10"
  EXPECT_NEAR(s.axisOrientation_deg.median, 0.0, 1e-9);  // the flip is no axis error
  ASSERT_EQ(s.orientationCumulative.size(), 181U);
  EXPECT_NEAR(s.orientationCumulative[9], 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(s.orientationCumulative[179], 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(s.orientationCumulative[180], 1.0, 1e-12);
  // Type: top-1 right 1 of 3, top-2 right 2 of 3 (the SUV as second choice).
  EXPECT_EQ(s.typeSamples, 3);
  EXPECT_NEAR(s.typeOa1, 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(s.typeOa2, 2.0 / 3.0, 1e-12);
  // Sedan: TP 1, FP 2 (SUV and van predicted as sedan), FN 0 -> F1 = 2 / (2 + 2).
  const ClassScore& sedan = s.typeF1[static_cast<std::size_t>(kSedan)];
  EXPECT_EQ(sedan.truePositives, 1);
  EXPECT_EQ(sedan.falsePositives, 2);
  EXPECT_EQ(sedan.falseNegatives, 0);
  EXPECT_NEAR(sedan.f1, 0.5, 1e-12);
  EXPECT_NEAR(s.typeF1[static_cast<std::size_t>(kSuv)].f1, 0.0, 1e-12);
  EXPECT_TRUE(std::isnan(s.typeF1[0].f1));  // estate never occurs
  EXPECT_EQ(s.confusion[kSuv][kSedan], 1);
  // No ASM given: no shape measures (NaN, not 0).
  EXPECT_EQ(s.shapeSamples, 0);
  EXPECT_TRUE(std::isnan(s.rmsLength_m));
  EXPECT_TRUE(std::isnan(s.keypointsBox.planimetricRms_m));
}

TEST(Evaluator, PositionInMetresUsesTheReferenceGsd) {
  Evaluator evaluator;
  const std::vector<ReferenceObject> refs{reference({100, 100, 40, 16, 0.0}, 3, 0.04)};
  const std::vector<PredictedObject> preds{prediction({103, 104, 40, 16, 0.0}, 0.9F, 3, 4)};
  evaluator.addImage(refs, preds);
  const EvaluationSummary s = evaluator.summary();
  EXPECT_DOUBLE_EQ(s.position_px.median, 5.0);
  EXPECT_NEAR(s.position_m.median, 0.2, 1e-12);
  EXPECT_DOUBLE_EQ(s.position_m.mad, 0.0);
}

TEST(Evaluator, IgnoredReferencesAndAxisAlignedMatching) {
  // Axis-aligned reference 40 x 16: a rotated 40 x 16 prediction at 0 or 180 degrees encloses
  // 40 x 16 (IoU 1), one at 90 degrees encloses 16 x 40 (IoU 256 / 1024).
  ReferenceObject aa;
  aa.axisAligned = true;
  aa.directionKnown = false;
  aa.box = {50, 50, 40, 16, 0.0};
  ReferenceObject ignored = aa;
  ignored.box.cx = 200;
  ignored.ignore = true;
  EvaluationOptions options;
  options.axisAligned = true;
  Evaluator evaluator(options);
  PredictedObject onAa;
  onAa.box = {50, 50, 40, 16, kPi};  // reversed: the same enclosing box
  onAa.score = 0.9F;
  PredictedObject onIgnored = onAa;
  onIgnored.box.cx = 200;
  onIgnored.score = 0.8F;
  PredictedObject standing = onAa;
  standing.box = {50, 50, 40, 16, kPi / 2};  // encloses 16 x 40: IoU 256 / 1024 < 0.5
  standing.score = 0.7F;
  const std::vector<ReferenceObject> refs{aa, ignored};
  const std::vector<PredictedObject> preds{onAa, onIgnored, standing};
  evaluator.addImage(refs, preds);
  const EvaluationSummary s = evaluator.summary();
  EXPECT_EQ(s.truePositives, 1);
  EXPECT_EQ(s.falsePositives, 1);  // the standing one (its reference is taken)
  EXPECT_EQ(s.falseNegatives, 0);
  EXPECT_EQ(s.ignoredPredictions, 1);
  EXPECT_EQ(s.ignoredReferences, 1);
  EXPECT_EQ(s.orientation_deg.count, 0);  // axis-aligned references carry no direction
  EXPECT_DOUBLE_EQ(s.precision, 0.5);
  EXPECT_DOUBLE_EQ(s.recall, 1.0);
}

// A synthetic ASM with known effects: component 0 lifts every keypoint by gamma_0 metres,
// component 1 moves every keypoint forward by gamma_1 metres (sigma 6, eigenvectors of
// 36 entries 1/6 each: unit norm).
class ShapeMeasures : public ::testing::Test {
 protected:
  void SetUp() override {
    shape::KeypointModel mean;
    for (int k = 0; k < shape::kKeypointCount; ++k) {
      mean.col(k) = Eigen::Vector3d(2.0 * std::cos(k), 0.8 * std::sin(3.0 * k), 0.3 + 0.03 * k);
    }
    std::array<shape::KeypointModel, 2> e{shape::KeypointModel::Zero(),
                                          shape::KeypointModel::Zero()};
    e[0].row(2).setConstant(1.0 / 6.0);
    e[1].row(0).setConstant(1.0 / 6.0);
    const std::array<double, 2> eigenvalues{36.0, 36.0};
    std::string why;
    ASSERT_TRUE(model_.init(mean, eigenvalues, e, 0.9, &why)) << why;
    options_.asmModel = &model_;
  }

  static shape::ShapeParams gamma(float g0, float g1) {
    shape::ShapeParams p;
    p.count = 2;
    p.gamma[0] = g0;
    p.gamma[1] = g1;
    return p;
  }

  EvaluationSummary evaluate(ReferenceObject ref, PredictedObject pred) const {
    Evaluator evaluator(options_);
    const std::vector<ReferenceObject> refs{ref};
    const std::vector<PredictedObject> preds{pred};
    evaluator.addImage(refs, preds);
    return evaluator.summary();
  }

  ReferenceObject ref() const {
    ReferenceObject r = reference({100, 100, 40, 16, 1.0}, 3, 0.1);
    r.shape = gamma(0.0F, 0.0F);
    r.hasWorld = true;
    r.positionEnu = {10, 20, 250};
    r.headingEnu_rad = 2.0;
    r.dimensions_m = {4.5, 1.8, 1.5};
    return r;
  }

  PredictedObject pred() const {
    PredictedObject p = prediction({100, 100, 40, 16, 1.0}, 0.9F, 3, 4);
    p.shape = gamma(0.0F, 0.0F);
    p.lifted = true;
    p.positionEnu = {10, 20, 250};
    p.headingEnu_rad = 2.0;
    p.dimensions_m = {4.5, 1.8, 1.5};
    return p;
  }

  shape::ActiveShapeModel model_;
  EvaluationOptions options_;
};

TEST_F(ShapeMeasures, PerfectPredictionHasZeroErrors) {
  const EvaluationSummary s = evaluate(ref(), pred());
  EXPECT_EQ(s.shapeSamples, 1);
  EXPECT_EQ(s.keypointsBox.vehicles, 1);
  EXPECT_EQ(s.keypointsWorld.vehicles, 1);
  EXPECT_EQ(s.keypointsVehicle.vehicles, 1);
  for (const double e :
       {s.rmsLength_m, s.rmsWidth_m, s.rmsHeight_m, s.keypointsBox.planimetricRms_m,
        s.keypointsBox.heightRms_m, s.keypointsWorld.planimetricRms_m, s.keypointsWorld.heightRms_m,
        s.rmsLiftedLength_m, s.positionWorld_m.median}) {
    EXPECT_NEAR(e, 0.0, 1e-12);
  }
}

TEST_F(ShapeMeasures, HeightComponentGivesKnownHeightErrors) {
  PredictedObject p = pred();
  p.shape = gamma(0.5F, 0.0F);  // every keypoint 0.5 m higher
  const EvaluationSummary s = evaluate(ref(), p);
  EXPECT_NEAR(s.keypointsVehicle.heightRms_m, 0.5, 1e-6);
  EXPECT_NEAR(s.keypointsVehicle.planimetricRms_m, 0.0, 1e-9);
  EXPECT_NEAR(s.keypointsBox.heightRms_m, 0.5, 1e-6);
  EXPECT_NEAR(s.rmsHeight_m, 0.5, 1e-6);  // the highest keypoint rose by 0.5 m
  EXPECT_NEAR(s.rmsLength_m, 0.0, 1e-9);
  EXPECT_NEAR(s.rmsWidth_m, 0.0, 1e-9);
}

TEST_F(ShapeMeasures, ForwardComponentAndPoseErrorsGiveKnownDistances) {
  PredictedObject p = pred();
  p.shape = gamma(0.0F, 0.25F);  // every keypoint 0.25 m forward: a shift, no size change
  EvaluationSummary s = evaluate(ref(), p);
  EXPECT_NEAR(s.keypointsVehicle.planimetricRms_m, 0.25, 1e-6);
  EXPECT_NEAR(s.keypointsBox.planimetricRms_m, 0.25, 1e-6);
  EXPECT_NEAR(s.keypointsWorld.planimetricRms_m, 0.25, 1e-6);
  EXPECT_NEAR(s.rmsLength_m, 0.0, 1e-6);

  // Same shape, box 3 px off at 0.1 m/px: every keypoint 0.3 m off in the box placement;
  // lifted 0.4 m east and 0.1 m up: 0.4 m and 0.1 m in the world placement.
  p = pred();
  p.box.cx += 3.0;
  p.positionEnu += Eigen::Vector3d(0.4, 0.0, 0.1);
  p.dimensions_m.x() += 0.2;
  s = evaluate(ref(), p);
  EXPECT_NEAR(s.keypointsBox.planimetricRms_m, 0.3, 1e-9);
  EXPECT_NEAR(s.keypointsBox.heightRms_m, 0.0, 1e-12);
  EXPECT_NEAR(s.keypointsWorld.planimetricRms_m, 0.4, 1e-9);
  EXPECT_NEAR(s.keypointsWorld.heightRms_m, 0.1, 1e-9);
  EXPECT_NEAR(s.keypointsVehicle.planimetricRms_m, 0.0, 1e-12);
  EXPECT_NEAR(s.positionWorld_m.median, 0.4, 1e-9);
  EXPECT_NEAR(s.rmsLiftedLength_m, 0.2, 1e-9);
  EXPECT_NEAR(s.position_m.median, 0.3, 1e-9);
}

TEST_F(ShapeMeasures, ReversedDirectionMirrorsTheKeypoints) {
  PredictedObject p = pred();
  p.box.angle = geometry::wrapTwoPi(p.box.angle + kPi);
  p.headingEnu_rad = geometry::wrapTwoPi(p.headingEnu_rad + kPi);
  const EvaluationSummary s = evaluate(ref(), p);
  // Turned by 180 degrees about the centre: keypoint (x, y) moves by 2 |(x, y)|.
  double sum = 0.0;
  for (const int k : shape::evaluationKeypoints()) {
    sum += 4.0 * model_.mean().col(k).head<2>().squaredNorm();
  }
  const double expected = std::sqrt(sum / shape::kEvaluationKeypointCount);
  EXPECT_NEAR(s.keypointsBox.planimetricRms_m, expected, 1e-9);
  EXPECT_NEAR(s.keypointsWorld.planimetricRms_m, expected, 1e-9);
  EXPECT_NEAR(s.orientation_deg.median, 180.0, 1e-9);
  EXPECT_NEAR(s.headingWorld_deg.median, 180.0, 1e-9);
  EXPECT_NEAR(s.keypointsVehicle.planimetricRms_m, 0.0, 1e-12);
}

TEST(Gsd, FromWheelKeypoints) {
  // Wheels 2.7 m apart along x, 1.5 m across, seen at 0.05 m/px.
  const std::array<Eigen::Vector3d, 4> world{
      Eigen::Vector3d(1.35, 0.75, 0.3), Eigen::Vector3d(1.35, -0.75, 0.3),
      Eigen::Vector3d(-1.35, 0.75, 0.3), Eigen::Vector3d(-1.35, -0.75, 0.3)};
  std::array<Eigen::Vector2d, 4> pixels;
  for (std::size_t i = 0; i < 4; ++i) {
    pixels[i] = world[i].head<2>() / 0.05;
  }
  EXPECT_NEAR(gsdFromWheelKeypoints(pixels, world), 0.05, 1e-12);
  pixels.fill(Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN()));
  EXPECT_TRUE(std::isnan(gsdFromWheelKeypoints(pixels, world)));
}

TEST(SeedReference, TablesAreTranscribed) {
  EXPECT_DOUBLE_EQ(seedFigure("precision")->value, 0.816);
  EXPECT_DOUBLE_EQ(seedFigure("orientation_median_deg")->value, 2.8);
  EXPECT_DOUBLE_EQ(seedFigure("type_oa2")->value, 0.781);
  EXPECT_DOUBLE_EQ(seedFigure("e_dh_m")->value, 0.24);
  EXPECT_TRUE(seedFigure("orientation_flip_share")->approximate);
  EXPECT_FALSE(seedFigure("no_such_measure").has_value());
  for (const SeedFigure& f : seedFigures()) {
    EXPECT_FALSE(f.source.empty()) << f.measure;
  }
}

}  // namespace
}  // namespace vp::evaluation
