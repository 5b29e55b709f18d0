// Tests of the simulator's traffic islands (vp_simulate --islands): the island's shape (pointed
// and wedge-shaped ends), their place in a widened median beside the lanes and behind the stop
// lines, the ground texture drawing them as kerb and grass or setts, and that no vehicle,
// parked or moving, ever drives over one. Without the option a seed's scene is the one it was.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>

#include "furniture_checks.hpp"
#include "ground_texture.hpp"
#include "scene.hpp"
#include "traffic_walk.hpp"

namespace {

using vp::sim::Island;
using vp::sim::SceneKind;
using vp::sim::SceneSpec;

constexpr auto& kKinds = vp::sim::testing::kSceneKinds;

SceneSpec sceneFor(SceneKind kind, std::uint64_t seed, bool islands) {
  vp::sim::Rng rng(seed);
  return vp::sim::generateScene(kind, rng, islands);
}

const vp::sim::Road& roadOf(const SceneSpec& scene, const Island& island) {
  for (const vp::sim::Road& road : scene.roads) {
    if (road.islandHalfWidth_m > 0.0 && std::fabs(road.lateral(island.centre)) < 1e-6 &&
        std::fabs(road.dir.dot(island.dir)) > 0.999) {
      return road;
    }
  }
  ADD_FAILURE() << "island at (" << island.centre.transpose() << ") stands on no road's centreline";
  return scene.roads.front();
}

TEST(Islands, DistanceDescribesAPointedOrWedgeShapedIsland) {
  Island island;
  island.centre = {10.0, 5.0};
  island.dir = {0.0, 1.0};
  island.halfLength_m = 6.0;
  island.halfWidth_m = 1.0;
  island.noseLength_m = 2.0;
  island.noseHighLength_m = 0.0;                              // blunt towards +dir (north)
  EXPECT_NEAR(island.distance({10.0, 5.0}), -1.0, 1e-9);      // centre: 1 m from the sides
  EXPECT_NEAR(island.distance({11.0, 5.0}), 0.0, 1e-9);       // on the side
  EXPECT_NEAR(island.distance({12.5, 5.0}), 1.5, 1e-9);       // beside it
  EXPECT_NEAR(island.distance({10.0, -1.0}), 0.0, 1e-9);      // the southern tip
  EXPECT_GT(island.distance({10.9, -0.5}), 0.0);              // outside the taper
  EXPECT_LT(island.distance({10.2, -0.5}), 0.0);              // inside it (0.25 m half width)
  EXPECT_NEAR(island.distance({10.95, 10.95}), -0.05, 1e-9);  // the blunt corner is square
  EXPECT_NEAR(island.distance({10.0, 11.5}), 0.5, 1e-9);      // beyond the blunt end
}

TEST(Islands, StandInAWidenedMedianBehindTheStopLines) {
  int scenesWithIslands = 0;
  int planted = 0;
  int wedges = 0;
  int islands = 0;
  for (const SceneKind kind : kKinds) {
    for (std::uint64_t seed = 1; seed <= 20; ++seed) {
      const SceneSpec scene = sceneFor(kind, seed, true);
      scenesWithIslands += scene.islands.empty() ? 0 : 1;
      for (const Island& island : scene.islands) {
        ++islands;
        planted += island.planted ? 1 : 0;
        wedges += island.noseLength_m == 0.0 || island.noseHighLength_m == 0.0 ? 1 : 0;
        const vp::sim::Road& road = roadOf(scene, island);
        const std::string where = std::string(toString(kind)) + " seed " + std::to_string(seed);
        EXPECT_GE(island.halfWidth_m, 0.6) << where;
        EXPECT_LE(island.halfWidth_m, 2.0) << where;
        EXPECT_GE(2.0 * island.halfLength_m, 4.0) << where;
        // The kerb stays 0.25 m or more from the innermost lanes.
        EXPECT_GE(road.medianHalf_m - island.halfWidth_m, 0.25 - 1e-9) << where;
        EXPECT_EQ(road.centreLine, vp::sim::CentreLine::DoubleYellow) << where;
        if (kind == SceneKind::Intersection) {
          const double near = std::fabs(road.along(island.centre)) - island.halfLength_m;
          EXPECT_GT(near, road.stopDistance_m) << where << ": the island reaches the junction";
        }
      }
    }
  }
  EXPECT_GE(scenesWithIslands, 25) << "of 60 scenes";
  EXPECT_GT(planted, islands / 2);
  EXPECT_GT(wedges, 0);
  EXPECT_LT(wedges, islands);
}

TEST(Islands, GroundTextureDrawsKerbAndGrassOrSetts) {
  int checked = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const SceneSpec scene = sceneFor(SceneKind::Intersection, seed, true);
    const vp::sim::GroundTexture texture(scene);
    for (const Island& island : scene.islands) {
      const Eigen::Vector2d across(-island.dir.y(), island.dir.x());
      vp::sim::GroundClass inside = vp::sim::GroundClass::Road;
      vp::sim::GroundClass edge = vp::sim::GroundClass::Road;
      vp::sim::GroundClass beside = vp::sim::GroundClass::Kerb;
      // The middle of the part at full width (a wedge's is off its centre).
      const Eigen::Vector2d c =
          island.centre + 0.5 * (island.noseLength_m - island.noseHighLength_m) * island.dir;
      texture.albedo(c.x(), c.y(), &inside);
      const Eigen::Vector2d e = c + (island.halfWidth_m - 0.5 * scene.kerbWidth_m) * across;
      texture.albedo(e.x(), e.y(), &edge);
      const vp::sim::Road& road = roadOf(scene, island);
      const Eigen::Vector2d lane = c + road.laneOffset_m(false, 0) * road.leftNormal();
      texture.albedo(lane.x(), lane.y(), &beside);
      EXPECT_EQ(inside,
                island.planted ? vp::sim::GroundClass::Verge : vp::sim::GroundClass::Sidewalk)
          << "seed " << seed;
      EXPECT_EQ(edge, vp::sim::GroundClass::Kerb) << "seed " << seed;
      EXPECT_EQ(beside, vp::sim::GroundClass::Road) << "seed " << seed;
      ++checked;
    }
  }
  EXPECT_GT(checked, 5);
}

