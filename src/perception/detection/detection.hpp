// detection/detection: one vehicle found in a camera frame, in image space.
//
// Contract: the detection stage (decoder + second-stage crop network) fills these values and
// every later stage only reads them. Coordinates are pixels of the *frame* the perception
// stage works in: the undistorted full-resolution frame when undistortion is on (then the
// lifting stage uses the pinhole camera of that undistorted image), else the raw camera
// frame. box.angle is the driving direction over 360 degrees (docs/conventions.md: from +u
// towards +v) when directionKnown, else only the box axis is meaningful. score is the
// detector's vehicle-vs-background confidence in [0, 1]. typeProbabilities sum to 1 over
// shape::VehicleType (index = static_cast<int>(type)); uniform when no classifier ran.
// gamma holds the ASM shape parameters (count 0 when none was estimated, e.g. large vehicles).
// A Detection is a plain value: fixed size, no heap, copyable into preallocated arrays.
#pragma once

#include <array>
#include <cstdint>
#include <limits>

#include "geometry/rotated_box.hpp"
#include "shape/vehicle_model.hpp"

namespace vp::detection {

// Upper bound on detections per frame, after NMS across tiles (fixed memory).
constexpr int kMaxDetectionsPerFrame = 512;

struct Detection {
  geometry::RotatedBox box{};  // frame pixels; angle = driving direction when directionKnown
  float score = 0.0F;          // [0, 1]
  bool directionKnown = false;
  std::array<float, shape::kVehicleTypeCount> typeProbabilities{};  // sum 1
  shape::ShapeParams gamma{};                                       // ASM gamma (Eq. 1)
  float flipProbability = 0.0F;  // second stage's belief that the first stage's front was the rear
                                 // (already applied to box.angle; kept for the tracker / reports)
  std::int16_t tile = -1;        // index of the tile it came from (diagnostics)
  bool atFrameEdge = false;      // the box reaches the frame's border: the vehicle may be cut
                                 // off there, so its centre and size are biased
  float insideShare = 1.0F;      // share of the box's area inside the frame, [0, 1]
  // The second stage's verifier: probability that the box shows a vehicle at all (NaN: the
  // crop network has no verifier output or did not run). score stays the first stage's.
  float vehicleProbability = std::numeric_limits<float>::quiet_NaN();
};

// Most likely type and the runner-up (the pipeline keeps the top two).
struct TopTwoTypes {
  shape::VehicleType first = shape::VehicleType::Sedan;
  float firstProbability = 0.0F;
  shape::VehicleType second = shape::VehicleType::Sedan;
  float secondProbability = 0.0F;
};
TopTwoTypes topTwoTypes(const Detection& detection);

}  // namespace vp::detection
