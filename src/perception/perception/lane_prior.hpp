// perception/lane_prior: a known site's lanes as a prior on the front/back of the vehicles in
// them — a vehicle standing in a lane nearly always faces the lane's driving direction.
//
// Contract: init() borrows the site (null, empty or without lanes: no prior) and takes the prior
// probability that a vehicle in a lane faces the lane's way (site.lane_direction_prior, [0.5, 1];
// 0.5: the lanes say nothing, inactive) and the DetectionLifter the frame was lifted with. apply()
// looks at each lifted observation's footprint centre: alongside a lane (within half the lane's
// width of its centre line, between its ends) and facing more than 90 degrees against the lane's
// direction, the observation is turned round when its own front/back confidence c = max(p, 1 - p)
// (p: the second stage's flip probability) is below the prior — where the posterior of its shown
// direction, c (1 - prior), falls below that of the lane's, (1 - c) prior. A turned observation
// gets its image box's angle turned by pi and the flip probability 1 - p, and is lifted again with
// the frame's Lifter and camera pose, so its heading, corners, keypoints and rear axle follow the
// vehicle's new front. Everything else is left as it was: observations not lifted, outside every
// lane or facing the lane's way, and a vehicle whose crops are surer of its front than the prior
// (a wrong-way driver seen clearly; the tracker turns a track to its motion in any case). Why:
// the crop network sees a bus's or a truck's middle and ends, which often look alike from above,
// and it cannot know what the site's lanes say. apply() works in place, never allocates and never
// throws; it is const and may run on any thread that owns the observations.
#pragma once

#include <cstddef>
#include <span>
#include <string>

#include "lifting/lifting.hpp"
#include "perception/detection_lifter.hpp"
#include "site/site.hpp"

namespace vp::perception {

struct LaneScreening {
  std::size_t inLane = 0;   // lifted observations alongside a lane
  std::size_t against = 0;  // of those, facing more than 90 degrees against it
  std::size_t turned = 0;   // of those, turned round to the lane's way
};

class LanePrior {
 public:
  // Borrows site and lifter (both must outlive the prior). False + *why for a prior outside
  // [0.5, 1].
  bool init(const site::Site* site, double prior, const DetectionLifter* lifter,
            std::string* why = nullptr);
  // True when apply() may turn observations (a site with lanes, a lifter, a prior above 0.5).
  bool active() const { return active_; }

  // Turns, in place, the observations the lanes disagree with (see the contract). lifter and
  // cameraPose: those the observations were lifted with (the pose is not used for a fixed view
  // lifted through ground control points).
  LaneScreening apply(std::span<VehicleObservation> observations, const lifting::Lifter& lifter,
                      const lifting::CameraPoseWorld& cameraPose) const;

 private:
  // The driving direction (ENU, rad) of the lane the point stands alongside; false outside all.
  bool laneDirectionAt(const Eigen::Vector2d& point_m, double* direction_rad) const;

  const site::Site* site_ = nullptr;
  const DetectionLifter* lifter_ = nullptr;
  double prior_ = 0.5;
  bool active_ = false;
};

}  // namespace vp::perception
