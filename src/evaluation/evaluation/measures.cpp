#include "evaluation/measures.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace vp::evaluation {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kDegPerRad = 180.0 / geometry::kPi;
constexpr double kMinWheelSide_px = 1.0;  // shorter sides give no usable GSD

enum Placement { kBox = 0, kWorld = 1, kVehicle = 2 };

// Keypoints of a model placed on a ground plane: x, y horizontal (right-handed), z up.
Eigen::Matrix<double, 3, shape::kKeypointCount> place(const shape::KeypointModel& model,
                                                      const Eigen::Vector3d& origin,
                                                      double heading_rad) {
  const double c = std::cos(heading_rad);
  const double s = std::sin(heading_rad);
  Eigen::Matrix3d rotation;
  rotation << c, -s, 0, s, c, 0, 0, 0, 1;
  return (rotation * model).colwise() + origin;
}

// The image box on a metric ground plane x = u g, y = -v g (right-handed, y "up" the image):
// the forward axis (cos a, sin a) in (u, v) becomes heading -a.
Eigen::Vector3d boxOrigin(const geometry::RotatedBox& box, double gsd) {
  return {box.cx * gsd, -box.cy * gsd, 0.0};
}

// Index order of the type probabilities, most probable first (ties: VehicleType order).
std::array<int, shape::kVehicleTypeCount> typeRanking(
    const std::array<float, shape::kVehicleTypeCount>& p) {
  std::array<int, shape::kVehicleTypeCount> order{};
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return p[static_cast<std::size_t>(a)] > p[static_cast<std::size_t>(b)];
  });
  return order;
}

double safeRatio(int numerator, int denominator) {
  return denominator > 0 ? static_cast<double>(numerator) / static_cast<double>(denominator) : kNan;
}

}  // namespace

MatchResult Evaluator::addImage(std::span<const ReferenceObject> references,
                                std::span<const PredictedObject> predictions) {
  ++images_;
  references_ += static_cast<int>(references.size());
  predictions_ += static_cast<int>(predictions.size());
  std::vector<geometry::RotatedBox> predictedBoxes;
  std::vector<float> scores;
  for (const PredictedObject& p : predictions) {
    predictedBoxes.push_back(p.box);
    scores.push_back(p.score);
  }
  std::vector<std::uint8_t> ignore;
  for (const ReferenceObject& r : references) {
    ignore.push_back(r.ignore ? 1 : 0);
    ignoredReferences_ += r.ignore ? 1 : 0;
  }
  std::vector<double> iou;
  if (options_.axisAligned) {
    std::vector<AxisBox> boxes;
    for (const ReferenceObject& r : references) {
      boxes.push_back(r.axisAligned ? AxisBox{r.box.cx, r.box.cy, r.box.length, r.box.width}
                                    : enclosingAxisBox(r.box));
    }
    iou = axisAlignedIouMatrix(predictedBoxes, boxes);
  } else {
    std::vector<geometry::RotatedBox> boxes;
    for (const ReferenceObject& r : references) {
      boxes.push_back(r.box);
    }
    iou = rotatedIouMatrix(predictedBoxes, boxes);
  }
  MatchResult match = greedyMatch(scores, iou, ignore, options_.iouThreshold);
  truePositives_ += static_cast<int>(match.pairs.size());
  falsePositives_ += static_cast<int>(match.falsePositives.size());
  falseNegatives_ += static_cast<int>(match.falseNegatives.size());
  for (const int r : match.falseNegatives) {
    falseNegativesCutByBorder_ += references[static_cast<std::size_t>(r)].cutByImageBorder ? 1 : 0;
  }
  for (const int p : match.falsePositives) {
    falsePositivesAtFrameEdge_ += predictions[static_cast<std::size_t>(p)].atFrameEdge ? 1 : 0;
  }
  ignoredPredictions_ += static_cast<int>(match.ignoredPredictions.size());
  for (const auto& [p, r] : match.pairs) {
    const auto pi = static_cast<std::size_t>(p);
    const auto ri = static_cast<std::size_t>(r);
    addPair(references[ri], predictions[pi], iou[pi * references.size() + ri]);
  }
  return match;
}

