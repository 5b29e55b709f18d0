// tests/site: the site file's loader (every refusal names the feature and the problem), the
// conversion to the world frame and the point-in-area queries.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "geodesy/geodesy.hpp"
#include "site/site.hpp"

namespace vp::site {
namespace {

const geodesy::LocalFrame kFrame(geodesy::GeodeticPoint{48.137, 11.575, 520.0});

// "[lon, lat]" of a world ENU point.
std::string position(double east_m, double north_m) {
  const geodesy::GeodeticPoint p = kFrame.toGeodetic(Eigen::Vector3d(east_m, north_m, 0.0));
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "[%.10f, %.10f]", p.longitude_deg, p.latitude_deg);
  return buffer;
}

std::string ring(const std::vector<Eigen::Vector2d>& points, bool close = true) {
  std::string s = "[[";
  for (std::size_t i = 0; i < points.size(); ++i) {
    s += (i ? ", " : "") + position(points[i].x(), points[i].y());
  }
  if (close) {
    s += ", " + position(points[0].x(), points[0].y());
  }
  return s + "]]";
}

std::string rectangle(double x0, double y0, double x1, double y1) {
  return ring({{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}});
}

std::string feature(const std::string& kind, const std::string& id, const std::string& type,
                    const std::string& coordinates, const std::string& extra = "") {
  return R"({"type": "Feature", "properties": {"kind": ")" + kind + R"(", "id": ")" + id +
         R"(", "name": ")" + id + "\"" + extra + R"(}, "geometry": {"type": ")" + type +
         R"(", "coordinates": )" + coordinates + "}}";
}

std::string collection(const std::vector<std::string>& features, const std::string& extra = "") {
  std::string s = "{\"type\": \"FeatureCollection\"" + extra + ",\n \"features\": [\n";
  for (std::size_t i = 0; i < features.size(); ++i) {
    s += (i ? ",\n" : "") + features[i];
  }
  return s + "\n]}\n";
}

// A road 20 m wide along x, a roof on it (exclusion), a parking lot north of it, a lane, a gate.
std::vector<std::string> goodFeatures() {
  return {feature("drivable", "road-1", "Polygon", rectangle(-100, -10, 100, 10)),
          feature("parking", "lot-1", "Polygon", rectangle(-20, 30, 20, 60)),
          feature("exclusion", "roof-1", "Polygon", rectangle(40, -5, 50, 5)),
          feature("lane", "lane-1", "LineString",
                  "[" + position(-100, -5) + ", " + position(100, -5) + "]"),
          feature("gate", "gate-1", "LineString",
                  "[" + position(0, -10) + ", " + position(0, 10) + "]")};
}

std::string refusal(const std::string& text) {
  Site site;
  std::string why;
  EXPECT_FALSE(parseSite(text, "site.geojson", kFrame, &site, &why));
  EXPECT_TRUE(site.empty()) << "a refused file leaves the site unchanged";
  return why;
}

TEST(SiteLoader, ReadsEveryKindIntoTheWorldFrame) {
  Site site;
  std::string why;
  ASSERT_TRUE(parseSite(collection(goodFeatures()), "site.geojson", kFrame, &site, &why)) << why;
  ASSERT_EQ(site.features().size(), 5u);
  EXPECT_EQ(site.count(FeatureKind::Drivable), 1u);
  EXPECT_EQ(site.count(FeatureKind::Lane), 1u);
  const Feature& road = site.features()[0];
  EXPECT_EQ(road.id, "road-1");
  ASSERT_EQ(road.count, 4u) << "the closing vertex is not repeated";
  EXPECT_NEAR(site.vertices(road)[0].x(), -100.0, 1e-3);
  EXPECT_NEAR(site.vertices(road)[0].y(), -10.0, 1e-3);
  EXPECT_NEAR(road.max_m.x(), 100.0, 1e-3);
  const Feature& lane = site.features()[3];
  ASSERT_EQ(lane.count, 2u);
  EXPECT_LT(site.vertices(lane)[0].x(), site.vertices(lane)[1].x())
      << "a lane keeps its vertex order (the driving direction)";
}

TEST(SiteLoader, AcceptsTheWgs84CrsMember) {
  const std::string crs =
      R"(, "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:OGC:1.3:CRS84"}})";
  std::string why;
  EXPECT_TRUE(parseSite(collection(goodFeatures(), crs), "s", kFrame, nullptr, &why)) << why;
}