TEST(Islands, NoVehicleEverDrivesOverAnIsland) {
  long checked = 0;
  long near = 0;  // vehicle-island pairs within 3 m: the test sees close calls
  for (const SceneKind kind : kKinds) {
    for (std::uint64_t seed = 1; seed <= 4; ++seed) {
      vp::sim::Rng rng(seed);
      const SceneSpec scene = vp::sim::generateScene(kind, rng, true);
      vp::sim::testing::walkTraffic(scene, rng, [&](const auto& v, const auto& fv, int step) {
        for (const Island& island : scene.islands) {
          // The island's enclosing rectangle is larger than the island: a stricter test.
          const vp::sim::Footprint fi{island.centre, island.dir, island.halfLength_m,
                                      island.halfWidth_m};
          ++checked;
          EXPECT_FALSE(vp::sim::footprintsOverlap(fv, fi, 0.0))
              << "vehicle " << v.trackId << (v.parked ? " (parked)" : "")
              << " drives over an island, " << toString(kind) << " seed " << seed << " step "
              << step;
          near += vp::sim::footprintsOverlap(fv, fi, 1.5) ? 1 : 0;
        }
      });
    }
  }
  EXPECT_GT(checked, 10000);
  EXPECT_GT(near, 0) << "no vehicle ever came within 3 m of an island: the test proves little";
}

TEST(Islands, WithoutTheOptionASeedsSceneIsUnchanged) {
  for (const SceneKind kind : kKinds) {
    for (std::uint64_t seed = 1; seed <= 6; ++seed) {
      vp::sim::Rng a(seed);
      vp::sim::Rng b(seed);
      const SceneSpec plain = vp::sim::generateScene(kind, a);
      const SceneSpec withIslands = vp::sim::generateScene(kind, b, true);
      EXPECT_TRUE(plain.islands.empty());
      ASSERT_EQ(plain.roads.size(), withIslands.roads.size());
      bool widened = false;
      for (std::size_t i = 0; i < plain.roads.size(); ++i) {
        EXPECT_EQ(plain.roads[i].dir, withIslands.roads[i].dir);
        EXPECT_EQ(plain.roads[i].laneWidth_m, withIslands.roads[i].laneWidth_m);
        EXPECT_EQ(plain.roads[i].islandHalfWidth_m, 0.0);
        widened = widened || withIslands.roads[i].islandHalfWidth_m > 0.0;
      }
      if (!widened) {
        // The islands' own Rng took no draw from the sequence's: the same scene follows.
        EXPECT_EQ(a.next(), b.next()) << toString(kind) << " seed " << seed;
        EXPECT_EQ(plain.trees.size(), withIslands.trees.size());
        EXPECT_EQ(plain.light.sunAzimuth_deg, withIslands.light.sunAzimuth_deg);
      }
    }
  }
}

}  // namespace
