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
  section.warnUnknownKeys();
  return s;
}

}  // namespace vp::config::detail
