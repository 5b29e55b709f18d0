// site/site: GeoJSON -> Site. yaml-cpp parses the text (JSON is YAML 1.2 flow style) and keeps
// each node's line, which every message quotes; the checks run feature by feature, in file order,
// and the first problem refuses the file.
#include "site/site.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <string_view>
#include <utility>

namespace vp::site {
namespace {

// A lane's vertices closer than this are one position (no direction between them), m.
constexpr double kMinSegment_m = 1e-6;

constexpr std::array<FeatureKind, 6> kKinds = {FeatureKind::Drivable,  FeatureKind::Parking,
                                               FeatureKind::Exclusion, FeatureKind::Lane,
                                               FeatureKind::Gate,      FeatureKind::Zone};

// The CRS names RFC 7946 allows (the 2008 draft's member; WGS84 longitude/latitude only).
constexpr std::array<std::string_view, 3> kWgs84CrsNames = {
    "urn:ogc:def:crs:OGC:1.3:CRS84", "urn:ogc:def:crs:OGC::CRS84", "EPSG:4326"};

struct Failure {
  std::string message;
};

int lineOf(const YAML::Node& node) {
  return node.Mark().line >= 0 ? node.Mark().line + 1 : 0;
}

std::string text(const YAML::Node& node) {
  return node.IsScalar() ? node.Scalar() : std::string();
}

// Proper crossing of segments ab and cd, or a touch of non-adjacent segments (collinear overlap
// included): a ring that does either is not simple.
double cross(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}
bool onSegment(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& p) {
  return std::min(a.x(), b.x()) <= p.x() && p.x() <= std::max(a.x(), b.x()) &&
         std::min(a.y(), b.y()) <= p.y() && p.y() <= std::max(a.y(), b.y());
}
bool segmentsMeet(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                  const Eigen::Vector2d& d) {
  const double d1 = cross(c, d, a);
  const double d2 = cross(c, d, b);
  const double d3 = cross(a, b, c);
  const double d4 = cross(a, b, d);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) {
    return true;
  }
  return (d1 == 0 && onSegment(c, d, a)) || (d2 == 0 && onSegment(c, d, b)) ||
         (d3 == 0 && onSegment(a, b, c)) || (d4 == 0 && onSegment(a, b, d));
}

// The first pair of crossing edges of a closed ring (vertices without the closing repeat).
std::optional<std::pair<std::size_t, std::size_t>> selfIntersection(
    std::span<const Eigen::Vector2d> ring) {
  const std::size_t n = ring.size();
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = i + 1; j < n; ++j) {
      const bool adjacent = j == i + 1 || (i == 0 && j == n - 1);
      if (adjacent) {
        continue;
      }
      if (segmentsMeet(ring[i], ring[(i + 1) % n], ring[j], ring[(j + 1) % n])) {
        return std::make_pair(i, j);
      }
    }
  }
  return std::nullopt;
}

class Reader {
 public:
  Reader(std::string sourceName, const geodesy::LocalFrame& frame)
      : source_(std::move(sourceName)), frame_(frame) {}

  [[noreturn]] void fail(const std::string& where, const std::string& problem) const {
    throw Failure{source_ + ": " + (where.empty() ? "" : where + ": ") + problem};
  }

  void read(const YAML::Node& root, Site& site) {
    if (!root.IsMap() || text(root["type"]) != "FeatureCollection") {
      fail("", "not GeoJSON: expected an object with \"type\": \"FeatureCollection\"");
    }
    for (const auto& member : root) {
      const std::string key = member.first.Scalar();
      if (key == "crs") {
        checkCrs(member.second);
      } else if (key != "type" && key != "features" && key != "name" && key != "bbox") {
        fail("line " + std::to_string(lineOf(member.first)),
             "unknown member \"" + key + "\" of the FeatureCollection");
      }
    }
    const YAML::Node features = root["features"];
    if (!features || !features.IsSequence()) {
      fail("", "not GeoJSON: \"features\" must be an array");
    }
    std::set<std::string> ids;
    for (std::size_t i = 0; i < features.size(); ++i) {
      readFeature(features[i], i, ids, site);
    }
    checkLaneReferences(site);
    if (site.count(FeatureKind::Drivable) + site.count(FeatureKind::Parking) == 0) {
      fail("",
           "no drivable area: the site needs at least one feature of kind drivable or "
           "parking");
    }
  }