TEST(SiteLoader, RefusesWhatIsNotGeoJson) {
  EXPECT_NE(refusal(R"({"type": "Topology", "objects": {}})").find("not GeoJSON"),
            std::string::npos);
  EXPECT_NE(refusal("{\"type\": \"FeatureCollection\", \"features\": [").find("site.geojson"),
            std::string::npos);
  const std::string why = refusal(R"({"type": "FeatureCollection", "features": 3})");
  EXPECT_NE(why.find("\"features\" must be an array"), std::string::npos) << why;
}

TEST(SiteLoader, RefusesAnOpenRingNamingTheFeature) {
  std::vector<std::string> features = goodFeatures();
  features.push_back(
      feature("exclusion", "yard-7", "Polygon", ring({{60, 0}, {70, 0}, {70, 8}, {60, 8}}, false)));
  const std::string why = refusal(collection(features));
  EXPECT_NE(why.find("site.geojson: feature 5 (id \"yard-7\", line"), std::string::npos) << why;
  EXPECT_NE(why.find("ring is not closed"), std::string::npos) << why;
}

TEST(SiteLoader, RefusesAWrongCrs) {
  const std::string crs =
      R"(, "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32632"}})";
  const std::string why = refusal(collection(goodFeatures(), crs));
  EXPECT_NE(why.find("crs (line"), std::string::npos) << why;
  EXPECT_NE(why.find("wrong CRS \"urn:ogc:def:crs:EPSG::32632\""), std::string::npos) << why;
}

TEST(SiteLoader, RefusesProjectedCoordinatesNamingThePosition) {
  std::vector<std::string> features = goodFeatures();
  features[1] = feature("parking", "lot-1", "Polygon",
                        "[[[691000, 5334000], [691040, 5334000], [691040, 5334030], "
                        "[691000, 5334000]]]");
  const std::string why = refusal(collection(features));
  EXPECT_NE(why.find("feature 1 (id \"lot-1\", line"), std::string::npos) << why;
  EXPECT_NE(why.find("position 0: not a WGS84 longitude/latitude"), std::string::npos) << why;
}

TEST(SiteLoader, RefusesAnUnknownPropertyOrKind) {
  std::vector<std::string> features = goodFeatures();
  features[2] =
      feature("exclusion", "roof-1", "Polygon", rectangle(40, -5, 50, 5), R"(, "height_m": 12)");
  std::string why = refusal(collection(features));
  EXPECT_NE(why.find("feature 2 (id \"roof-1\", line"), std::string::npos) << why;
  EXPECT_NE(why.find("unknown property \"height_m\""), std::string::npos) << why;

  features = goodFeatures();
  features[2] = feature("roof", "roof-1", "Polygon", rectangle(40, -5, 50, 5));
  why = refusal(collection(features));
  EXPECT_NE(why.find("feature 2 (id \"roof-1\", line"), std::string::npos) << why;
  EXPECT_NE(why.find("unknown kind \"roof\""), std::string::npos) << why;
}

TEST(SiteLoader, ReadsLaneWidthsAndZoneRolesWithTheirDefaults) {
  std::vector<std::string> features = goodFeatures();
  features[3] =
      feature("lane", "lane-1", "LineString",
              "[" + position(-100, -5) + ", " + position(100, -5) + "]", R"(, "width_m": 3.2)");
  features.push_back(feature("lane", "lane-2", "LineString",
                             "[" + position(100, 5) + ", " + position(-100, 5) + "]"));
  features.push_back(feature("zone", "queue-1", "Polygon", rectangle(-40, -10, 0, 0),
                             R"(, "role": "queue", "lane": "lane-1")"));
  features.push_back(feature("zone", "box-1", "Polygon", rectangle(0, -10, 10, 10),
                             R"(, "role": "box_junction")"));
  features.push_back(feature("zone", "count-1", "Polygon", rectangle(10, -10, 20, 10)));
  Site site;
  std::string why;
  ASSERT_TRUE(parseSite(collection(features), "site.geojson", kFrame, &site, &why)) << why;
  const auto f = site.features();
  ASSERT_EQ(f.size(), 9u);
  EXPECT_DOUBLE_EQ(f[3].width_m, 3.2);
  EXPECT_DOUBLE_EQ(f[5].width_m, kDefaultLaneWidth_m);
  EXPECT_EQ(f[6].role, ZoneRole::Queue);
  EXPECT_EQ(f[6].lane, "lane-1");
  EXPECT_EQ(f[7].role, ZoneRole::BoxJunction);
  EXPECT_TRUE(f[7].lane.empty());
  EXPECT_EQ(f[8].role, ZoneRole::Count);
  EXPECT_STREQ(toString(ZoneRole::BoxJunction), "box_junction");
}

