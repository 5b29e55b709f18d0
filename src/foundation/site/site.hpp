// site/site: the map of the site a hovering drone serves (site.geojson, docs/site_map.md),
// loaded and checked once at start-up and queried in the loop.
//
// Contract: parseSite()/loadSite() read a GeoJSON FeatureCollection (RFC 7946: WGS84
// longitude/latitude, no other CRS) whose features carry the properties `kind`, `id` and
// `name`, and optionally `width_m` on a lane (default 3.5 m) and `role` (count, queue,
// box_junction; default count) and, on a queue zone, `lane` (the id of a lane of the file whose
// end is the stop line) on a zone; nothing else. Areas (`drivable`, `parking`, `exclusion`, `zone`)
// are Polygons with one closed, simple outer ring; `lane` (driving direction = vertex order) and
// `gate` (a counting line) are LineStrings. A file that is not such a collection, a feature with a
// wrong geometry, an open or self-intersecting ring, a CRS other than WGS84, an unknown property or
// kind, a duplicate id, a property on the wrong kind, a width out of (0, 50] m, an unknown role, a
// zone's lane that is not a lane of the file, or a site without a drivable or parking area is
// refused, the message naming the file, the feature (index and id, line) and the problem. Every
// vertex is converted once to the world ENU frame (geodesy::LocalFrame, east/north in metres).
// After loading, a Site is immutable: its queries (contains(), classify(), placeOnLane()) are
// const, never allocate and never throw, so the loop may call them per detection; it is safe to
// share read-only between threads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "geodesy/geodesy.hpp"

namespace vp::site {

enum class FeatureKind : std::uint8_t { Drivable, Parking, Exclusion, Lane, Gate, Zone };
const char* toString(FeatureKind kind);  // the file's word: "drivable", ...
std::optional<FeatureKind> featureKindFromString(const std::string& text);
// Areas are Polygons; lanes and gates are LineStrings.
bool isArea(FeatureKind kind);

// What a zone is for (its optional `role`): a plain counting zone (occupancy, dwell), the queue
// upstream of a stop line (its `lane` ends there), or a box junction (no vehicle may stop in it).
enum class ZoneRole : std::uint8_t { Count, Queue, BoxJunction };
const char* toString(ZoneRole role);  // the file's word: "count", "queue", "box_junction"
std::optional<ZoneRole> zoneRoleFromString(const std::string& text);

constexpr double kDefaultLaneWidth_m = 3.5;

struct Feature {
  FeatureKind kind = FeatureKind::Drivable;
  std::string id;
  std::string name;
  std::size_t index = 0;  // position in the file's `features` array
  // The vertices (Site::vertices()): an area's ring without the repeated closing vertex.
  std::uint32_t first = 0;
  std::uint32_t count = 0;
  Eigen::Vector2d min_m{0.0, 0.0};  // bounding box, ENU east/north
  Eigen::Vector2d max_m{0.0, 0.0};
  double width_m = kDefaultLaneWidth_m;  // a lane's width (`width_m`), > 0
  ZoneRole role = ZoneRole::Count;       // a zone's `role`
  std::string lane;                      // a queue zone's `lane`: the id of an existing lane
};

// Where a world point lies on the site.
enum class Placement : std::uint8_t {
  OnRoad,    // inside a drivable or parking area and inside no exclusion
  OffRoad,   // outside every drivable and parking area
  Excluded,  // inside an exclusion area (roof, yard)
};
const char* toString(Placement placement);

// What the perception stage does with a lifted detection whose footprint centre is not on the
// road (Placement OffRoad or Excluded): drop it before the tracker (counted), flag it (counted,
// tracked all the same), or keep it (not checked).
enum class OffRoadPolicy : std::uint8_t { Drop, Flag, Keep };
const char* toString(OffRoadPolicy policy);  // "drop", "flag", "keep"
std::optional<OffRoadPolicy> offRoadPolicyFromString(const std::string& text);

// Range of SiteOptions::maxStructureHeight_m, m.
inline constexpr double kMinStructureHeight_m = 0.5;
inline constexpr double kMaxStructureHeight_m = 50.0;

// Range of SiteOptions::laneDirectionPrior.
inline constexpr double kMinLaneDirectionPrior = 0.5;
inline constexpr double kMaxLaneDirectionPrior = 1.0;

// The `site:` section of the configuration (docs/site_map.md).
struct SiteOptions {
  std::string file;  // the site file, absolute after loading; empty: none
  OffRoadPolicy offRoad = OffRoadPolicy::Drop;  // only with a site file
  // With a surface model (terrain.dsm_path; with or without a site file): where the surface
  // stands more than this above the DTM under a lifted detection, the vehicle is on a structure
  // (a deck when a drivable or parking area marks the point, else a roof: onStructure). Above
  // a car's height and the surface model's noise, below a storey. [0.5, 50] m.
  double maxStructureHeight_m = 2.5;
  OffRoadPolicy onStructure = OffRoadPolicy::Drop;  // what is done with vehicles on a roof
  // The probability that a vehicle standing in a lane faces the lane's driving direction: the
  // prior the lanes put on a detection's front/back (perception/lane_prior.hpp). Wrong-way
  // driving is rare; 0.5 says nothing (off). [0.5, 1].
  double laneDirectionPrior = 0.99;
};

// Where a point lies relative to a lane (a LineString in its driving direction): the nearest
// point of its centre line.
struct LanePlace {
  double distance_m = 0.0;     // from the centre line (infinity: not a lane)
  double along_m = 0.0;        // arc length of the nearest point from the lane's start
  double direction_rad = 0.0;  // of the nearest segment, ENU, counter-clockwise from east
  bool betweenEnds = false;    // the nearest point is neither the lane's first nor its last
                               // vertex (the point lies alongside the lane)
};

class Site {
 public:
  Site() = default;
  explicit Site(std::string sourceName) : sourceName_(std::move(sourceName)) {}

