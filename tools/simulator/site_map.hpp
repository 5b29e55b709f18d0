// simulator/site_map: the site file (docs/site_map.md) of a simulated scene, written beside
// rig.yaml as site.geojson so that a replay of the sequence runs with its site map.
//
// Contract: siteGeoJson() describes the scene's static layout in the site file's format: each
// road as a drivable polygon (its carriageway and kerb parking, kerb to kerb, over the
// generated extent), the junction of an intersection (with its rounded corners) as one more
// drivable polygon, parking lots as parking, the extra paved rectangles (driveways) as drivable,
// buildings as exclusion (their footprint), one lane LineString per travel lane in its driving
// direction with its width (`width_m`), and at an intersection one counting gate across each
// approach at its stop line. At an intersection each travel lane ends at its stop line (id
// road-R-forward|backward-L) and goes on beyond the junction (id ...-exit); a queue zone
// (`role: queue`, ...-queue) covers the lane's width over 40 m upstream of the stop line and names
// the lane; a box_junction zone (junction-box) covers the parallelogram where the two roads'
// travel lanes cross.
// Positions are WGS84 longitude/latitude through the sequence's world frame. Pure: it reads the
// scene only (the file is checked by site::parseSite in the simulator's tests).
#pragma once

#include <string>

#include "geodesy/geodesy.hpp"
#include "scene.hpp"

namespace vp::sim {

std::string siteGeoJson(const SceneSpec& scene, const geodesy::LocalFrame& frame);

}  // namespace vp::sim
