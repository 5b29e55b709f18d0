// Tracker options these tests were written for: the motion model's measurement noise and the
// tracker's timing as tuned on synthetic seed 1 (docs/tracking.md), before the shipped
// configuration's values (measurement noise 0.3 m / 8 deg, steering decay 2 s, coast 0.3 s,
// high score 0.45) became the structs' defaults. The tests check the algorithms' behaviour at
// these settings, not the product's tuning.
#pragma once

#include "tracking/association.hpp"
#include "tracking/motion_model.hpp"
#include "tracking/track_manager.hpp"

namespace vp::tracking::test {

inline MotionNoise seedOneNoise() {
  MotionNoise noise;
  noise.measurementPosition_m = 0.10;
  noise.measurementHeading_rad = 0.06;
  noise.steeringDecay_s = 0.0;
  return noise;
}

inline AssociationParams seedOneAssociation() {
  AssociationParams params;
  params.highScore = 0.5F;
  return params;
}

inline TrackerConfig seedOneTracker() {
  TrackerConfig config;
  config.noise = seedOneNoise();
  config.association = seedOneAssociation();
  config.maxCoast_s = 0.0;
  return config;
}

}  // namespace vp::tracking::test
