// tracking/world_detection: the tracker's input, one vehicle detection lifted to the world.
//
// Contract: a plain value the perception stage fills from a detection and its GroundBox
// (lifting/lifting.hpp) and the tracker only reads. Positions are world ENU metres
// (docs/conventions.md); the heading is the driving direction, counter-clockwise from east,
// never folded to 180 degrees; headingKnown is false when the detector could not tell
// front from back (the tracker then uses the position only). typeProbabilities sum to 1
// over shape::VehicleType (index = static_cast<int>(type)); shape holds the detector's ASM
// gamma (count 0 when it has none, e.g. large vehicles). score in [0, 1] splits the
// detections into the two association passes. A detection with a non-finite field, a size
// <= 0, a score or insideShare outside [0, 1] is rejected and counted by the tracker, never used.
#pragma once

#include <array>
#include <cstdint>

#include <Eigen/Core>

#include "shape/vehicle_model.hpp"

namespace vp::tracking {

struct WorldDetection {
  std::int64_t timestamp_ns = 0;        // frame capture time (the loop's clock)
  Eigen::Vector2d centreEnu{0.0, 0.0};  // footprint centre, m
  double headingEnu_rad = 0.0;          // driving direction, [0, 2 pi)
  bool headingKnown = true;             // false: front/back undecided
  double length_m = 0.0;                // footprint along the heading
  double width_m = 0.0;                 // footprint across it
  float score = 0.0f;                   // detector confidence, [0, 1]
  std::array<float, shape::kVehicleTypeCount> typeProbabilities{};  // sum 1
  shape::ShapeParams shape{};                                       // ASM gamma
  bool atFrameEdge = false;  // cut by the image border: centre and size biased (less weight)
  double insideShare = 1.0;  // share of the image box inside the frame, [0, 1]
};

}  // namespace vp::tracking