 private:
  void checkCrs(const YAML::Node& crs) const {
    const YAML::Node name = crs.IsMap() && crs["properties"] && crs["properties"].IsMap()
                                ? crs["properties"]["name"]
                                : YAML::Node();
    const std::string value = name ? text(name) : std::string();
    if (std::find(kWgs84CrsNames.begin(), kWgs84CrsNames.end(), value) == kWgs84CrsNames.end()) {
      fail("crs (line " + std::to_string(lineOf(crs)) + ")",
           "wrong CRS \"" + value +
               "\": GeoJSON (RFC 7946) is WGS84 longitude/latitude "
               "(urn:ogc:def:crs:OGC:1.3:CRS84); convert the file, or leave the member out");
    }
  }

  std::string featureName(std::size_t index, const std::string& id, const YAML::Node& node) const {
    std::string s = "feature " + std::to_string(index) + " (";
    if (!id.empty()) {
      s += "id \"" + id + "\", ";
    }
    return s + "line " + std::to_string(lineOf(node)) + ")";
  }

  void readFeature(const YAML::Node& node, std::size_t index, std::set<std::string>& ids,
                   Site& site) {
    // The id first, so that every later message names it.
    std::string id;
    const YAML::Node properties = node.IsMap() ? node["properties"] : YAML::Node();
    if (properties && properties.IsMap() && properties["id"]) {
      id = text(properties["id"]);
    }
    const std::string where = featureName(index, id, node);
    if (!node.IsMap() || text(node["type"]) != "Feature") {
      fail(where, "not a GeoJSON Feature (\"type\": \"Feature\")");
    }
    if (!properties || !properties.IsMap()) {
      fail(where, "no \"properties\" object (kind, id, name)");
    }
    Feature feature;
    feature.index = index;
    std::optional<FeatureKind> kind;
    std::vector<std::pair<std::string, YAML::Node>> extras;  // read once the kind is known
    for (const auto& p : properties) {
      const std::string key = p.first.Scalar();
      if (key == "kind") {
        kind = featureKindFromString(text(p.second));
        if (!kind) {
          fail(where, "unknown kind \"" + text(p.second) +
                          "\" (expected drivable, parking, exclusion, lane, gate or zone)");
        }
      } else if (key == "id") {
        if (id.empty()) {
          fail(where, "property \"id\" must be a non-empty string");
        }
      } else if (key == "name") {
        feature.name = text(p.second);
      } else if (key == "width_m" || key == "role" || key == "lane") {
        extras.emplace_back(key, p.second);
      } else {
        fail(where, "unknown property \"" + key +
                        "\" (expected kind, id, name; width_m on a lane; role, lane on a zone)");
      }
    }
    if (!kind) {
      fail(where, "no property \"kind\"");
    }
    for (const auto& [key, value] : extras) {
      readExtra(key, value, *kind, where, feature);
    }
    if (!feature.lane.empty() && feature.role != ZoneRole::Queue) {
      fail(where, "property \"lane\" is for queue zones only (role \"queue\")");
    }
    if (id.empty()) {
      fail(where, "no property \"id\"");
    }
    if (!ids.insert(id).second) {
      fail(where, "duplicate id \"" + id + "\"");
    }
    feature.kind = *kind;
    feature.id = id;

    const YAML::Node geometry = node["geometry"];
    const std::string expected = isArea(*kind) ? "Polygon" : "LineString";
    if (!geometry || !geometry.IsMap() || text(geometry["type"]) != expected) {
      fail(where, std::string("a ") + toString(*kind) + " must have a " + expected + " geometry");
    }
    const YAML::Node coordinates = geometry["coordinates"];
    if (!coordinates || !coordinates.IsSequence()) {
      fail(where, "geometry has no \"coordinates\" array");
    }
    std::vector<Eigen::Vector2d> points;
    if (isArea(*kind)) {
      if (coordinates.size() != 1) {
        fail(where, coordinates.size() == 0 ? "polygon has no ring"
                                            : "polygon with holes (only one outer ring is read)");
      }
      points = readPositions(coordinates[0], where);
      if (points.size() < 4) {
        fail(where, "ring has " + std::to_string(points.size()) +
                        " positions (a closed ring needs at least 4, the last equal to the first)");
      }
      if (!(lonLat_.front() == lonLat_.back())) {
        fail(where, "ring is not closed: its last position must repeat the first");
      }
      points.pop_back();
      if (const auto crossing = selfIntersection(points)) {
        fail(where, "ring intersects itself (edges " + std::to_string(crossing->first) + " and " +
                        std::to_string(crossing->second) + ")");
      }
    } else {
      points = readPositions(coordinates, where);
      if (points.size() < 2) {
        fail(where, "a line needs at least 2 positions");
      }
    }
    site.append(std::move(feature), points);
  }

