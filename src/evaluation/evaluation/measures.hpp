// evaluation/measures: every measure of seed 000, section 5.1, accumulated image by image:
// detection (precision, recall, F1 at IoU 0.5), pose (median and MAD of the position and
// orientation errors, the cumulative histogram of |d_theta|, the share of flipped directions),
// type (F1 per class, OA-1, OA-2) and shape (RMS of the length, width and height of the
// enclosing 3D boxes of the ASM models, Eq. 10; RMS of the planimetric keypoint distance E_D2D
// and of the keypoint height difference E_dH, Eq. 9, over the ASM's 24 evaluation keypoints).
//
// Contract: the Evaluator is given, per image, the reference objects (ReferenceObject) and the
// predictions (PredictedObject), matches them with greedyMatch() (matching.hpp) and keeps the
// errors of the matched pairs; summary() computes the measures. Definitions (docs/evaluation.md):
//   - position: |centre_pred - centre_ref| in px, and in metres as px x the reference's ground
//     sampling distance (the seed converts with the GSD too); separately the horizontal
//     distance of the lifted world position to the reference's, where the prediction was lifted;
//   - orientation: |d_theta| over 360 degrees of the box angles (a reversed driving direction
//     is 180 degrees), where the reference's direction is known;
//   - type: over matched pairs whose reference type is known; the ranking is the prediction's
//     probabilities (ties: VehicleType order); per-class F1 = 2 TP / (2 TP + FP + FN);
//   - shape: over matched pairs where both have gamma and an ASM is given: keypoints
//     M(gamma) (Eq. 1) placed three ways: "box" = each model shifted and rotated into its own
//     image box on a ground plane scaled by the reference's GSD (pose + shape error, the
//     seed's image-space reading); "world" = at the lifted world position and heading vs the
//     reference's world pose (needs lifting); "vehicle" = both in the vehicle frame (shape only).
// Offline: it allocates; the real-time loop never calls it. Values that cannot be computed
// (no sample) are NaN, never 0.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "evaluation/matching.hpp"
#include "evaluation/statistics.hpp"
#include "geometry/rotated_box.hpp"
#include "shape/vehicle_model.hpp"

namespace vp::evaluation {

constexpr double kDefaultIouThreshold = 0.5;   // seed 000, sec. 5.1
constexpr double kFlipThreshold_deg = 90.0;    // |d_theta| above this: front and back swapped
constexpr int kCumulativeHistogramBins = 181;  // |d_theta| <= 0, 1, ..., 180 deg

// A label box within this distance of the image's edge counts as cut by the border, px.
constexpr double kImageBorderTolerance_px = 2.0;

struct ReferenceObject {
  geometry::RotatedBox box{};  // image px; axis-aligned references: angle 0, length = w, width = h
  bool axisAligned = false;    // only the axis-aligned box is known (YOLO labels)
  bool ignore = false;         // heavily occluded / truncated: neither TP nor FP when matched
  // The labelled box reaches the image's edge (within kImageBorderTolerance_px): a vehicle cut
  // by the border, labelled as its visible part (YOLO labels). Counted apart among the misses.
  bool cutByImageBorder = false;
  bool directionKnown = true;  // box.angle is the driving direction
  int type = -1;               // static_cast<int>(shape::VehicleType), -1 unknown
  shape::ShapeParams shape{};  // count 0: no shape (large vehicles, real images)
  double gsd_m = std::numeric_limits<double>::quiet_NaN();  // metres per px at the object
  bool hasWorld = false;                                    // the next three are set
  Eigen::Vector3d positionEnu{0, 0, 0};                     // vehicle-frame origin, world ENU, m
  double headingEnu_rad = 0.0;
  Eigen::Vector3d dimensions_m{0, 0, 0};  // length, width, height
};

struct PredictedObject {
  geometry::RotatedBox box{};  // image px
  float score = 0.0F;
  bool directionKnown = true;
  // The box reaches the frame's border (the detections file's at_frame_edge, format 2): a false
  // one is counted apart, for sets that label no vehicle cut by the border.
  bool atFrameEdge = false;
  bool hasTypeProbabilities = true;
  std::array<float, shape::kVehicleTypeCount> typeProbabilities{};
  shape::ShapeParams shape{};
  bool lifted = false;  // the next three are set
  Eigen::Vector3d positionEnu{0, 0, 0};
  double headingEnu_rad = 0.0;
  Eigen::Vector3d dimensions_m{0, 0, 0};
};

struct EvaluationOptions {
  double iouThreshold = kDefaultIouThreshold;
  bool axisAligned = false;  // match enclosing axis-aligned boxes (references must be axis-aligned)
  const shape::ActiveShapeModel* asmModel = nullptr;  // borrowed; null: no shape measures
};

struct ClassScore {
  int truePositives = 0;
  int falsePositives = 0;
  int falseNegatives = 0;
  double f1 = 0.0;  // NaN when the class never occurs in reference or prediction
};

// RMS keypoint errors of one placement (Eq. 9).
struct KeypointErrors {
  int vehicles = 0;
  double planimetricRms_m = 0.0;  // E_D2D; NaN when vehicles is 0
  double heightRms_m = 0.0;       // E_dH
};

struct EvaluationSummary {
  // counts
  int images = 0;
  int references = 0;         // all reference objects, ignored ones included
  int ignoredReferences = 0;  // flagged ignore
  int predictions = 0;
  int truePositives = 0;
  int falsePositives = 0;
  int falseNegatives = 0;
  int falseNegativesCutByBorder = 0;  // of falseNegatives: references with cutByImageBorder
  int falsePositivesAtFrameEdge = 0;  // of falsePositives: predictions with atFrameEdge
  // TP / (TP + FP - falsePositivesAtFrameEdge): the precision of a set whose labels leave out
  // every vehicle cut by the frame's border (information; the rule's precision is `precision`).
  double precisionInside = 0.0;
  int ignoredPredictions = 0;  // matched to / overlapping an ignored reference
  double precision = 0.0;      // TP / (TP + FP); 0 when nothing was predicted
  double recall = 0.0;         // TP / (TP + FN)
  double f1 = 0.0;
  double meanMatchedIou = 0.0;  // NaN without pairs
  // pose
  RobustSummary position_px;
  RobustSummary position_m;                   // px x reference GSD
  RobustSummary positionWorld_m;              // lifted vs reference, horizontal
  RobustSummary orientation_deg;              // |d_theta| over 360 deg
  RobustSummary axisOrientation_deg;          // ignoring front/back, [0, 90]
  RobustSummary headingWorld_deg;             // lifted heading vs reference heading
  double flipShare = 0.0;                     // share of |d_theta| > 90 deg
  double shareBelow10_deg = 0.0;              // share of |d_theta| <= 10 deg (the seed quotes it)
  std::vector<double> orientationCumulative;  // [k] share with |d_theta| <= k deg, k = 0..180
  std::vector<double> orientationErrors_deg;  // all |d_theta|, sorted (for plots)
  int directionUnknownPredictions = 0;        // matched predictions without a known direction
  // type
  int typeSamples = 0;
  double typeOa1 = 0.0;  // NaN without samples
  double typeOa2 = 0.0;
  std::array<ClassScore, shape::kVehicleTypeCount> typeF1{};
  std::array<std::array<int, shape::kVehicleTypeCount>, shape::kVehicleTypeCount> confusion{};
  // shape
  int shapeSamples = 0;      // matched pairs where both have gamma (and an ASM is given)
  double rmsLength_m = 0.0;  // Eq. 10 over the enclosing boxes of M(gamma); NaN without samples
  double rmsWidth_m = 0.0;
  double rmsHeight_m = 0.0;
  int liftedDimensionSamples = 0;  // lifted length/width/height vs the reference's
  double rmsLiftedLength_m = 0.0;
  double rmsLiftedWidth_m = 0.0;
  double rmsLiftedHeight_m = 0.0;
  KeypointErrors keypointsBox;      // placed in the image boxes (GSD)
  KeypointErrors keypointsWorld;    // placed at the lifted world pose
  KeypointErrors keypointsVehicle;  // shape only
};

class Evaluator {
 public:
  explicit Evaluator(const EvaluationOptions& options = {}) : options_(options) {}

