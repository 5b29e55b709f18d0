// perception/lane_prior: each lifted observation's heading against the lane it stands in.
#include "perception/lane_prior.hpp"

#include <algorithm>
#include <cmath>

#include "geometry/rotated_box.hpp"

namespace vp::perception {

bool LanePrior::init(const site::Site* site, double prior, const DetectionLifter* lifter,
                     std::string* why) {
  active_ = false;
  if (!(prior >= site::kMinLaneDirectionPrior && prior <= site::kMaxLaneDirectionPrior)) {
    if (why != nullptr) {
      *why = "site.lane_direction_prior must be in [0.5, 1] (got " + std::to_string(prior) + ")";
    }
    return false;
  }
  site_ = site;
  lifter_ = lifter;
  prior_ = prior;
  active_ = site != nullptr && site->count(site::FeatureKind::Lane) > 0 && lifter != nullptr &&
            prior > site::kMinLaneDirectionPrior;
  return true;
}

bool LanePrior::laneDirectionAt(const Eigen::Vector2d& point_m, double* direction_rad) const {
  for (const site::Feature& feature : site_->features()) {
    if (feature.kind != site::FeatureKind::Lane) {
      continue;
    }
    const site::LanePlace place = site_->placeOnLane(feature, point_m);
    if (place.betweenEnds && place.distance_m <= 0.5 * feature.width_m) {
      *direction_rad = place.direction_rad;
      return true;
    }
  }
  return false;
}

LaneScreening LanePrior::apply(std::span<VehicleObservation> observations,
                               const lifting::Lifter& lifter,
                               const lifting::CameraPoseWorld& cameraPose) const {
  LaneScreening result;
  if (!active_) {
    return result;
  }
  for (VehicleObservation& observation : observations) {
    if (observation.liftStatus != LiftStatus::Ok) {
      continue;
    }
    double lane_rad = 0.0;
    if (!laneDirectionAt(observation.ground.centreEnu.head<2>(), &lane_rad)) {
      continue;
    }
    ++result.inLane;
    if (geometry::absAngleDifference(observation.ground.headingEnu_rad, lane_rad) <=
        0.5 * geometry::kPi) {
      continue;
    }
    ++result.against;
    const double p = observation.detection.flipProbability;
    const double confidence = std::max(p, 1.0 - p);
    if (!(confidence < prior_)) {
      continue;
    }
    // Lifted again from the turned box: the world values start from zero, as liftFrame()'s do.
    VehicleObservation turned;
    turned.timestamp_ns = observation.timestamp_ns;
    turned.detection = observation.detection;
    turned.detection.box.angle = geometry::wrapTwoPi(turned.detection.box.angle + geometry::kPi);
    turned.detection.flipProbability = static_cast<float>(1.0 - p);
    lifter_->liftObservation(lifter, cameraPose, turned);
    if (turned.liftStatus != LiftStatus::Ok) {
      continue;  // cannot happen for a box that lifted before; kept as it was
    }
    observation = turned;
    ++result.turned;
  }
  return result;
}

}  // namespace vp::perception