  // The kind-specific properties: a lane's width, a zone's role and (queue zones) lane.
  void readExtra(const std::string& key, const YAML::Node& value, FeatureKind kind,
                 const std::string& where, Feature& feature) {
    if (key == "width_m") {
      if (kind != FeatureKind::Lane) {
        fail(where, "property \"width_m\" is for lanes only");
      }
      double width_m = 0.0;
      try {
        width_m = value.as<double>();
      } catch (const YAML::Exception&) {
        fail(where, "property \"width_m\" must be a number (metres)");
      }
      if (!std::isfinite(width_m) || width_m <= 0.0 || width_m > 50.0) {
        fail(where, "property \"width_m\" must be in (0, 50] m, got " + text(value));
      }
      feature.width_m = width_m;
    } else if (key == "role") {
      if (kind != FeatureKind::Zone) {
        fail(where, "property \"role\" is for zones only");
      }
      const std::optional<ZoneRole> role = zoneRoleFromString(text(value));
      if (!role) {
        fail(where, "unknown role \"" + text(value) + "\" (expected count, queue or box_junction)");
      }
      feature.role = *role;
    } else if (key == "lane") {
      if (kind != FeatureKind::Zone) {
        fail(where, "property \"lane\" is for zones only");
      }
      if (text(value).empty()) {
        fail(where, "property \"lane\" must be a lane's id");
      }
      feature.lane = text(value);
      laneRefs_.emplace_back(where, feature.lane);
    }
  }

 public:
  // After every feature: a queue zone's lane must name a lane of the file.
  void checkLaneReferences(const Site& site) const {
    for (const auto& [where, lane] : laneRefs_) {
      const auto features = site.features();
      const auto found = std::find_if(features.begin(), features.end(),
                                      [&](const Feature& f) { return f.id == lane; });
      if (found == features.end()) {
        fail(where, "lane \"" + lane + "\" does not exist");
      }
      if (found->kind != FeatureKind::Lane) {
        fail(where, "lane \"" + lane + "\" is a " + toString(found->kind) + ", not a lane");
      }
    }
  }

 private:
  std::vector<Eigen::Vector2d> readPositions(const YAML::Node& list, const std::string& where) {
    if (!list.IsSequence()) {
      fail(where, "coordinates must be an array of positions");
    }
    std::vector<Eigen::Vector2d> points;
    lonLat_.clear();
    for (std::size_t i = 0; i < list.size(); ++i) {
      const YAML::Node position = list[i];
      const std::string at = where + ": position " + std::to_string(i);
      if (!position.IsSequence() || position.size() < 2 || position.size() > 3) {
        fail(at, "expected [longitude, latitude] or [longitude, latitude, height]");
      }
      geodesy::GeodeticPoint p;
      try {
        p.longitude_deg = position[0].as<double>();
        p.latitude_deg = position[1].as<double>();
      } catch (const YAML::Exception&) {
        fail(at, "longitude and latitude must be numbers");
      }
      if (!std::isfinite(p.longitude_deg) || !std::isfinite(p.latitude_deg) ||
          std::abs(p.longitude_deg) > 180.0 || std::abs(p.latitude_deg) > 90.0) {
        fail(at, "not a WGS84 longitude/latitude (is the file in a projected CRS?)");
      }
      // The site is a plan: the height of the world origin, so that east/north are exact there.
      p.height_m = frame_.origin().height_m;
      lonLat_.emplace_back(p.longitude_deg, p.latitude_deg);
      points.push_back(frame_.toEnu(p).head<2>());
    }
    return points;
  }

