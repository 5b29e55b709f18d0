// perception/site_prior: the footprint centre of each lifted observation against the site's areas.
#include "perception/site_prior.hpp"

namespace vp::perception {

SiteScreening SitePrior::screen(std::span<const VehicleObservation> observations,
                                std::span<VehicleObservation> out) const {
  SiteScreening result;
  for (const VehicleObservation& observation : observations) {
    bool offSite = false;
    if (active() && observation.liftStatus == LiftStatus::Ok) {
      const Eigen::Vector2d centre_m = observation.ground.centreEnu.head<2>();
      offSite = site_->classify(centre_m) != site::Placement::OnRoad;
    }
    if (offSite) {
      ++result.offSite;
      if (policy_ == site::OffRoadPolicy::Drop) {
        continue;
      }
    }
    if (result.written == out.size()) {
      continue;  // counted all the same
    }
    VehicleObservation& kept = out[result.written++];
    kept = observation;
    kept.offSite = offSite;
  }
  return result;
}

}  // namespace vp::perception