  // One image: references and predictions. Returns the matches (for callers that list them).
  MatchResult addImage(std::span<const ReferenceObject> references,
                       std::span<const PredictedObject> predictions);
  EvaluationSummary summary() const;

 private:
  void addPair(const ReferenceObject& reference, const PredictedObject& prediction, double iou);

  EvaluationOptions options_;
  int images_ = 0;
  int references_ = 0;
  int ignoredReferences_ = 0;
  int predictions_ = 0;
  int truePositives_ = 0;
  int falsePositives_ = 0;
  int falseNegatives_ = 0;
  int falseNegativesCutByBorder_ = 0;
  int falsePositivesAtFrameEdge_ = 0;
  int ignoredPredictions_ = 0;
  int directionUnknown_ = 0;
  std::vector<double> iou_;
  std::vector<double> positionPx_;
  std::vector<double> positionM_;
  std::vector<double> positionWorldM_;
  std::vector<double> orientationDeg_;
  std::vector<double> axisOrientationDeg_;
  std::vector<double> headingWorldDeg_;
  int typeSamples_ = 0;
  int typeTop1_ = 0;
  int typeTop2_ = 0;
  std::array<std::array<int, shape::kVehicleTypeCount>, shape::kVehicleTypeCount> confusion_{};
  std::array<std::vector<double>, 3> dimensionErrors_;        // length, width, height
  std::array<std::vector<double>, 3> liftedDimensionErrors_;  // length, width, height
  // Per placement (box, world, vehicle): per-keypoint planimetric distances and height
  // differences, and the vehicle count.
  std::array<std::vector<double>, 3> keypointDistances_;
  std::array<std::vector<double>, 3> keypointHeights_;
  std::array<int, 3> keypointVehicles_{};
};

// Ground sampling distance at a vehicle from its wheel-centre keypoints (shape::
// wheelCentreKeypoints(): front left, front right, rear left, rear right): the ratio of the
// horizontal world distance to the pixel distance over the four sides of the wheel rectangle,
// weighted by the world length; sides shorter than 1 px or with a non-finite keypoint are
// skipped. NaN when none is left. (The same estimate as tools/detector/datasets.py.)
double gsdFromWheelKeypoints(std::span<const Eigen::Vector2d, shape::kWheelCount> pixels,
                             std::span<const Eigen::Vector3d, shape::kWheelCount> worldEnu);

}  // namespace vp::evaluation