  std::string source_;
  const geodesy::LocalFrame& frame_;
  std::vector<Eigen::Vector2d> lonLat_;  // the last positions read, as written (closure check)
  std::vector<std::pair<std::string, std::string>> laneRefs_;  // (where, lane id) of zones
};

}  // namespace

const char* toString(FeatureKind kind) {
  switch (kind) {
    case FeatureKind::Drivable:
      return "drivable";
    case FeatureKind::Parking:
      return "parking";
    case FeatureKind::Exclusion:
      return "exclusion";
    case FeatureKind::Lane:
      return "lane";
    case FeatureKind::Gate:
      return "gate";
    case FeatureKind::Zone:
      return "zone";
  }
  return "unknown";
}

std::optional<FeatureKind> featureKindFromString(const std::string& text) {
  for (const FeatureKind kind : kKinds) {
    if (text == toString(kind)) {
      return kind;
    }
  }
  return std::nullopt;
}

const char* toString(ZoneRole role) {
  switch (role) {
    case ZoneRole::Count:
      return "count";
    case ZoneRole::Queue:
      return "queue";
    case ZoneRole::BoxJunction:
      return "box_junction";
  }
  return "unknown";
}

std::optional<ZoneRole> zoneRoleFromString(const std::string& text) {
  for (const ZoneRole role : {ZoneRole::Count, ZoneRole::Queue, ZoneRole::BoxJunction}) {
    if (text == toString(role)) {
      return role;
    }
  }
  return std::nullopt;
}

bool isArea(FeatureKind kind) {
  return kind != FeatureKind::Lane && kind != FeatureKind::Gate;
}

const char* toString(Placement placement) {
  switch (placement) {
    case Placement::OnRoad:
      return "on road";
    case Placement::OffRoad:
      return "off road";
    case Placement::Excluded:
      return "in an exclusion area";
  }
  return "unknown";
}

const char* toString(OffRoadPolicy policy) {
  switch (policy) {
    case OffRoadPolicy::Drop:
      return "drop";
    case OffRoadPolicy::Flag:
      return "flag";
    case OffRoadPolicy::Keep:
      return "keep";
  }
  return "unknown";
}

std::optional<OffRoadPolicy> offRoadPolicyFromString(const std::string& text) {
  for (const OffRoadPolicy policy :
       {OffRoadPolicy::Drop, OffRoadPolicy::Flag, OffRoadPolicy::Keep}) {
    if (text == toString(policy)) {
      return policy;
    }
  }
  return std::nullopt;
}

void Site::append(Feature feature, std::span<const Eigen::Vector2d> vertices_m) {
  feature.first = static_cast<std::uint32_t>(vertices_.size());
  feature.count = static_cast<std::uint32_t>(vertices_m.size());
  feature.min_m = feature.max_m = vertices_m.empty() ? Eigen::Vector2d::Zero() : vertices_m[0];
  for (const Eigen::Vector2d& v : vertices_m) {
    feature.min_m = feature.min_m.cwiseMin(v);
    feature.max_m = feature.max_m.cwiseMax(v);
  }
  vertices_.insert(vertices_.end(), vertices_m.begin(), vertices_m.end());
  features_.push_back(std::move(feature));
}

std::size_t Site::count(FeatureKind kind) const {
  return static_cast<std::size_t>(std::count_if(
      features_.begin(), features_.end(), [kind](const Feature& f) { return f.kind == kind; }));
}

