// tests/tracking/synthetic_scene: a fast synthetic intersection for tracker tests, with the
// truth and the noisy world detections a detector + lifting would produce.
//
// Contract: makeIntersection() is deterministic per seed. Four approaches with two lanes
// each (3.5 m wide, right-hand traffic); cars enter at the area's edge, drive under the
// kinematic bicycle model (rear axle, wheelbase from the ASM shape), go straight or turn
// left/right at the centre with a constant steering angle, and leave; parked cars line the
// kerbs. Each frame lists the truth (every vehicle inside the area, `visible` false during
// an occlusion window) and the detections: centre noise, heading noise, heading flips by
// 180 degrees, misses, low-score true detections, false positives, noisy type
// probabilities and ASM gamma.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "shape/vehicle_model.hpp"
#include "tracking/world_detection.hpp"

namespace vp::tracking::test {

struct SceneParams {
  unsigned seed = 1;
  int frames = 300;
  double frameRate_hz = 10.0;
  double halfSize_m = 70.0;         // area: |x|, |y| <= halfSize
  double meanArrivalGap_s = 4.0;    // per inbound lane
  double turnShare = 0.4;           // of the cars, half left, half right
  int parkedPerKerb = 4;            // on each of the 4 approaches
  double positionNoise_m = 0.05;    // per axis, 1 sigma
  double headingNoise_rad = 0.035;  // 2 degrees
  double flipRate = 0.05;           // heading turned by 180 degrees
  double missRate = 0.05;
  double lowScoreRate = 0.10;   // true detections with score in [0.15, 0.45)
  double occlusionShare = 0.3;  // vehicles that get one occlusion window of 3-15 frames
  double falsePositivesPerFrame = 0.5;
  double typeLogitBias = 1.6;  // detector type confidence (per-frame OA-1 ~ 0.65)
  double gammaNoise = 0.3;
  double sizeNoise_m = 0.1;
};

struct TruthObject {
  int id = 0;
  shape::VehicleType type = shape::VehicleType::Sedan;
  shape::ShapeParams shape{};
  Eigen::Vector2d centre{0.0, 0.0};
  Eigen::Vector2d rearAxle{0.0, 0.0};
  double heading_rad = 0.0;
  double speed_mps = 0.0;
  double yawRate_radps = 0.0;
  double length_m = 4.5;
  double width_m = 1.8;
  bool parked = false;
  bool visible = true;
};

struct SceneFrame {
  std::int64_t timestamp_ns = 0;
  std::vector<TruthObject> truth;
  std::vector<WorldDetection> detections;
};

// asmModel: the shape model that gives each car its size and wheelbase (may be null: then
// fixed typical sizes are used).
std::vector<SceneFrame> makeIntersection(const SceneParams& params,
                                         const shape::ActiveShapeModel* asmModel);

// n vehicles in parallel lanes 5 m apart driving east at 10 m/s, exact detections with
// score 0.9: the load for the allocation test and the benchmark.
std::vector<WorldDetection> makeConvoyFrame(int n, int frame, double frameRate_hz);

}  // namespace vp::tracking::test