TEST(SiteLoader, RefusesBadLaneWidthsRolesAndLaneReferences) {
  const auto withFeature = [](const std::string& extraFeature) {
    std::vector<std::string> features = goodFeatures();
    features.push_back(extraFeature);
    return collection(features);
  };
  const std::string lane = "[" + position(-100, 5) + ", " + position(100, 5) + "]";
  std::string why =
      refusal(withFeature(feature("lane", "lane-9", "LineString", lane, R"(, "width_m": -1)")));
  EXPECT_NE(why.find("feature 5 (id \"lane-9\", line"), std::string::npos) << why;
  EXPECT_NE(why.find("\"width_m\" must be in (0, 50] m, got -1"), std::string::npos) << why;
  why =
      refusal(withFeature(feature("lane", "lane-9", "LineString", lane, R"(, "width_m": "wide")")));
  EXPECT_NE(why.find("\"width_m\" must be a number"), std::string::npos) << why;
  why = refusal(
      withFeature(feature("zone", "z-9", "Polygon", rectangle(-5, -5, 5, 5), R"(, "width_m": 3)")));
  EXPECT_NE(why.find("(id \"z-9\""), std::string::npos) << why;
  EXPECT_NE(why.find("\"width_m\" is for lanes only"), std::string::npos) << why;
  why = refusal(withFeature(
      feature("zone", "z-9", "Polygon", rectangle(-5, -5, 5, 5), R"(, "role": "parking")")));
  EXPECT_NE(why.find("unknown role \"parking\" (expected count, queue or box_junction)"),
            std::string::npos)
      << why;
  why = refusal(withFeature(feature("lane", "lane-9", "LineString", lane, R"(, "role": "queue")")));
  EXPECT_NE(why.find("\"role\" is for zones only"), std::string::npos) << why;
  why = refusal(withFeature(feature("zone", "z-9", "Polygon", rectangle(-5, -5, 5, 5),
                                    R"(, "role": "queue", "lane": "lane-7")")));
  EXPECT_NE(why.find("feature 5 (id \"z-9\", line"), std::string::npos) << why;
  EXPECT_NE(why.find("lane \"lane-7\" does not exist"), std::string::npos) << why;
  why = refusal(withFeature(feature("zone", "z-9", "Polygon", rectangle(-5, -5, 5, 5),
                                    R"(, "role": "queue", "lane": "gate-1")")));
  EXPECT_NE(why.find("lane \"gate-1\" is a gate, not a lane"), std::string::npos) << why;
  why = refusal(withFeature(
      feature("zone", "z-9", "Polygon", rectangle(-5, -5, 5, 5), R"(, "lane": "lane-1")")));
  EXPECT_NE(why.find("\"lane\" is for queue zones only"), std::string::npos) << why;
}

TEST(SiteLoader, RefusesAWrongGeometryADuplicateIdAndACrossedRing) {
  std::vector<std::string> features = goodFeatures();
  features[4] = feature("gate", "gate-1", "Polygon", rectangle(0, 0, 1, 1));
  std::string why = refusal(collection(features));
  EXPECT_NE(why.find("feature 4 (id \"gate-1\""), std::string::npos) << why;
  EXPECT_NE(why.find("a gate must have a LineString geometry"), std::string::npos) << why;

  features = goodFeatures();
  features[1] = feature("parking", "road-1", "Polygon", rectangle(-20, 30, 20, 60));
  why = refusal(collection(features));
  EXPECT_NE(why.find("feature 1 (id \"road-1\""), std::string::npos) << why;
  EXPECT_NE(why.find("duplicate id \"road-1\""), std::string::npos) << why;

  features = goodFeatures();  // a bow tie: edges 0 and 2 cross
  features[2] =
      feature("exclusion", "roof-1", "Polygon", ring({{40, -5}, {50, 5}, {50, -5}, {40, 5}}));
  why = refusal(collection(features));
  EXPECT_NE(why.find("feature 2 (id \"roof-1\""), std::string::npos) << why;
  EXPECT_NE(why.find("ring intersects itself (edges 0 and 2)"), std::string::npos) << why;
}

TEST(SiteLoader, RefusesASiteWithoutDrivableArea) {
  std::vector<std::string> features = goodFeatures();
  features.erase(features.begin(), features.begin() + 2);  // no road, no lot
  const std::string why = refusal(collection(features));
  EXPECT_NE(why.find("site.geojson: no drivable area"), std::string::npos) << why;
}

TEST(SiteLoader, LoadSiteNamesAMissingFile) {
  std::string why;
  EXPECT_FALSE(loadSite("/nonexistent/site.geojson", kFrame, nullptr, &why));
  EXPECT_NE(why.find("/nonexistent/site.geojson: cannot open"), std::string::npos) << why;
}

