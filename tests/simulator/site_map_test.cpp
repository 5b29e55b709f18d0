// tests/simulator/site_map_test: the site file vp_simulate writes for a scene loads, and at an
// intersection carries what the traffic analysis needs: each travel lane ending at its approach's
// gate (the stop line) with a queue zone before it that names it, the lanes' widths, and a box
// junction over the junction's centre; traffic islands are exclusion areas.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "geodesy/geodesy.hpp"
#include "scene.hpp"
#include "sim_random.hpp"
#include "site/site.hpp"
#include "site_map.hpp"

namespace vp::sim {
namespace {

const geodesy::LocalFrame kFrame(geodesy::GeodeticPoint{43.07, -89.40, 260.0});

double distanceToSegment(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                         const Eigen::Vector2d& b) {
  const Eigen::Vector2d d = b - a;
  const double t = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
  return (p - (a + t * d)).norm();
}

site::Site load(const SceneSpec& scene) {
  site::Site site;
  std::string why;
  EXPECT_TRUE(site::parseSite(siteGeoJson(scene, kFrame), "site.geojson", kFrame, &site, &why))
      << why;
  return site;
}

TEST(SimulatorSiteMap, IntersectionQueuesEndAtTheGatesAndTheBoxCoversTheJunction) {
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    Rng rng(seed);
    const SceneSpec scene = generateScene(SceneKind::Intersection, rng);
    const site::Site site = load(scene);
    const auto features = site.features();
    const auto byId = [&](const std::string& id) {
      return std::find_if(features.begin(), features.end(),
                          [&](const site::Feature& f) { return f.id == id; });
    };
    int travelLanes = 0;
    for (const Road& road : scene.roads) {
      travelLanes += road.lanesForward + road.lanesBackward;
    }
    int queues = 0;
    int boxes = 0;
    for (const site::Feature& f : features) {
      if (f.kind == site::FeatureKind::Lane) {
        const bool matches =
            std::any_of(scene.roads.begin(), scene.roads.end(),
                        [&](const Road& r) { return std::abs(f.width_m - r.laneWidth_m) < 1e-3; });
        EXPECT_TRUE(matches) << "seed " << seed << " lane " << f.id << " width " << f.width_m;
      }
      if (f.kind != site::FeatureKind::Zone) {
        continue;
      }
      if (f.role == site::ZoneRole::BoxJunction) {
        ++boxes;
        EXPECT_TRUE(site.contains(f, scene.junction)) << "seed " << seed;
        continue;
      }
      ASSERT_EQ(f.role, site::ZoneRole::Queue) << f.id;
      ++queues;
      const auto lane = byId(f.lane);
      ASSERT_NE(lane, features.end()) << f.lane;
      ASSERT_EQ(lane->kind, site::FeatureKind::Lane);
      const auto v = site.vertices(*lane);
      const Eigen::Vector2d end = v.back();
      const Eigen::Vector2d dir = (v.back() - v.front()).normalized();
      // The lane ends on a gate (its stop line).
      double nearest_m = 1e9;
      for (const site::Feature& g : features) {
        if (g.kind == site::FeatureKind::Gate) {
          const auto gv = site.vertices(g);
          nearest_m = std::min(nearest_m, distanceToSegment(end, gv.front(), gv.back()));
        }
      }
      EXPECT_LT(nearest_m, 0.05) << "seed " << seed << " lane " << lane->id;
      // The zone lies on the lane just upstream of the stop line, not beyond it.
      EXPECT_TRUE(site.contains(f, end - 3.0 * dir)) << "seed " << seed << " " << f.id;
      EXPECT_FALSE(site.contains(f, end + 3.0 * dir)) << "seed " << seed << " " << f.id;
    }
    EXPECT_EQ(queues, travelLanes) << "seed " << seed;
    EXPECT_EQ(boxes, 1) << "seed " << seed;
    EXPECT_EQ(site.count(site::FeatureKind::Gate), 4U) << "seed " << seed;
  }
}

TEST(SimulatorSiteMap, AStraightRoadHasWholeLanesAndNoQueueZones) {
  Rng rng(3);
  const SceneSpec scene = generateScene(SceneKind::Straight, rng);
  const site::Site site = load(scene);
  EXPECT_EQ(site.count(site::FeatureKind::Zone), 0U);
  EXPECT_EQ(site.count(site::FeatureKind::Lane),
            static_cast<std::size_t>(scene.roads[0].lanesForward + scene.roads[0].lanesBackward));
}

TEST(SimulatorSiteMap, TrafficIslandsAreExclusionAreasInsideTheRoad) {
  int islands = 0;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    for (const SceneKind kind : {SceneKind::Intersection, SceneKind::Straight}) {
      Rng rng(seed);
      const SceneSpec scene = generateScene(kind, rng, true);
      const site::Site site = load(scene);
      for (std::size_t i = 0; i < scene.islands.size(); ++i) {
        const Island& island = scene.islands[i];
        const std::string id = "island-" + std::to_string(i + 1);
        const auto features = site.features();
        const auto f = std::find_if(features.begin(), features.end(),
                                    [&](const site::Feature& x) { return x.id == id; });
        ASSERT_NE(f, features.end()) << id << " seed " << seed;
        EXPECT_EQ(f->kind, site::FeatureKind::Exclusion) << id;
        // The middle of its part at full width is excluded; the lane beside it is on the road.
        const Eigen::Vector2d middle =
            island.centre + 0.5 * (island.noseLength_m - island.noseHighLength_m) * island.dir;
        EXPECT_EQ(site.classify(middle), site::Placement::Excluded) << id << " seed " << seed;
        const Eigen::Vector2d across(-island.dir.y(), island.dir.x());
        EXPECT_FALSE(site.contains(*f, middle + (island.halfWidth_m + 0.2) * across)) << id;
        ++islands;
      }
    }
  }
  EXPECT_GT(islands, 10);
}

}  // namespace
}  // namespace vp::sim