void Evaluator::addPair(const ReferenceObject& reference, const PredictedObject& prediction,
                        double iou) {
  iou_.push_back(iou);
  // Position.
  const double distance_px =
      std::hypot(prediction.box.cx - reference.box.cx, prediction.box.cy - reference.box.cy);
  positionPx_.push_back(distance_px);
  const bool hasGsd = std::isfinite(reference.gsd_m);
  if (hasGsd) {
    positionM_.push_back(distance_px * reference.gsd_m);
  }
  const bool world = prediction.lifted && reference.hasWorld;
  if (world) {
    positionWorldM_.push_back((prediction.positionEnu - reference.positionEnu).head<2>().norm());
    headingWorldDeg_.push_back(
        geometry::absAngleDifference(prediction.headingEnu_rad, reference.headingEnu_rad) *
        kDegPerRad);
  }
  // Orientation: axis-aligned references carry no angle.
  if (!options_.axisAligned && !reference.axisAligned && reference.directionKnown) {
    orientationDeg_.push_back(
        geometry::absAngleDifference(prediction.box.angle, reference.box.angle) * kDegPerRad);
    axisOrientationDeg_.push_back(
        geometry::axisAngleDifference(prediction.box.angle, reference.box.angle) * kDegPerRad);
    directionUnknown_ += prediction.directionKnown ? 0 : 1;
  }
  // Type.
  if (prediction.hasTypeProbabilities && reference.type >= 0 &&
      reference.type < shape::kVehicleTypeCount) {
    const auto ranking = typeRanking(prediction.typeProbabilities);
    ++typeSamples_;
    typeTop1_ += ranking[0] == reference.type ? 1 : 0;
    typeTop2_ += (ranking[0] == reference.type || ranking[1] == reference.type) ? 1 : 0;
    ++confusion_[static_cast<std::size_t>(reference.type)][static_cast<std::size_t>(ranking[0])];
  }
  // Lifted size against the reference's 3D box.
  if (world) {
    for (int d = 0; d < 3; ++d) {
      liftedDimensionErrors_[static_cast<std::size_t>(d)].push_back(prediction.dimensions_m[d] -
                                                                    reference.dimensions_m[d]);
    }
  }
  // Shape.
  const shape::ActiveShapeModel* model = options_.asmModel;
  if (model == nullptr || reference.shape.count == 0 || prediction.shape.count == 0) {
    return;
  }
  const shape::KeypointModel predicted = model->shape(prediction.shape);
  const shape::KeypointModel truth = model->shape(reference.shape);
  const Eigen::Vector3d predictedSize = shape::boundingBoxSize(predicted);
  const Eigen::Vector3d truthSize = shape::boundingBoxSize(truth);
  for (int d = 0; d < 3; ++d) {
    dimensionErrors_[static_cast<std::size_t>(d)].push_back(predictedSize[d] - truthSize[d]);
  }
  const auto addKeypoints = [&](Placement placement, const auto& a, const auto& b) {
    for (const int k : shape::evaluationKeypoints()) {
      const Eigen::Vector3d delta = a.col(k) - b.col(k);
      keypointDistances_[placement].push_back(delta.head<2>().norm());
      keypointHeights_[placement].push_back(std::abs(delta.z()));
    }
    ++keypointVehicles_[placement];
  };
  addKeypoints(kVehicle, predicted, truth);
  if (hasGsd && !reference.axisAligned) {
    addKeypoints(
        kBox, place(predicted, boxOrigin(prediction.box, reference.gsd_m), -prediction.box.angle),
        place(truth, boxOrigin(reference.box, reference.gsd_m), -reference.box.angle));
  }
  if (world) {
    addKeypoints(kWorld, place(predicted, prediction.positionEnu, prediction.headingEnu_rad),
                 place(truth, reference.positionEnu, reference.headingEnu_rad));
  }
}