TEST(SiteQueries, PointInPolygonAndPlacement) {
  Site site;
  std::string why;
  std::vector<std::string> features = goodFeatures();
  // A concave (L-shaped) drivable area east of the road: its notch is off the road.
  features.push_back(
      feature("drivable", "l-1", "Polygon",
              ring({{200, 0}, {240, 0}, {240, 10}, {210, 10}, {210, 40}, {200, 40}})));
  ASSERT_TRUE(parseSite(collection(features), "site.geojson", kFrame, &site, &why)) << why;
  const Feature& l = site.features()[5];
  EXPECT_TRUE(site.contains(l, {205.0, 30.0}));
  EXPECT_TRUE(site.contains(l, {235.0, 5.0}));
  EXPECT_FALSE(site.contains(l, {230.0, 30.0})) << "the notch of a concave ring is outside";
  EXPECT_FALSE(site.contains(site.features()[3], {0.0, -5.0})) << "a lane has no inside";

  EXPECT_EQ(site.classify({0.0, 0.0}), Placement::OnRoad);
  EXPECT_EQ(site.classify({0.0, 45.0}), Placement::OnRoad) << "parking counts as drivable";
  EXPECT_EQ(site.classify({45.0, 0.0}), Placement::Excluded) << "the roof over the road";
  EXPECT_EQ(site.classify({0.0, 20.0}), Placement::OffRoad);
  EXPECT_EQ(site.classify({230.0, 30.0}), Placement::OffRoad);
}

}  // namespace
}  // namespace vp::site

namespace vp::site {
namespace {

// placeOnLane(): the nearest point of a lane's centre line, its arc length and direction, and
// whether the point lies alongside the lane or beyond one of its ends.
TEST(SitePlaceOnLane, NearestPointAlongAndBetweenTheEnds) {
  Site site("lanes.geojson");
  Feature lane;
  lane.kind = FeatureKind::Lane;
  lane.id = "l";
  // East 10 m, a repeated vertex, then north 5 m.
  const std::vector<Eigen::Vector2d> line = {{0.0, 0.0}, {10.0, 0.0}, {10.0, 0.0}, {10.0, 5.0}};
  site.append(lane, line);
  Feature area;
  area.kind = FeatureKind::Drivable;
  area.id = "a";
  const std::vector<Eigen::Vector2d> ring = {{0.0, 0.0}, {1.0, 0.0}, {1.0, 1.0}};
  site.append(area, ring);
  const Feature& l = site.features()[0];

  LanePlace p = site.placeOnLane(l, {4.0, 1.0});
  EXPECT_NEAR(p.distance_m, 1.0, 1e-12);
  EXPECT_NEAR(p.along_m, 4.0, 1e-12);
  EXPECT_NEAR(p.direction_rad, 0.0, 1e-12);
  EXPECT_TRUE(p.betweenEnds);

  p = site.placeOnLane(l, {11.0, 3.0});  // beside the second segment
  EXPECT_NEAR(p.distance_m, 1.0, 1e-12);
  EXPECT_NEAR(p.along_m, 13.0, 1e-12);
  EXPECT_NEAR(p.direction_rad, 0.5 * 3.141592653589793, 1e-12);
  EXPECT_TRUE(p.betweenEnds);

  p = site.placeOnLane(l, {-1.0, 0.5});  // before the start
  EXPECT_NEAR(p.distance_m, std::hypot(1.0, 0.5), 1e-12);
  EXPECT_NEAR(p.along_m, 0.0, 1e-12);
  EXPECT_FALSE(p.betweenEnds);

  p = site.placeOnLane(l, {10.5, 6.0});  // beyond the end
  EXPECT_NEAR(p.along_m, 15.0, 1e-12);
  EXPECT_FALSE(p.betweenEnds);

  p = site.placeOnLane(l, {11.0, -1.0});  // outside the corner: nearest is the joint, inside
  EXPECT_NEAR(p.distance_m, std::sqrt(2.0), 1e-12);
  EXPECT_TRUE(p.betweenEnds);

  // Not a lane: infinitely far.
  EXPECT_TRUE(std::isinf(site.placeOnLane(site.features()[1], {0.5, 0.5}).distance_m));

  // Its length: the segments', the repeated vertex adding nothing; 0 for an area.
  EXPECT_NEAR(site.laneLength_m(l), 15.0, 1e-12);
  EXPECT_EQ(site.laneLength_m(site.features()[1]), 0.0);
}

}  // namespace
}  // namespace vp::site