  // Start-up only (the loader): adds a feature with its vertices (world ENU east/north, an
  // area's ring without the closing repeat); sets its first, count and bounding box.
  void append(Feature feature, std::span<const Eigen::Vector2d> vertices_m);

  std::span<const Feature> features() const { return features_; }
  std::span<const Eigen::Vector2d> vertices(const Feature& feature) const {
    return {vertices_.data() + feature.first, feature.count};
  }
  const std::string& sourceName() const { return sourceName_; }
  bool empty() const { return features_.empty(); }
  std::size_t count(FeatureKind kind) const;

  // Point in an area (even-odd rule; a point on the boundary may fall either way). False for a
  // line feature.
  bool contains(const Feature& feature, const Eigen::Vector2d& point_m) const;
  Placement classify(const Eigen::Vector2d& point_m) const;
  // The nearest point of a lane's centre line to point_m (segments of zero length skipped; on a
  // tie the first segment). distance_m is infinite for a feature that is not a lane.
  LanePlace placeOnLane(const Feature& lane, const Eigen::Vector2d& point_m) const;
  // A lane's length along its centre line (0 for a feature that is not a lane, or a lane whose
  // vertices all stand at one position).
  double laneLength_m(const Feature& lane) const;

 private:
  std::string sourceName_;
  std::vector<Feature> features_;
  std::vector<Eigen::Vector2d> vertices_;
};

// text: the file's content; sourceName names it in messages. On failure returns false, leaves
// *site unchanged and sets *why ("site.geojson: feature 2 (id \"roof-1\", line 14): ...").
bool parseSite(const std::string& text, const std::string& sourceName,
               const geodesy::LocalFrame& frame, Site* site, std::string* why);
bool loadSite(const std::string& path, const geodesy::LocalFrame& frame, Site* site,
              std::string* why);

}  // namespace vp::site
