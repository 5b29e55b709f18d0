#include "evaluation/matching.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numeric>

namespace vp::evaluation {

AxisBox enclosingAxisBox(const geometry::RotatedBox& box) {
  const double c = std::abs(std::cos(box.angle));
  const double s = std::abs(std::sin(box.angle));
  return AxisBox{box.cx, box.cy, box.length * c + box.width * s, box.length * s + box.width * c};
}

double axisAlignedIou(const AxisBox& a, const AxisBox& b) {
  const double overlapU = std::min(a.cx + a.width / 2, b.cx + b.width / 2) -
                          std::max(a.cx - a.width / 2, b.cx - b.width / 2);
  const double overlapV = std::min(a.cy + a.height / 2, b.cy + b.height / 2) -
                          std::max(a.cy - a.height / 2, b.cy - b.height / 2);
  const double intersection = std::max(overlapU, 0.0) * std::max(overlapV, 0.0);
  const double unionArea = a.width * a.height + b.width * b.height - intersection;
  return unionArea > 0.0 ? intersection / unionArea : 0.0;
}

std::vector<double> rotatedIouMatrix(std::span<const geometry::RotatedBox> predictions,
                                     std::span<const geometry::RotatedBox> references) {
  std::vector<double> iou(predictions.size() * references.size(), 0.0);
  for (std::size_t p = 0; p < predictions.size(); ++p) {
    for (std::size_t r = 0; r < references.size(); ++r) {
      iou[p * references.size() + r] = geometry::rotatedIou(predictions[p], references[r]);
    }
  }
  return iou;
}

std::vector<double> axisAlignedIouMatrix(std::span<const geometry::RotatedBox> predictions,
                                         std::span<const AxisBox> references) {
  std::vector<double> iou(predictions.size() * references.size(), 0.0);
  for (std::size_t p = 0; p < predictions.size(); ++p) {
    const AxisBox box = enclosingAxisBox(predictions[p]);
    for (std::size_t r = 0; r < references.size(); ++r) {
      iou[p * references.size() + r] = axisAlignedIou(box, references[r]);
    }
  }
  return iou;
}

MatchResult greedyMatch(std::span<const float> scores, std::span<const double> iou,
                        std::span<const std::uint8_t> ignore, double iouThreshold) {
  const std::size_t predictionCount = scores.size();
  const std::size_t referenceCount = ignore.size();
  assert(iou.size() == predictionCount * referenceCount);
  MatchResult out;
  std::vector<std::size_t> order(predictionCount);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return scores[a] > scores[b]; });
  std::vector<std::uint8_t> taken(referenceCount, 0);
  for (const std::size_t p : order) {
    const double* row = iou.data() + p * referenceCount;
    int best = -1;
    double bestIou = -1.0;
    for (std::size_t r = 0; r < referenceCount; ++r) {
      const double value = taken[r] != 0 ? -1.0 : row[r];
      if (value > bestIou) {
        bestIou = value;
        best = static_cast<int>(r);
      }
    }
    if (best >= 0 && bestIou >= iouThreshold) {
      taken[static_cast<std::size_t>(best)] = 1;
      if (ignore[static_cast<std::size_t>(best)] != 0) {
        out.ignoredPredictions.push_back(static_cast<int>(p));
      } else {
        out.pairs.emplace_back(static_cast<int>(p), best);
      }
      continue;
    }
    // Overlapping an ignored reference (taken or not) is not a false positive.
    bool overlapsIgnored = false;
    for (std::size_t r = 0; r < referenceCount; ++r) {
      overlapsIgnored = overlapsIgnored || (ignore[r] != 0 && row[r] >= iouThreshold);
    }
    (overlapsIgnored ? out.ignoredPredictions : out.falsePositives).push_back(static_cast<int>(p));
  }
  for (std::size_t r = 0; r < referenceCount; ++r) {
    if (taken[r] == 0 && ignore[r] == 0) {
      out.falseNegatives.push_back(static_cast<int>(r));
    }
  }
  return out;
}

}  // namespace vp::evaluation
