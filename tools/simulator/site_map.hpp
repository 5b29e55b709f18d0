// simulator/site_map: the site file (docs/site_map.md) of a simulated scene, written beside
// rig.yaml as site.geojson so that a replay of the sequence runs with its site map.
//
// Contract: siteGeoJson() describes the scene's static layout in the site file's format: each
// road as a drivable polygon (its carriageway and kerb parking, kerb to kerb, over the
// generated extent), the junction of an intersection (with its rounded corners) as one more
// drivable polygon, parking lots as parking, the extra paved rectangles (driveways) as drivable,
// buildings as exclusion (their footprint), one lane LineString per travel lane in its driving
// direction, and at an intersection one counting gate across each approach at its stop line.
// Positions are WGS84 longitude/latitude through the sequence's world frame. Pure: it reads the
// scene only (the file is checked by site::parseSite in the simulator's tests).
#pragma once

#include <string>

#include "geodesy/geodesy.hpp"
#include "scene.hpp"

namespace vp::sim {

std::string siteGeoJson(const SceneSpec& scene, const geodesy::LocalFrame& frame);

}  // namespace vp::sim
