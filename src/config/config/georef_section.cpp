// config/georef_section: `georef:` (ground control points of a fixed view, used when there is no
// telemetry) into georef::GeorefOptions (georef/georeference.hpp).
#include <string>

#include "config/sections.hpp"
#include "rig_config/section_reader.hpp"

namespace vp::config::detail {
namespace {

const Range kMaxResidualRange_m = Range{0.0, 100.0, true};  // (0, 100]

}  // namespace

georef::GeorefOptions readGeoref(MapReader section, const std::string& baseDir) {
  const georef::GeorefOptions d;
  georef::GeorefOptions g;
  g.gcpFile = readOptionalPath(section, "gcp_file", baseDir, d.gcpFile);
  g.maxResidual_m = section.number("max_residual_m", kMaxResidualRange_m, d.maxResidual_m);
  section.warnUnknownKeys();
  return g;
}

}  // namespace vp::config::detail
