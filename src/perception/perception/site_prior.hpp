// perception/site_prior: the scene prior of a known site on lifted detections — a vehicle stands
// on a road or a parking lot, never on a roof or in a yard.
//
// Contract: init() borrows the site (site/site.hpp; null or empty: no prior) and takes the
// policy of `site.off_road`. screen() looks at each lifted observation's footprint centre (its
// world position, ENU east/north): inside an exclusion area, or outside every drivable and parking
// area, it is off the site. Drop leaves such observations out of the output; Flag keeps them with
// offSite set; Keep (or no site) copies every observation unchanged. Observations that are not
// lifted (no pose, off the DTM) have no world position and are always kept, unflagged. Order is
// kept. screen() is const, never allocates and never throws. The tracker never sees the site:
// it only receives what screen() kept.
#pragma once

#include <cstddef>
#include <span>

#include "perception/detection_lifter.hpp"
#include "site/site.hpp"

namespace vp::perception {

struct SiteScreening {
  std::size_t written = 0;  // observations in the output
  std::size_t offSite = 0;  // lifted observations off the site (dropped or flagged)
};

class SitePrior {
 public:
  void init(const site::Site* site, site::OffRoadPolicy policy) {
    site_ = site != nullptr && !site->empty() ? site : nullptr;
    policy_ = policy;
  }
  // True when screen() checks observations (a site and a policy other than Keep).
  bool active() const { return site_ != nullptr && policy_ != site::OffRoadPolicy::Keep; }
  site::OffRoadPolicy policy() const { return policy_; }

  // Copies the observations to keep into out (at most out.size()).
  SiteScreening screen(std::span<const VehicleObservation> observations,
                       std::span<VehicleObservation> out) const;

 private:
  const site::Site* site_ = nullptr;
  site::OffRoadPolicy policy_ = site::OffRoadPolicy::Drop;
};

}  // namespace vp::perception
