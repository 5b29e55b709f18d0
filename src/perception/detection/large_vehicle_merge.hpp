// detection/large_vehicle_merge: one box for a bus or truck the first stage boxed in parts.
//
// Contract: the first stage can fire twice along a long vehicle (a 14 m box truck at 4 cm/px is
// 350 px long), and when the two boxes overlap less than the suppression's thresholds both
// survive, each a part of the vehicle. mergeLargeVehicleParts() joins such parts after the
// second stage: detections i and k (k earlier in the array, i.e. the better one) merge when both
// are most likely Large (topTwoTypes), their axes are parallel within maxAxisAngle_deg (folded
// to 180 deg), the centre of i lies within maxLateralShare x the narrower width of k's axis,
// and their extents along k's axis overlap or touch (two vehicles queued bumper to bumper leave
// a gap). The merged box is k's, stretched along its own axis over both extents (centre moved
// to the middle), with the larger width and score; type, shape and heading stay k's. A merge
// whose length would pass maxLength_m (at gsd_m; no limit when gsd_m is not positive) is not
// made. Chains of parts merge one after the other. Order is kept. No heap allocation.
// absorbLongerDuplicate() serves the detection stage's last suppression: where the first stage
// boxed one bus twice, its front part and nearly all of it, the part (the better score) would
// win and the longer box go; instead a most-likely-Large kept box is stretched over the longer
// duplicate with the same geometry and limits (its type need not be Large: the crop network
// sees only the middle of a long box).
#pragma once

#include <cstddef>
#include <span>

#include "detection/detection.hpp"

namespace vp::detection {

// Defaults are the shipped configuration's (perception.large_vehicle_merge*, config/default.yaml).
struct LargeVehicleMergeOptions {
  bool enabled = true;
  double maxAxisAngle_deg = 10.0;  // parts' axes parallel within this, [0, 45]
  double maxLateralShare = 0.5;    // centre offset across the axis / narrower width, [0, 1]
  double maxLength_m = 25.0;       // no merged box longer than this (articulated bus), (0, 60]
};

// Merges the parts in place (see contract); returns the number of detections kept (the first
// ones of detections).
std::size_t mergeLargeVehicleParts(std::span<Detection> detections, double gsd_m,
                                   const LargeVehicleMergeOptions& options);

// Stretches kept over duplicate (see contract) when options.enabled, kept is most likely Large
// and duplicate is the longer box; true when it did (the caller then drops duplicate as before).
bool absorbLongerDuplicate(Detection& kept, const Detection& duplicate, double gsd_m,
                           const LargeVehicleMergeOptions& options);

}  // namespace vp::detection
