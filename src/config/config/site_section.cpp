// config/site_section: `site:` (the site map and the scene prior on detections) into
// site::SiteOptions (site/site.hpp). The file itself is read at start-up by the app, in the world
// frame it builds.
#include <array>
#include <string>
#include <string_view>

#include "config/sections.hpp"
#include "rig_config/section_reader.hpp"

namespace vp::config::detail {
namespace {

constexpr std::string_view kOffRoadNames = "drop, flag, keep";

}  // namespace

site::SiteOptions readSite(MapReader section, const std::string& baseDir) {
  const site::SiteOptions d;
  site::SiteOptions s;
  s.file = readOptionalPath(section, "file", baseDir, d.file);
  s.offRoad = section.choice<site::OffRoadPolicy>("off_road", site::offRoadPolicyFromString,
                                                  kOffRoadNames, d.offRoad);
  s.maxStructureHeight_m =
      section.number("max_structure_height_m",
                     Range::closed(site::kMinStructureHeight_m, site::kMaxStructureHeight_m),
                     d.maxStructureHeight_m);
  s.onStructure = section.choice<site::OffRoadPolicy>("on_structure", site::offRoadPolicyFromString,
                                                      kOffRoadNames, d.onStructure);
  s.laneDirectionPrior =
      section.number("lane_direction_prior",
                     Range::closed(site::kMinLaneDirectionPrior, site::kMaxLaneDirectionPrior),
                     d.laneDirectionPrior);
  section.warnUnknownKeys();
  return s;
}

}  // namespace vp::config::detail
