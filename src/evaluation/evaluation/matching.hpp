// evaluation/matching: pairing predictions with reference objects in one image, as seed 000,
// section 5.1 counts true positives, false positives and false negatives.
//
// Contract: greedyMatch() visits the predictions by decreasing score (ties: input order); each
// takes the still-free reference with the highest IoU (ties: the first); the pair counts when
// that IoU is >= the threshold (the seed says "above 50 %"; >= and > only differ on exact
// ties). A reference flagged `ignore` (heavily occluded or truncated) can be taken, but the pair
// is neither a true positive nor a false positive; a prediction that is not matched but
// overlaps an ignored reference by the threshold is not a false positive either. Unmatched,
// non-ignored references are false negatives. This is the rule of tools/detector/evaluate.py's
// match(), so both tools count the same. The IoU helpers give the rotated IoU
// (geometry::rotatedIou) or the axis-aligned IoU of a prediction's enclosing box against an
// axis-aligned reference (real images labelled in YOLO format). Offline: results allocate.
#pragma once

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "geometry/rotated_box.hpp"

namespace vp::evaluation {

// Axis-aligned box: centre and full extents along u and v, px.
struct AxisBox {
  double cx = 0.0;
  double cy = 0.0;
  double width = 0.0;
  double height = 0.0;
};

// The smallest axis-aligned box holding the rotated box.
AxisBox enclosingAxisBox(const geometry::RotatedBox& box);
// Intersection over union in [0, 1]; 0 when either box is empty.
double axisAlignedIou(const AxisBox& a, const AxisBox& b);

// IoU matrices, row-major [prediction][reference].
std::vector<double> rotatedIouMatrix(std::span<const geometry::RotatedBox> predictions,
                                     std::span<const geometry::RotatedBox> references);
std::vector<double> axisAlignedIouMatrix(std::span<const geometry::RotatedBox> predictions,
                                         std::span<const AxisBox> references);

struct MatchResult {
  std::vector<std::pair<int, int>> pairs;  // (prediction, reference): true positives
  std::vector<int> falsePositives;         // predictions
  std::vector<int> falseNegatives;         // references
  std::vector<int> ignoredPredictions;     // matched to, or overlapping, an ignored reference
};

// scores: one per prediction; iou: predictions x references (row-major); ignore: one flag
// (0/1) per reference.
MatchResult greedyMatch(std::span<const float> scores, std::span<const double> iou,
                        std::span<const std::uint8_t> ignore, double iouThreshold);

}  // namespace vp::evaluation