bool Site::contains(const Feature& feature, const Eigen::Vector2d& p) const {
  if (!isArea(feature.kind) || p.x() < feature.min_m.x() || p.y() < feature.min_m.y() ||
      p.x() > feature.max_m.x() || p.y() > feature.max_m.y()) {
    return false;
  }
  // Even-odd rule: count the edges a ray towards +x crosses.
  const std::span<const Eigen::Vector2d> ring = vertices(feature);
  bool inside = false;
  for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++) {
    const Eigen::Vector2d& a = ring[i];
    const Eigen::Vector2d& b = ring[j];
    if ((a.y() > p.y()) != (b.y() > p.y())) {
      const double xCross = a.x() + (p.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
      if (p.x() < xCross) {
        inside = !inside;
      }
    }
  }
  return inside;
}

LanePlace Site::placeOnLane(const Feature& lane, const Eigen::Vector2d& point_m) const {
  LanePlace best;
  best.distance_m = std::numeric_limits<double>::infinity();
  if (lane.kind != FeatureKind::Lane) {
    return best;
  }
  const std::span<const Eigen::Vector2d> line = vertices(lane);
  double along_m = 0.0;
  for (std::size_t i = 0; i + 1 < line.size(); ++i) {
    const Eigen::Vector2d d = line[i + 1] - line[i];
    const double length_m = d.norm();
    if (!(length_m > kMinSegment_m)) {
      continue;  // a repeated position
    }
    const Eigen::Vector2d dir = d / length_m;
    const Eigen::Vector2d rel = point_m - line[i];
    const double t = std::clamp(rel.dot(dir), 0.0, length_m);
    const double distance_m = (rel - t * dir).norm();
    if (distance_m < best.distance_m) {
      best.distance_m = distance_m;
      best.along_m = along_m + t;
      best.direction_rad = std::atan2(dir.y(), dir.x());
    }
    along_m += length_m;
  }
  // Nearest to the first or the last vertex: the point lies before or beyond the lane.
  best.betweenEnds = best.along_m > 0.0 && best.along_m < along_m;
  return best;
}

double Site::laneLength_m(const Feature& lane) const {
  if (lane.kind != FeatureKind::Lane) {
    return 0.0;
  }
  const std::span<const Eigen::Vector2d> line = vertices(lane);
  double length_m = 0.0;
  for (std::size_t i = 0; i + 1 < line.size(); ++i) {
    const double segment_m = (line[i + 1] - line[i]).norm();
    length_m += segment_m > kMinSegment_m ? segment_m : 0.0;
  }
  return length_m;
}

Placement Site::classify(const Eigen::Vector2d& point_m) const {
  bool onArea = false;
  for (const Feature& feature : features_) {
    if (feature.kind == FeatureKind::Exclusion && contains(feature, point_m)) {
      return Placement::Excluded;
    }
    if (!onArea &&
        (feature.kind == FeatureKind::Drivable || feature.kind == FeatureKind::Parking)) {
      onArea = contains(feature, point_m);
    }
  }
  return onArea ? Placement::OnRoad : Placement::OffRoad;
}

bool parseSite(const std::string& text, const std::string& sourceName,
               const geodesy::LocalFrame& frame, Site* site, std::string* why) {
  Site loaded(sourceName);
  try {
    YAML::Node root;
    try {
      root = YAML::Load(text);
    } catch (const YAML::Exception& e) {
      throw Failure{sourceName + ": line " + std::to_string(e.mark.line + 1) +
                    ": not JSON: " + e.msg};
    }
    Reader(sourceName, frame).read(root, loaded);
  } catch (const Failure& failure) {
    if (why) {
      *why = failure.message;
    }
    return false;
  } catch (const YAML::Exception& e) {
    if (why) {
      *why = sourceName + ": line " + std::to_string(e.mark.line + 1) + ": " + e.msg;
    }
    return false;
  }
  if (site) {
    *site = std::move(loaded);
  }
  return true;
}

bool loadSite(const std::string& path, const geodesy::LocalFrame& frame, Site* site,
              std::string* why) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    if (why) {
      *why = path + ": cannot open the site file";
    }
    return false;
  }
  std::ostringstream content;
  content << in.rdbuf();
  return parseSite(content.str(), path, frame, site, why);
}

}  // namespace vp::site