EvaluationSummary Evaluator::summary() const {
  EvaluationSummary s;
  s.images = images_;
  s.references = references_;
  s.ignoredReferences = ignoredReferences_;
  s.predictions = predictions_;
  s.truePositives = truePositives_;
  s.falsePositives = falsePositives_;
  s.falseNegatives = falseNegatives_;
  s.falseNegativesCutByBorder = falseNegativesCutByBorder_;
  s.falsePositivesAtFrameEdge = falsePositivesAtFrameEdge_;
  s.ignoredPredictions = ignoredPredictions_;
  // evaluate.py's convention: max(1, denominator), so nothing predicted gives 0, not NaN.
  s.precision = static_cast<double>(truePositives_) / std::max(1, truePositives_ + falsePositives_);
  s.recall = static_cast<double>(truePositives_) / std::max(1, truePositives_ + falseNegatives_);
  s.precisionInside = static_cast<double>(truePositives_) /
                      std::max(1, truePositives_ + falsePositives_ - falsePositivesAtFrameEdge_);
  s.f1 =
      s.precision + s.recall > 0.0 ? 2.0 * s.precision * s.recall / (s.precision + s.recall) : 0.0;
  s.meanMatchedIou = iou_.empty() ? kNan
                                  : std::accumulate(iou_.begin(), iou_.end(), 0.0) /
                                        static_cast<double>(iou_.size());
  s.position_px = robustSummary(positionPx_);
  s.position_m = robustSummary(positionM_);
  s.positionWorld_m = robustSummary(positionWorldM_);
  s.orientation_deg = robustSummary(orientationDeg_);
  s.axisOrientation_deg = robustSummary(axisOrientationDeg_);
  s.headingWorld_deg = robustSummary(headingWorldDeg_);
  s.flipShare = shareAbove(orientationDeg_, kFlipThreshold_deg);
  const std::array<double, 1> ten{10.0};
  s.shareBelow10_deg = cumulativeShare(orientationDeg_, ten)[0];
  std::vector<double> thresholds(kCumulativeHistogramBins);
  std::iota(thresholds.begin(), thresholds.end(), 0.0);
  s.orientationCumulative = cumulativeShare(orientationDeg_, thresholds);
  s.orientationErrors_deg = orientationDeg_;
  std::sort(s.orientationErrors_deg.begin(), s.orientationErrors_deg.end());
  s.directionUnknownPredictions = directionUnknown_;
  s.typeSamples = typeSamples_;
  s.typeOa1 = safeRatio(typeTop1_, typeSamples_);
  s.typeOa2 = safeRatio(typeTop2_, typeSamples_);
  s.confusion = confusion_;
  for (int c = 0; c < shape::kVehicleTypeCount; ++c) {
    ClassScore& score = s.typeF1[static_cast<std::size_t>(c)];
    for (int other = 0; other < shape::kVehicleTypeCount; ++other) {
      if (other == c) {
        continue;
      }
      score.falseNegatives +=
          confusion_[static_cast<std::size_t>(c)][static_cast<std::size_t>(other)];
      score.falsePositives +=
          confusion_[static_cast<std::size_t>(other)][static_cast<std::size_t>(c)];
    }
    score.truePositives = confusion_[static_cast<std::size_t>(c)][static_cast<std::size_t>(c)];
    score.f1 = safeRatio(2 * score.truePositives,
                         2 * score.truePositives + score.falsePositives + score.falseNegatives);
  }
  s.shapeSamples = static_cast<int>(dimensionErrors_[0].size());
  s.rmsLength_m = rootMeanSquare(dimensionErrors_[0]);
  s.rmsWidth_m = rootMeanSquare(dimensionErrors_[1]);
  s.rmsHeight_m = rootMeanSquare(dimensionErrors_[2]);
  s.liftedDimensionSamples = static_cast<int>(liftedDimensionErrors_[0].size());
  s.rmsLiftedLength_m = rootMeanSquare(liftedDimensionErrors_[0]);
  s.rmsLiftedWidth_m = rootMeanSquare(liftedDimensionErrors_[1]);
  s.rmsLiftedHeight_m = rootMeanSquare(liftedDimensionErrors_[2]);
  const auto keypoints = [&](Placement placement) {
    return KeypointErrors{keypointVehicles_[placement],
                          rootMeanSquare(keypointDistances_[placement]),
                          rootMeanSquare(keypointHeights_[placement])};
  };
  s.keypointsBox = keypoints(kBox);
  s.keypointsWorld = keypoints(kWorld);
  s.keypointsVehicle = keypoints(kVehicle);
  return s;
}

double gsdFromWheelKeypoints(std::span<const Eigen::Vector2d, shape::kWheelCount> pixels,
                             std::span<const Eigen::Vector3d, shape::kWheelCount> worldEnu) {
  // Wheel sides: left (FL-RL), right (FR-RR), front (FL-FR), rear (RL-RR).
  constexpr std::array<std::pair<int, int>, 4> kSides{{{0, 2}, {1, 3}, {0, 1}, {2, 3}}};
  double weighted = 0.0;
  double weights = 0.0;
  for (const auto& [i, j] : kSides) {
    const auto a = static_cast<std::size_t>(i);
    const auto b = static_cast<std::size_t>(j);
    // std::hypot, as numpy's hypot in datasets.py, so both give the same bits.
    const double pixel = std::hypot(pixels[a].x() - pixels[b].x(), pixels[a].y() - pixels[b].y());
    const double world =
        std::hypot(worldEnu[a].x() - worldEnu[b].x(), worldEnu[a].y() - worldEnu[b].y());
    if (std::isfinite(pixel) && std::isfinite(world) && pixel > kMinWheelSide_px) {
      weighted += world / pixel * world;
      weights += world;
    }
  }
  return weights > 0.0 ? weighted / weights : kNan;
}

}  // namespace vp::evaluation
