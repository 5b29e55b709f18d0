// map_export/map_export: what the app wrote about a run -> one GeoJSON map for people
// (vp_map_export, docs/site_map.md "Map export"): the tracks of trajectory.csv as lines, the
// site's features, each gate with its counts, each zone with its occupancy and queue, each lane
// with its speeds, the turning movements as lines from gate to gate, and the traffic events as
// points.
//
// Contract: exportMap() reads every input it is given (each optional, at least one), checks
// them against each other (a count, movement, zone, lane or event naming a feature the site
// does not have is refused; traffic statistics need the site, whose geometry they are drawn
// on), and returns one GeoJSON FeatureCollection (RFC 7946: WGS84 [longitude, latitude], no
// `crs` member, valid UTF-8, no NaN) as text. Longitude and latitude are rounded to 1e-7 degree
// (about 1 cm), other numbers to 1e-3 of their unit. On any problem it returns false and the
// message names the file, the line and the column where the readers know them
// ("trajectory.csv:12:40: latitude_deg: ..."; "traffic_counts.csv:5:27: gate_id: ...").
// Positions: a trajectory row or an event with WGS84 fields is placed there; one with ENU only
// needs the world frame's origin (options.origin, from --origin or --rig). The site is read by
// the product's loader (site::loadSite) in a frame at its own first position and converted back.
#pragma once

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "geodesy/geodesy.hpp"

namespace vp::map_export {

struct MapExportOptions {
  std::string trajectoryPath;  // the app's trajectory.csv; empty: no tracks
  std::string sitePath;        // site.geojson; empty: no site
  std::string countsPath;      // traffic_counts.csv (needs the site)
  std::string movementsPath;   // traffic_movements.csv (needs the site)
  std::string zonesPath;       // traffic_zones.csv (needs the site)
  std::string lanesPath;       // traffic_lanes.csv (needs the site)
  std::string eventsPath;      // traffic_events.csv
  // The world ENU frame's origin of the run (the rig's origin); needed only by rows without
  // WGS84 fields.
  std::optional<geodesy::GeodeticPoint> origin;
  int minTrackPoints = 2;   // tracks with fewer trajectory rows are left out; >= 1
  double simplify_m = 0.0;  // a track's vertex closer than this along the line to the last kept
                            // one is dropped (the last vertex is always kept); >= 0, 0: none
};

struct MapExportSummary {
  std::size_t tracks = 0;          // written
  std::size_t tracksTooShort = 0;  // fewer rows than minTrackPoints: left out
  std::size_t trackRows = 0;       // trajectory rows of the written tracks
  std::size_t trackVertices = 0;   // their vertices after simplification
  std::size_t siteFeatures = 0;
  std::size_t gatesWithCounts = 0;  // gates given count properties (traffic_counts.csv read)
  std::size_t zonesWithStatistics = 0;
  std::size_t lanesWithStatistics = 0;
  std::size_t movements = 0;  // gate-to-gate pairs drawn
  std::size_t events = 0;
};

// Checks the options' ranges; false + a message naming the option.
bool checkOptions(const MapExportOptions& options, std::string* why);

bool exportMap(const MapExportOptions& options, std::string* geojson, MapExportSummary* summary,
               std::string* why);

// The vertices kept by --simplify-m: the first, then each vertex whose distance along the line
// from the last kept vertex reaches minSpacing_m, and always the last (which replaces the last
// kept one when that is closer than minSpacing_m and is not the first). minSpacing_m 0 keeps
// every vertex.
std::vector<Eigen::Vector2d> simplifyLine(std::span<const Eigen::Vector2d> line,
                                          double minSpacing_m);

// The WGS84 position of a site vertex that site::parseSite() converted with `frame` (east/north
// of a point at the origin's height: the height is restored before converting back).
geodesy::GeodeticPoint siteVertexToWgs84(const geodesy::LocalFrame& frame,
                                         const Eigen::Vector2d& east_north_m);

}  // namespace vp::map_export
